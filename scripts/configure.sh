#!/usr/bin/env bash
# Installs what is missing and configures the Release build in build/ (quick when nothing changed). Used by
# demo.sh and test.sh; extra arguments go to cmake.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

scripts/install_deps.sh

cmake_args=(-S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release)
# clang++ for a new build folder (install_deps.sh installs it; $CXX or -DCMAKE_CXX_COMPILER=... choose another):
# it compiles our files 12-40% faster than g++ 12, which is most of CI's time, and the programs it makes run as
# fast (docs/benchmarks.md, "CI time"). A folder configured before keeps its compiler: changing it would make
# CMake drop the folder's cache and the settings in it. nvcc keeps its own host compiler (g++).
if [[ ! -f build/CMakeCache.txt && -z "${CXX:-}" ]] && command -v clang++ >/dev/null 2>&1; then
    cmake_args+=(-DCMAKE_CXX_COMPILER=clang++)
fi
# CMake looks for nvcc on PATH (or $CUDACXX) only; CI has it at /usr/local/cuda without PATH set, and we want the
# CUDA code compiled there so that host-only code in shared headers fails the build.
if ! command -v nvcc >/dev/null 2>&1 && [[ -z "${CUDACXX:-}" && -x /usr/local/cuda/bin/nvcc ]]; then
    cmake_args+=(-DCMAKE_CUDA_COMPILER=/usr/local/cuda/bin/nvcc)
fi
cmake "${cmake_args[@]}" "$@"
