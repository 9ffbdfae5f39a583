#!/usr/bin/env bash
# The OptiX backend's first cycle on the GPU machine (issue 13), after `scripts/gpu_check.sh pack` here with
# the OptiX headers in .optix/ (carry .gpu/bundle.tar.xz and .gpu/scenes): the GPU tests (the OptiX parity
# tests among them), then render_bench on the Cornell scenes with both backends. Logs in $OUT.
set -uo pipefail
cd "$(dirname "$0")/.."
out=${OUT:-/tmp/gpu_out}
mkdir -p "$out"
timeout 300 scripts/gpu_check.sh run --gtest_filter='OptixRender.*:SharedMathGpu.*' 2>&1 | tee "$out/optix_tests.log" |
    grep -E "OptiX|relMSE|example|PASSED|FAILED|Failure|error" | head -40
export LD_LIBRARY_PATH=/tmp/nerfpt-gpu/lib NERFPT_SHARED_DATA=$PWD/.gpu
for res in 320x240 1920x1080; do
    timeout 120 /tmp/nerfpt-gpu/bin/render_bench --backend optix --res $res --spp 64 --repeats 3 \
        --scene cornell --scene cornell_volume 2>&1 | tee -a "$out/render_bench.log"
done
