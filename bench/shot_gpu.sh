#!/usr/bin/env bash
# The shot benchmark of issue 26 on the GPU machine: a 48-frame shot of the NeRF demo (the camera moving, the
# lego model queried directly) at 1920x1080, 1 spp, OptiX, against the prepared still of the same scene.
#   - still: render_bench --frames 48 (the prepared scene rendered 48 times into the renderer's own frame: the
#     viewer's frame rate, no files);
#   - shot: nerfpt render --frames 1-48 (posed per frame, each frame's EXR + PNG written), twice; its last lines
#     say where a frame goes (rendering / posing and updating / writing).
# Goal: the shot's rendering per frame within 5% of the still's frame time.
# Run there after `scripts/gpu_check.sh run` (carry .gpu: the bundle and .gpu/nerf_demo, .gpu/nerf_synthetic).
# MODEL=path/to/lego.npt skips the 60 s training; STATIC=1 adds the like-for-like runs at the end. Logs in $OUT
# (default /tmp/gpu_out).
set -uo pipefail
cd "$(dirname "$0")/.."
out=${OUT:-/tmp/gpu_out}
mkdir -p "$out"
export LD_LIBRARY_PATH=/tmp/nerfpt-gpu/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
bin=${BIN:-/tmp/nerfpt-gpu/bin}
demo=/tmp/nerf_shot
mkdir -p $demo
cp .gpu/nerf_demo/scene.gltf $demo/scene.gltf
if [[ -n ${MODEL:-} ]]; then
    cp "$MODEL" $demo/lego.npt
elif [[ ! -f $demo/lego.npt ]]; then
    timeout 120 $bin/nerfpt train .gpu/nerf_synthetic/lego -o $demo/lego.npt --backend cuda --time 60 -q --force
fi
# Made by `scripts/gpu_check.sh pack` (python3 here only when it was not).
if [[ -f .gpu/nerf_demo/shot.gltf ]]; then
    cp .gpu/nerf_demo/shot.gltf $demo/shot.gltf
else
    python3 scripts/make_nerf_demo_shot.py $demo/scene.gltf $demo/shot.gltf
fi
nvidia-smi --query-gpu=name,driver_version,clocks.sm,clocks.max.sm --format=csv | tee "$out/shot_gpu.log"
echo "== still: render_bench, 48 frames of the prepared scene (frame 0's pose)" | tee -a "$out/shot_gpu.log"
timeout 180 $bin/render_bench --backend optix --res 1920x1080 --spp 1 --repeats 3 --frames 48 \
    --scene-file $demo/shot.gltf 2>&1 | tee -a "$out/shot_gpu.log"
for run in 1 2; do
    echo "== shot, run $run: nerfpt render --frames 1-48" | tee -a "$out/shot_gpu.log"
    rm -rf $demo/frames && mkdir -p $demo/frames
    timeout 300 $bin/nerfpt render $demo/shot.gltf -o $demo/frames/shot.####.exr --frames 1-48 --res 1920x1080 \
        --spp 1 --backend optix 2>&1 | grep -E "frames to render|per frame|rendered|error|warn" | tee -a "$out/shot_gpu.log"
done
# Two frames for the record (PNG previews).
cp $demo/frames/shot.0001.png $demo/frames/shot.0048.png "$out/" 2>/dev/null || true
# STATIC=1: like for like (docs/benchmarks.md, "Like for like"): the shot without its animation (every frame
# frame 0's pose), render_bench against `render --frames 1-48` with 8 writer threads and with 1, twice: whether
# the writers' compression on the host is what slows the sequence's rendering.
if [[ ${STATIC:-0} == 1 ]]; then
    python3 - $demo/shot.gltf $demo/shot_static.gltf <<'PY'
import json, sys
g = json.load(open(sys.argv[1])); g.pop("animations", None); json.dump(g, open(sys.argv[2], "w"))
PY
    for rep in 1 2; do
        echo "== static, rep $rep: render_bench" | tee -a "$out/shot_gpu.log"
        timeout 120 $bin/render_bench --backend optix --res 1920x1080 --spp 1 --repeats 1 --frames 48 \
            --scene-file $demo/shot_static.gltf 2>&1 | tail -1 | tee -a "$out/shot_gpu.log"
        for w in 8 1; do
            echo "== static, rep $rep: render --frames 1-48 --writers $w" | tee -a "$out/shot_gpu.log"
            rm -rf $demo/frames && mkdir -p $demo/frames
            timeout 120 $bin/nerfpt render $demo/shot_static.gltf -o $demo/frames/shot.####.exr --frames 1-48 \
                --res 1920x1080 --spp 1 --backend optix --writers $w 2>&1 | grep -E "per frame|rendered|error" |
                tee -a "$out/shot_gpu.log"
        done
    done
fi
