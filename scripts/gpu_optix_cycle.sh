#!/usr/bin/env bash
# One OptiX cycle on the GPU machine (issue 13), after `scripts/gpu_check.sh pack` here with the OptiX headers in
# .optix/ (carry .gpu/bundle.tar.xz, .gpu/scenes, .gpu/nerf_demo and .gpu/nerf_synthetic): the OptiX parity
# tests; render_bench on the Cornell scenes; a lego model trained for 60 s and baked at 256^3 for the
# model-in-scene demo (frames/s at 1920x1080, 1 spp), a NeRF-only view beside `nerfpt view`, the direct-vs-baked
# error at equal time; then Nsight Compute on one launch of each. Logs in $OUT. Usage: gpu_optix_cycle.sh [--no-ncu]
# (GTEST_FILTER='*' runs every GPU test, not only the OptiX and shared-maths ones).
set -uo pipefail
# NERFPT_OPTIX_WAVEFRONT=0 / NERFPT_WAVEFRONT_STATS=1: the NeRF demo without and with the wavefront form's
# breakdown (render/gpu/optix_wavefront.cpp); NERFPT_SEGMENT_WARP_BELOW=0: the NeRF pass without its warp rounds.
cd "$(dirname "$0")/.."
out=${OUT:-/tmp/gpu_out}
mkdir -p "$out"
timeout 400 scripts/gpu_check.sh run --gtest_filter="${GTEST_FILTER:-OptixRender.*:SharedMathGpu.*}" >"$out/optix_tests.log" 2>&1
grep -E "OptiX|relMSE|seed|PASSED|FAILED|SKIPPED|Failure|error" "$out/optix_tests.log" | head -40
export LD_LIBRARY_PATH=/tmp/nerfpt-gpu/lib NERFPT_SHARED_DATA=$PWD/.gpu
bin=/tmp/nerfpt-gpu/bin
bench() { timeout 180 $bin/render_bench --backend optix "$@" 2>&1 | tee -a "$out/render_bench.log"; }
bench --res 320x240 --spp 64 --repeats 3 --scene cornell --scene cornell_volume
bench --res 1920x1080 --spp 64 --repeats 3 --scene cornell --scene cornell_volume

