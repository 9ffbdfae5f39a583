#!/usr/bin/env bash
# The relighting cycle on the GPU machine (issue 24), after `scripts/gpu_check.sh pack` here (carry
# .gpu/bundle.tar.xz and .gpu/relight; .gpu/scenes for the OptiX tests): the dev object trained with
# --relightable on the GPU (TRAIN_SECONDS of NeRF training, default 60, then the relight stage), its intrinsic
# fields on the 20 test views (bench/relight_fields) and the relight scorer on them; with RELIT=1 also the 20
# views relit under `sunset` and `studio` and the room scene (bench/relight_dev.sh); then the GPU tests named by
# GTEST_FILTER, if any (gtest's syntax: parameterised suites carry a prefix, so `*RelightMarchGpu*`, not
# `RelightMarchGpu*`). Logs and small pictures in $OUT.
# ESTIMATORS=1 also scores the surface-normal estimators the stage can fit to (relight_fields --normals density |
# depth, at a few steps / stencil widths) on the trained NeRF. VARIANTS="name:ARGS;name:ARGS" re-runs the relight
# stage alone on copies of the trained model with extra `nerfpt train` ARGS (e.g. --relight-normals density) and
# scores each one's fields (at VARIANT_SPP, default 4). TRAIN_ARGS are added to the first training's arguments.
# SPP2 (with RELIT=1) renders and scores the same model's views again at that spp.
# Carry limit (64 MiB with the working tree, counted in disk blocks): the bundle of nerfpt and relight_fields
# (~23 MB) and all of .gpu/relight (~31 MB) do not fit together. Leave out the env.exr files (never read) and
# dev/test/r_*.png (blank stand-ins are written here: relight_fields needs only the test cameras); then RELIT=1
# and VARIANTS run in one call. Without RELIT=1, .gpu/relight/dev's relit/, scene/ and lights/ are not read.
# RELIGHT_DATA: another data set of that layout instead of .gpu/relight/dev (scripts/make_relight_object.py).
set -uo pipefail
cd "$(dirname "$0")/.."
out=${OUT:-/tmp/gpu_out}
mkdir -p "$out"
scripts/gpu_check.sh run --gtest_filter='NONE' >/dev/null 2>&1  # unpacks the bundle
export LD_LIBRARY_PATH=/tmp/nerfpt-gpu/lib
bin=/tmp/nerfpt-gpu/bin
data=${RELIGHT_DATA:-.gpu/relight/dev}  # another object made as dev was: scripts/make_relight_object.py
work=/tmp/relight
rm -rf $work  # a warm machine keeps the last call's renders, which the scorer would read as this call's
mkdir -p $work/pred
if [[ ! -f $data/test/r_0.png ]]; then
    # Left out of the carry (64 MiB) so that RELIT=1 and VARIANTS fit in one call: relight_fields reads only
    # the test cameras, but the loader wants their images, so blank ones of the views' size stand in.
    python3 - "$data" <<'EOF'
import json, os, struct, sys, zlib
data = sys.argv[1]
w = h = 400  # the dev set's views
def chunk(kind, body):
    return struct.pack('>I', len(body)) + kind + body + struct.pack('>I', zlib.crc32(kind + body) & 0xffffffff)
png = (b'\x89PNG\r\n\x1a\n' + chunk(b'IHDR', struct.pack('>IIBBBBB', w, h, 8, 6, 0, 0, 0)) +
       chunk(b'IDAT', zlib.compress(b''.join(b'\0' + bytes(4 * w) for _ in range(h)))) + chunk(b'IEND', b''))
for f in json.load(open(os.path.join(data, 'transforms_test.json')))['frames']:
    path = os.path.join(data, f['file_path'] + '.png')
    if not os.path.exists(path):
        open(path, 'wb').write(png)
EOF
fi
score() {  # score LABEL PRED_DIR [score.py options]
    PYTHONPATH=scripts/exr_shim python3 .gpu/relight/score.py $data "$2" --label "$1" "${@:3}" | tee -a "$out/score.log"
}
start=$(date +%s.%N)
# shellcheck disable=SC2086
timeout 400 $bin/nerfpt train $data -o $work/dev.npt --backend cuda --time "${TRAIN_SECONDS:-60}" --relightable \
    --force ${TRAIN_ARGS:-} 2>&1 | tr '\r' '\n' | grep -v -E '^train \[|^relight: (fit|surface) \[' | tee "$out/train.log"
echo "train + relight wall: $(awk "BEGIN {print $(date +%s.%N) - $start}") s" | tee -a "$out/train.log"
$bin/nerfpt info $work/dev.npt | tee -a "$out/train.log"
timeout 300 $bin/relight_fields $work/dev.npt $data/transforms_test.json $work/pred/aov --spp 8 --backend cuda \
    | tee "$out/fields.log"
score dev $work/pred --normals-zup
if [[ ${ESTIMATORS:-0} == 1 ]]; then
    for est in "density --normal-step 0.004" "density --normal-step 0.012" "depth --normal-pixels 1" \
               "depth --normal-pixels 2" "depth --normal-pixels 4"; do
        name=$(echo "$est" | tr -d ' -' | tr '.' '_')
        timeout 200 $bin/relight_fields $work/dev.npt $data/transforms_test.json $work/est_$name/aov --spp 2 \
            --backend cuda --normals $est | tee -a "$out/fields.log"
        score "estimator-$name" $work/est_$name --normals-zup
    done
