#!/usr/bin/env bash
# Installs what is missing and configures the Release build in build/ (quick when nothing changed). Used by
# demo.sh and test.sh; extra arguments go to cmake.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

scripts/install_deps.sh

cmake_args=(-S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release)
# CMake looks for nvcc on PATH (or $CUDACXX) only; CI has it at /usr/local/cuda without PATH set, and we want the
# CUDA code compiled there so that host-only code in shared headers fails the build.
if ! command -v nvcc >/dev/null 2>&1 && [[ -z "${CUDACXX:-}" && -x /usr/local/cuda/bin/nvcc ]]; then
    cmake_args+=(-DCMAKE_CUDA_COMPILER=/usr/local/cuda/bin/nvcc)
fi
cmake "${cmake_args[@]}" "$@"