demo=/tmp/nerf_demo
mkdir -p $demo && cp .gpu/nerf_demo/*.gltf scenes/nerf_round_trip/scene.json $demo/
timeout 120 $bin/nerfpt train .gpu/nerf_synthetic/lego -o $demo/lego.npt --backend cuda --time 60 -q --force
timeout 60 $bin/nerfpt bake $demo/lego.npt -o $demo/lego_256.vdb --res 256 --backend cuda -q
ls -la $demo | tee "$out/demo_files.log"
bench --res 1920x1080 --spp 1 --repeats 3 --frames 20 --scene-file $demo/scene.gltf --scene-file $demo/scene_baked.gltf
# The NeRF queried per thread (the wavefront form off), and where the wavefront form's time goes.
echo "== per thread (NERFPT_OPTIX_WAVEFRONT=0)" | tee -a "$out/render_bench.log"
NERFPT_OPTIX_WAVEFRONT=0 bench --res 1920x1080 --spp 1 --repeats 2 --frames 3 --scene-file $demo/scene.gltf
NERFPT_WAVEFRONT_STATS=1 timeout 60 $bin/render_bench --backend optix --res 1920x1080 --spp 1 --repeats 1 --frames 3 \
    --scene-file $demo/scene.gltf 2>&1 | grep -E "wavefront|frames" | tee "$out/wavefront_stats.log"
# The NeRF pass without its warp-per-segment rounds (every round a thread per segment), for the comparison.
echo "== a thread per segment in every round (NERFPT_SEGMENT_WARP_BELOW=0)" | tee -a "$out/render_bench.log"
NERFPT_SEGMENT_WARP_BELOW=0 bench --res 1920x1080 --spp 1 --repeats 2 --frames 20 --scene-file $demo/scene.gltf
NERFPT_SEGMENT_WARP_BELOW=0 NERFPT_WAVEFRONT_STATS=1 timeout 60 $bin/render_bench --backend optix --res 1920x1080 \
    --spp 1 --repeats 1 --frames 3 --scene-file $demo/scene.gltf 2>&1 | grep -E "wavefront" | sed 's/^/thread rounds only: /' |
    tee -a "$out/wavefront_stats.log"
# NeRF only (a volume cube, grey background) through the path tracer, and nerfpt view of the same model.
bench --res 800x800 --spp 1 --repeats 3 --frames 50 --scene-file $demo/scene.json
NERFPT_WAVEFRONT_STATS=1 timeout 60 $bin/render_bench --backend optix --res 800x800 --spp 1 --repeats 1 --frames 3 \
    --scene-file $demo/scene.json 2>&1 | grep -E "wavefront|frames" | tee -a "$out/wavefront_stats.log"
echo "== per thread (NERFPT_OPTIX_WAVEFRONT=0)" | tee -a "$out/render_bench.log"
NERFPT_OPTIX_WAVEFRONT=0 bench --res 800x800 --spp 1 --repeats 2 --frames 10 --scene-file $demo/scene.json
timeout 60 $bin/view_bench $demo/lego.npt --res 800 2>&1 | tail -5 | tee "$out/view_bench.log" ||
    timeout 60 $bin/view_bench --help 2>&1 | head -5

# Direct vs baked at equal time (960x540): each against a 256-spp direct render.
r() { timeout 120 $bin/nerfpt render "$@" --res 960x540 --backend optix -q; }
r $demo/scene.gltf -o $demo/ref.exr --spp 256 --seed 99
for spp in 1 4 16; do
    for s in scene scene_baked; do
        start=$(date +%s.%N)
        r $demo/$s.gltf -o $demo/${s}_$spp.exr --spp $spp --seed 1
        end=$(date +%s.%N)
        echo "$s $spp spp: $(awk "BEGIN {print $end - $start}") s (process), $($bin/nerfpt compare $demo/${s}_$spp.exr $demo/ref.exr 2>&1 | tr '\n' ' ')"
    done
done 2>&1 | tee "$out/direct_vs_baked.log"

[[ ${1:-} == --no-ncu ]] && exit 0
sections="--section SpeedOfLight --section LaunchStats --section Occupancy --section WarpStateStats --section ComputeWorkloadAnalysis --section MemoryWorkloadAnalysis"
prof() {
    local name=$1
    shift
    timeout 150 ncu $sections -k regex:raygen -c 1 $bin/render_bench --backend optix --repeats 1 --spp 1 "$@" \
        >"$out/ncu_$name.log" 2>&1
    # The launch's kernel name is OptiX's: where it is not named after the raygen program, profile everything.
    if grep -q "No kernels were profiled" "$out/ncu_$name.log"; then
        timeout 200 ncu $sections -c 16 $bin/render_bench --backend optix --repeats 1 --spp 1 "$@" \
            >"$out/ncu_$name.log" 2>&1
    fi
    grep -E "Duration|Registers Per|Achieved Occupancy|Compute \(SM\) Throughput|Memory Throughput|L1/TEX Hit|L2 Hit|Stall|Local" "$out/ncu_$name.log" | head -30
}
prof cornell --res 1920x1080 --scene cornell
prof cornell_volume --res 1920x1080 --scene cornell_volume
prof demo --res 1920x1080 --scene-file $demo/scene.gltf
# The wavefront form's kernels over one frame (launches and the NeRF pass's rounds), one line each.
timeout 200 ncu --section SpeedOfLight --section LaunchStats -c 60 $bin/render_bench --backend optix --repeats 1 \
    --spp 1 --frames 1 --res 1920x1080 --scene-file $demo/scene.gltf >"$out/ncu_wavefront.log" 2>&1
grep -E "^  [a-zA-Z_].*\(|Duration|Registers Per" "$out/ncu_wavefront.log" | head -120 >"$out/ncu_wavefront_summary.log"
