#!/usr/bin/env bash
# What `nerfpt train --serve` costs the CUDA trainer (issue 27: "the viewer adds no cost to training when
# unused"; with it, held-out views are rendered on the monitor's thread while training runs). On the GPU
# machine after `scripts/gpu_check.sh run` (carry .gpu: the bundle and .gpu/nerf_synthetic): lego, STEPS
# (default 5000) steps, plain and with `--serve --port 0` (no page open), alternated twice; the training time
# comes from train's last line, the evaluations from -v's lines. Logs in $OUT (default /tmp/gpu_out).
set -uo pipefail
cd "$(dirname "$0")/.."
out=${OUT:-/tmp/gpu_out}
mkdir -p "$out"
export LD_LIBRARY_PATH=/tmp/nerfpt-gpu/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
bin=${BIN:-/tmp/nerfpt-gpu/bin}
log=$out/train_serve_gpu.log
steps=${STEPS:-5000}
nvidia-smi --query-gpu=name,driver_version --format=csv | tee "$log"
for rep in 1 2; do
    for mode in plain serve; do
        extra=()
        [[ $mode == serve ]] && extra=(--serve --port 0)
        echo "== rep $rep, $mode: nerfpt train lego --steps $steps --backend ${BACKEND:-cuda} ${extra[*]}" | tee -a "$log"
        start=$(date +%s.%N)
        raw=$out/train_serve_${rep}_$mode.raw
        # With --serve the page stays up after training until Ctrl-C: stop it once the model is written.
        "$bin/nerfpt" train "${DATA:-.gpu/nerf_synthetic/lego}" -o /tmp/train_serve.npt --backend "${BACKEND:-cuda}" --steps "$steps" \
            --force -v "${extra[@]}" >"$raw" 2>&1 &
        pid=$!
        for _ in $(seq 1500); do
            grep -q "^wrote\|stays up" "$raw" 2>/dev/null && break
            kill -0 $pid 2>/dev/null || break
            sleep 0.2
        done
        echo "wall to the model written: $(awk "BEGIN {print $(date +%s.%N) - $start}") s" | tee -a "$log"
        kill -INT $pid 2>/dev/null
        wait $pid 2>/dev/null
        tr '\r' '\n' <"$raw" | grep -E "wrote|evaluat|snapshot|held-out|error|warn" | tee -a "$log"
    done
done
