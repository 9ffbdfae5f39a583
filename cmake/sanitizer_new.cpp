// Linked into the executables of the sanitizer build only (nerfpt_conforming_new in NerfptSanitizers.cmake).
// ASan's throwing operator new reports a failed allocation and aborts, even with allocator_may_return_null=1,
// where the C++ standard and a normal build throw std::bad_alloc (google/sanitizers#295). Our loaders turn a
// bad_alloc into a one-line error, and the tests and fuzzers must take that path, not abort: these forward to
// ASan's nothrow forms (null on failure under allocator_may_return_null=1) and throw. ASan still allocates
// and tracks every block, so overflows, leaks and new/delete mismatches are reported as before.
#include <new>

void* operator new(std::size_t n) {
    if (void* p = ::operator new(n, std::nothrow)) return p;
    throw std::bad_alloc();
}

void* operator new[](std::size_t n) {
    if (void* p = ::operator new[](n, std::nothrow)) return p;
    throw std::bad_alloc();
}

void* operator new(std::size_t n, std::align_val_t a) {
    if (void* p = ::operator new(n, a, std::nothrow)) return p;
    throw std::bad_alloc();
}

void* operator new[](std::size_t n, std::align_val_t a) {
    if (void* p = ::operator new[](n, a, std::nothrow)) return p;
    throw std::bad_alloc();
}
