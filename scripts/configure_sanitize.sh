#!/usr/bin/env bash
# Configures the ASan + UBSan build in build-san/ (or $NERFPT_SAN_BUILD): clang; the library, the CLI, the unit
# tests and the fuzz harnesses (fuzz/), libFuzzer coverage on the parsing code (cmake/NerfptSanitizers.cmake);
# no CUDA, no benchmarks. -O1 -g with assertions on (our debug-only checks, nlohmann's JSON_ASSERT). Used by
# scripts/test.sh --sanitize and scripts/fuzz.sh; extra arguments go to cmake.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

scripts/install_deps.sh >/dev/null
build=${NERFPT_SAN_BUILD:-build-san}
clangxx=$(command -v clang++ || command -v clang++-14 || true)
if [[ -z "$clangxx" ]]; then
    echo "configure_sanitize: clang++ not found (Debian: apt-get install clang; scripts/install_deps.sh lists it)" >&2
    exit 1
fi
cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Debug -DCMAKE_CXX_COMPILER="$clangxx" \
    -DCMAKE_CXX_FLAGS_DEBUG="-O1 -g" -DNERFPT_FUZZ=ON -DNERFPT_CUDA=OFF -DNERFPT_BENCH=OFF "$@"
