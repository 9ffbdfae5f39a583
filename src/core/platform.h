// Macros that let one function body compile for the CPU and, under nvcc, for the GPU.
// Everything that runs per sample (BSDFs, light and camera sampling, volume integration) is NPT_HD.
#pragma once

#if defined(__CUDACC__)
#define NPT_HD __host__ __device__
#define NPT_INLINE __forceinline__
#define NPT_UNROLL _Pragma("unroll")  // a loop over a local array: unrolled, the array stays in registers
#define NPT_DEVICE_NOINLINE __noinline__  // a large function called from a loop: a call, not its body inlined
#else
#define NPT_DEVICE_NOINLINE
#define NPT_HD
#define NPT_INLINE inline __attribute__((always_inline))
#define NPT_UNROLL
#endif

#include <cstddef>
#include <cstdint>

namespace npt {

// A non-owning view of device- or host-resident memory: the only container shared code may touch.
template <typename T>
struct Span {
    T* data = nullptr;
    size_t size = 0;
    NPT_HD NPT_INLINE T& operator[](size_t i) const { return data[i]; }
    NPT_HD NPT_INLINE bool empty() const { return size == 0; }
};

}  // namespace npt
