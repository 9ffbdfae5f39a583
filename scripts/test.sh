#!/usr/bin/env bash
# Installs what is missing, builds Release in build/ and runs every test that needs no GPU. Extra arguments go to
# ctest (e.g. scripts/test.sh -R Progress -V). Exits non-zero when the build or a test fails.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

scripts/configure.sh
# Default: all cores; CI machines have 2, shared machines can set NERFPT_JOBS.
cmake --build build -j "${NERFPT_JOBS:-$(nproc)}"

cd build
ctest -LE gpu --output-on-failure -j "${NERFPT_JOBS:-$(nproc)}" "$@"
