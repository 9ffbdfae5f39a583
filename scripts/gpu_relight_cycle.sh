#!/usr/bin/env bash
# The relighting cycle on the GPU machine (issue 24), after `scripts/gpu_check.sh pack` here (carry
# .gpu/bundle.tar.xz and .gpu/relight; .gpu/scenes for the OptiX tests): the dev object trained with
# --relightable on the GPU (TRAIN_SECONDS of NeRF training, default 60, then the relight stage), its intrinsic
# fields on the 20 test views (bench/relight_fields) and the relight scorer on them; with RELIT=1 also the 20
# views relit under `sunset` and `studio` and the room scene (bench/relight_dev.sh); then the GPU tests named by
# GTEST_FILTER, if any. Logs and small pictures in $OUT.
set -uo pipefail
cd "$(dirname "$0")/.."
out=${OUT:-/tmp/gpu_out}
mkdir -p "$out"
scripts/gpu_check.sh run --gtest_filter='NONE' >/dev/null 2>&1  # unpacks the bundle
export LD_LIBRARY_PATH=/tmp/nerfpt-gpu/lib
bin=/tmp/nerfpt-gpu/bin
data=.gpu/relight/dev
work=/tmp/relight
mkdir -p $work/pred
start=$(date +%s.%N)
timeout 400 $bin/nerfpt train $data -o $work/dev.npt --backend cuda --time "${TRAIN_SECONDS:-60}" --relightable \
    --force 2>&1 | tr '\r' '\n' | grep -v -E '^train \[|^relight: (fit|surface) \[' | tee "$out/train.log"
echo "train + relight wall: $(awk "BEGIN {print $(date +%s.%N) - $start}") s" | tee -a "$out/train.log"
$bin/nerfpt info $work/dev.npt | tee -a "$out/train.log"
timeout 300 $bin/relight_fields $work/dev.npt $data/transforms_test.json $work/pred/aov --spp 8 --backend cuda \
    | tee "$out/fields.log"
PYTHONPATH=scripts/exr_shim python3 .gpu/relight/score.py $data $work/pred --normals-zup --label dev | tee "$out/score.log"
if [[ ${RELIT:-0} == 1 ]]; then
    BIN=$bin MODEL=$work/dev.npt DATA=$data PRED=$work/pred bench/relight_dev.sh render 2>&1 | tee "$out/relit.log"
    # The render's AOVs replaced relight_fields' (world normals of the nerfpt scene, +Y up).
    PYTHONPATH=scripts/exr_shim python3 .gpu/relight/score.py $data $work/pred --label dev-render | tee -a "$out/score.log"
fi
if [[ ${EMISSIVE:-0} == 1 ]]; then
    # The baseline: the same model rendered as today, emissive (its capture light baked in).
    SHADING=emissive BIN=$bin MODEL=$work/dev.npt DATA=$data PRED=$work/emissive bench/relight_dev.sh render 2>&1 |
        tee "$out/emissive.log"
    PYTHONPATH=scripts/exr_shim python3 .gpu/relight/score.py $data $work/emissive --label dev-emissive | tee -a "$out/score.log"
fi
if [[ -n ${GTEST_FILTER:-} ]]; then
    timeout "${TEST_SECONDS:-300}" scripts/gpu_check.sh run --gtest_filter="$GTEST_FILTER" >"$out/gpu_tests.log" 2>&1
    grep -E "PASSED|FAILED|SKIPPED|Failure|error|relMSE" "$out/gpu_tests.log" | head -40
fi
python3 - "$work/pred" "$out" <<'PY'
# A strip of test views 0, 5, 10: albedo and normal (and relit views where they exist), as one PNG.
import os, sys
os.environ.setdefault('OPENCV_IO_ENABLE_OPENEXR', '1')
import cv2, numpy as np
pred, out = sys.argv[1], sys.argv[2]
rows = []
for name, f in (('albedo', 'aov/albedo_%d.exr'), ('normal', 'aov/normal_%d.exr'), ('sunset', 'relit/sunset/r_%d.exr'),
                ('studio', 'relit/studio/r_%d.exr')):
    tiles = []
    for k in (0, 5, 10):
        p = os.path.join(pred, f % k)
        if not os.path.exists(p): break
        im = cv2.imread(p, cv2.IMREAD_UNCHANGED)[..., :3].astype(np.float32)
        if name == 'normal': im = im * 0.5 + 0.5
        im = np.clip(im, 0, 1) ** (1 / 2.2)
        tiles.append((im * 255).astype(np.uint8))
    if len(tiles) == 3: rows.append(np.concatenate(tiles, 1))
if rows: cv2.imwrite(os.path.join(out, 'relight_views.png'), np.concatenate(rows, 0))
PY