fi
IFS=';' read -ra variants <<<"${VARIANTS:-}"
for v in "${variants[@]}"; do
    name=${v%%:*}
    args=${v#*:}
    cp $work/dev.npt $work/var.npt
    start=$(date +%s.%N)
    # shellcheck disable=SC2086
    timeout 300 $bin/nerfpt train $data -o $work/var.npt --backend cuda --time "${TRAIN_SECONDS:-60}" --resume \
        --relightable $args 2>&1 | tr '\r' '\n' | grep -E 'relight' | grep -v -E '^relight: (fit|surface) \[' |
        sed "s/^/[$name] /" | tee -a "$out/variants.log"
    echo "[$name] relight stage wall: $(awk "BEGIN {print $(date +%s.%N) - $start}") s" | tee -a "$out/variants.log"
    timeout 200 $bin/relight_fields $work/var.npt $data/transforms_test.json $work/var_$name/aov --spp "${VARIANT_SPP:-4}" \
        --backend cuda | sed "s/^/[$name] /" | tee -a "$out/fields.log"
    score "variant-$name" $work/var_$name --normals-zup
done
if [[ ${RELIT:-0} == 1 ]]; then
    BIN=$bin MODEL=$work/dev.npt DATA=$data PRED=$work/pred bench/relight_dev.sh render 2>&1 | tee "$out/relit.log"
    # The render's AOVs replaced relight_fields' (world normals of the nerfpt scene, +Y up).
    score dev-render $work/pred
    if [[ -n ${SPP2:-} ]]; then  # the same model's renders at another spp: how much of the score is MC noise
        SPP=$SPP2 BIN=$bin MODEL=$work/dev.npt DATA=$data PRED=$work/pred_spp2 bench/relight_dev.sh render 2>&1 |
            tee "$out/relit_spp2.log" | tail -1
        score "dev-render-${SPP2}spp" $work/pred_spp2
    fi
fi
if [[ ${EMISSIVE:-0} == 1 ]]; then
    # The baseline: the same model rendered as today, emissive (its capture light baked in).
    SHADING=emissive BIN=$bin MODEL=$work/dev.npt DATA=$data PRED=$work/emissive bench/relight_dev.sh render 2>&1 |
        tee "$out/emissive.log"
    score dev-emissive $work/emissive
fi
if [[ -n ${GTEST_FILTER:-} ]]; then
    timeout "${TEST_SECONDS:-300}" scripts/gpu_check.sh run --gtest_filter="$GTEST_FILTER" >"$out/gpu_tests.log" 2>&1
    grep -E "PASSED|FAILED|SKIPPED|Failure|error|relMSE" "$out/gpu_tests.log" | head -40
fi
PYTHONPATH=scripts/exr_shim python3 - "$work/pred" "$out" "$data" <<'PY'
# A strip of test views 0, 5, 10: albedo and normal (and relit views where they exist), as one PNG.
import os, sys
import cv2, numpy as np
import OpenImageIO as oiio  # scripts/exr_shim on the GPU machine: cv2 there cannot read EXR
def read(path):
    inp = oiio.ImageInput.open(path)
    spec = inp.spec(); px = inp.read_image(0, 0, 0, spec.nchannels, 'float'); inp.close()
    return np.asarray(px, np.float32).reshape(spec.height, spec.width, spec.nchannels)
pred, out, data = sys.argv[1], sys.argv[2], sys.argv[3]
rows = []
for name, f in (('albedo', 'aov/albedo_%d.exr'), ('normal', 'aov/normal_%d.exr'), ('sunset', 'relit/sunset/r_%d.exr'),
                ('studio', 'relit/studio/r_%d.exr')):
    tiles = []
    for k in (0, 5, 10):
        p = os.path.join(pred, f % k)
        if not os.path.exists(p): break
        im = read(p)[..., :3]
        if name == 'normal': im = im * 0.5 + 0.5
        im = np.clip(im, 0, 1) ** (1 / 2.2)
        tiles.append((im * 255).astype(np.uint8)[..., ::-1])  # RGB -> cv2's BGR
    if len(tiles) == 3: rows.append(np.concatenate(tiles, 1))
if rows: cv2.imwrite(os.path.join(out, 'relight_views.png'), np.concatenate(rows, 0))
# The room: Cycles' reference | nerfpt's render | 4 x |difference|, and the render itself for a closer look.
room = os.path.join(pred, 'scene', 'render.exr')
if os.path.exists(room):
    ref = read(os.path.join(data, 'scene', 'reference.exr'))[..., :3]
    r = read(room)[..., :3]
    tiles = [ref, r, 4 * np.abs(r - ref)]
    strip = np.concatenate([(np.clip(t, 0, 1) ** (1 / 2.2) * 255).astype(np.uint8)[..., ::-1] for t in tiles], 1)
    cv2.imwrite(os.path.join(out, 'room.png'), strip)
    with open(room, 'rb') as f, open(os.path.join(out, 'room_render.exr'), 'wb') as g: g.write(f.read())
PY
# KEEP_AOV=1: the albedo and roughness of test views 0, 5, 10 of the model and of each variant, for a closer look
# on this machine (aov.tar.xz).
if [[ ${KEEP_AOV:-0} == 1 ]]; then
    (cd $work && find pred var_* -path '*/aov/*' \( -name 'albedo_[05].exr' -o -name 'albedo_10.exr' \
        -o -name 'roughness_[05].exr' -o -name 'roughness_10.exr' \) -print0 2>/dev/null |
        tar -cJf "$out/aov.tar.xz" --null -T -)
fi
