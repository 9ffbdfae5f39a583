#!/usr/bin/env bash
# GPU test cycle for the lent GPU machine (no Debian libraries there, no package registry):
#   scripts/gpu_check.sh pack   here: build the GPU test binaries for sm_90 and copy them with the non-system
#                               shared libraries they need into the ignored folder .gpu/
#   scripts/gpu_check.sh run    there (carry .gpu): run every GPU-labelled test binary and print a summary
set -euo pipefail
cd "$(dirname "$0")/.."
mode=${1:-}
case "$mode" in
pack)
    build=${BUILD_DIR:-build}
    cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DNERFPT_CUDA=ON -DCMAKE_CUDA_ARCHITECTURES=90 \
        ${CUDACXX:+-DCMAKE_CUDA_COMPILER=$CUDACXX} >/dev/null
    cmake --build "$build" --target nerfpt_gpu_tests
    rm -rf .gpu && mkdir -p .gpu/lib
    cp "$build/tests/nerfpt_gpu_tests" .gpu/
    # Everything ldd resolves outside the C runtime travels along (the GPU machine runs another distribution).
    ldd .gpu/nerfpt_gpu_tests | awk '/=> \// {print $3}' |
        grep -v -E '/(libc|libm|libdl|libpthread|librt|libgcc_s|libstdc\+\+|ld-linux[^/]*)\.so' |
        xargs -r -I{} cp -L {} .gpu/lib/
    du -sh .gpu
    ;;
run)
    export LD_LIBRARY_PATH="$PWD/.gpu/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
    nvidia-smi -L
    status=0
    .gpu/nerfpt_gpu_tests --gtest_brief=1 || status=$?
    echo "gpu_check: nerfpt_gpu_tests exit code $status"
    exit $status
    ;;
*)
    echo "usage: scripts/gpu_check.sh pack|run" >&2
    exit 2
    ;;
esac
