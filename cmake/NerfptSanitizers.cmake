# NERFPT_SANITIZE: AddressSanitizer + UndefinedBehaviorSanitizer on every C++ file we compile (the library,
# the CLI, the tests), any UB report fatal. NERFPT_FUZZ (clang only) builds the libFuzzer harnesses
# (fuzz/CMakeLists.txt links them with -fsanitize=fuzzer); nerfpt_fuzz_coverage() below gives the code they
# parse through libFuzzer's coverage instrumentation. Third-party libraries stay uninstrumented: ASan still
# catches their heap errors through its allocator.
if(NERFPT_FUZZ)
    if(NOT CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
        message(FATAL_ERROR "NERFPT_FUZZ needs clang (libFuzzer): configure with -DCMAKE_CXX_COMPILER=clang++")
    endif()
    set(NERFPT_SANITIZE ON CACHE BOOL "" FORCE)
endif()
if(NERFPT_SANITIZE)
    set(_nerfpt_san -fsanitize=address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer)
    if(CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
        # Third-party headers' own UB (TBB's tagged pointers): not ours to fix; see the file.
        list(APPEND _nerfpt_san -fsanitize-ignorelist=${PROJECT_SOURCE_DIR}/cmake/sanitizer_ignorelist.txt)
    endif()
    add_compile_options("$<$<COMPILE_LANGUAGE:CXX>:${_nerfpt_san}>")
    add_link_options(-fsanitize=address,undefined)
endif()

# Executables of the sanitizer build get an operator new that throws std::bad_alloc on failure, as the standard
# and a normal build do (ASan's aborts: see cmake/sanitizer_new.cpp); a no-op in other builds.
function(nerfpt_conforming_new target)
    if(NERFPT_SANITIZE)
        target_sources(${target} PRIVATE ${PROJECT_SOURCE_DIR}/cmake/sanitizer_new.cpp)
    endif()
endfunction()

# libFuzzer's coverage (edge counters and a callback on every comparison) on the given sources, when NERFPT_FUZZ is
# on: the code that reads untrusted bytes, which is what guides the harnesses to new inputs. Only there: elsewhere
# it made a file's sanitizer compile 10-17% slower and the training tests under ASan 2x slower, and no harness
# reaches that code (docs/benchmarks.md, "CI time").
function(nerfpt_fuzz_coverage)
    if(NERFPT_FUZZ)
        set_property(SOURCE ${ARGN} APPEND PROPERTY COMPILE_OPTIONS -fsanitize=fuzzer-no-link)
    endif()
endfunction()
