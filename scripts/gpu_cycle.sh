#!/usr/bin/env bash
# One whole cycle on the lent GPU machine (after `scripts/gpu_check.sh pack` here; carry .gpu): the GPU tests,
# the lego training benchmark, the view benchmark and a kernel profile, each under its own time limit, logs in
# $OUT. Usage: scripts/gpu_cycle.sh [TRAIN_SECONDS_LIST] [PROFILE:0|1] [EXTRA_TRAIN_BENCH_ARGS...]
set -uo pipefail
cd "$(dirname "$0")/.."
out=${OUT:-/tmp/gpu_out}
mkdir -p "$out"
stops=${1:-5,15,60}
profile=${2:-1}
shift 2 2>/dev/null || shift $#
lego=.gpu/nerf_synthetic/lego
bin=/tmp/nerfpt-gpu/bin

timeout 240 scripts/gpu_check.sh run 2>&1 | tee "$out/gpu_tests.log" | grep -v "^\[ *OK" | tail -40
timeout 420 scripts/gpu_check.sh bench --backend cuda --data $lego --test-every 1 --seconds "$stops" \
    --save /tmp/lego.npt --fp32-eval "$@" 2>&1 | tee "$out/train_bench.log"
export LD_LIBRARY_PATH=/tmp/nerfpt-gpu/lib
[[ -f /tmp/lego.npt ]] && timeout 90 $bin/view_bench /tmp/lego.npt --data $lego --test-every 1 2>&1 |
    tee "$out/view_bench.log"
if [[ $profile == 1 ]] && command -v ncu >/dev/null; then
    # Kernels of steady-state steps (after the first few hundred launches: warm-up and grid warm-up).
    timeout 200 ncu --clock-control none --launch-skip 3000 --launch-count 24 \
        --section SpeedOfLight --section Occupancy --section LaunchStats \
        $bin/train_bench --backend cuda --data $lego --test-every 50 --seconds 4 >"$out/ncu.log" 2>&1
    grep -E "^\s+[a-z_:<>A-Z0-9]+.*\(|Duration|Compute \(SM\) Throughput|Memory Throughput|DRAM Throughput|Registers Per|Achieved Occupancy" \
        "$out/ncu.log" | head -150 > "$out/ncu_summary.log"
    tail -60 "$out/ncu_summary.log"
fi
