#!/usr/bin/env bash
# The OptiX A/B measurements of docs/benchmarks.md (issue 13), on the GPU machine after gpu_optix_cycle.sh has
# trained the demo model into /tmp/nerf_demo (or with DEMO=folder holding lego.npt, lego_256.vdb and the demo
# scenes): grids sampled through hardware-filtered textures or by eight voxel reads (NERFPT_OPTIX_GRID_TEXTURES),
# and the register limit of the OptiX module (NERFPT_OPTIX_MAX_REGISTERS). Logs in $OUT.
set -uo pipefail
cd "$(dirname "$0")/.."
out=${OUT:-/tmp/gpu_out}
mkdir -p "$out"
export LD_LIBRARY_PATH=/tmp/nerfpt-gpu/lib NERFPT_SHARED_DATA=$PWD/.gpu
bin=/tmp/nerfpt-gpu/bin
demo=${DEMO:-/tmp/nerf_demo}
bench() { timeout 120 $bin/render_bench --backend optix "$@" 2>&1 | grep -E "^\| [a-z]" | tee -a "$out/experiments.log"; }
NERFPT_OPTIX_GRID_TEXTURES=1 timeout 120 scripts/gpu_check.sh run --gtest_filter='OptixRender.CornellVolume*:OptixRender.Nerf*' \
    >"$out/texture_tests.log" 2>&1
grep -E "relMSE|seed|PASSED|FAILED" "$out/texture_tests.log"
for textures in 1 0; do
    echo "NERFPT_OPTIX_GRID_TEXTURES=$textures" | tee -a "$out/experiments.log"
    export NERFPT_OPTIX_GRID_TEXTURES=$textures
    bench --res 1920x1080 --spp 64 --repeats 3 --scene cornell_volume
    bench --res 320x240 --spp 64 --repeats 3 --scene cornell_volume
    bench --res 1920x1080 --spp 1 --repeats 3 --frames 20 --scene-file $demo/scene_baked.gltf
done
unset NERFPT_OPTIX_GRID_TEXTURES
for regs in 64 96 0; do  # 96 is the default since this run
    echo "NERFPT_OPTIX_MAX_REGISTERS=$regs (0: OptiX's default, 128 here)" | tee -a "$out/experiments.log"
    export NERFPT_OPTIX_MAX_REGISTERS=$regs
    bench --res 1920x1080 --spp 64 --repeats 3 --scene cornell --scene cornell_volume
    bench --res 1920x1080 --spp 1 --repeats 2 --frames 5 --scene-file $demo/scene.gltf
done
