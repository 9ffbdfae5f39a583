#!/usr/bin/env bash
# Issue 24's speed target on the GPU machine: the NeRF demo scene (scripts/make_nerf_demo_scene.py) with a
# relightable lego, relit, at 1920x1080, 1 spp on OptiX: >= 30 frames/s. One command:
#   - trains lego with --relightable on the GPU (60 s, then the relight stage) unless MODEL= names such a model;
#   - writes the demo scene with that model relit (the default for a relightable model) and, for reference, with
#     the same model emissive (extras.volume.shading "emissive": what the emissive demo renders);
#   - render_bench --frames N (the prepared scene rendered N times into the renderer's own frame: a viewer's frame
#     rate) for: relit in the wavefront form (the default), relit in the per-thread program
#     (NERFPT_OPTIX_WAVEFRONT=0; about 1 frame/s, so fewer frames), and emissive in the wavefront form; then one
#     relit render with NERFPT_WAVEFRONT_STATS=1 (where a frame's time goes: launches vs the NeRF pass).
# Run there after `scripts/gpu_check.sh run` (carry .gpu: the bundle with nerfpt and render_bench, .gpu/nerf_demo,
# .gpu/nerf_synthetic). MODEL=path/to/lego_relit.npt skips the training. Log in $OUT/relit_gpu.log (default
# /tmp/gpu_out); its last lines are the summary (frames/s per form).
set -uo pipefail
cd "$(dirname "$0")/.."
out=${OUT:-/tmp/gpu_out}
mkdir -p "$out"
log="$out/relit_gpu.log"
export LD_LIBRARY_PATH=/tmp/nerfpt-gpu/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
bin=${BIN:-/tmp/nerfpt-gpu/bin}
demo=/tmp/nerf_relit
mkdir -p $demo
nvidia-smi --query-gpu=name,driver_version,clocks.sm,clocks.max.sm --format=csv | tee "$log"
if [[ -n ${MODEL:-} ]]; then
    cp "$MODEL" $demo/lego_relit.npt
elif [[ ! -f $demo/lego_relit.npt ]]; then
    echo "== nerfpt train lego --relightable (60 s + the relight stage)" | tee -a "$log"
    start=$(date +%s)
    timeout 300 $bin/nerfpt train .gpu/nerf_synthetic/lego -o $demo/lego_relit.npt --backend cuda --time 60 \
        --relightable -q --force 2>&1 | tee -a "$log"
    echo "trained in $(($(date +%s) - start)) s" | tee -a "$log"
fi
[[ -f $demo/lego_relit.npt ]] || { echo "relit_gpu: no model $demo/lego_relit.npt" | tee -a "$log" >&2; exit 1; }
# The demo scene names lego.npt (in its own folder): the same scene with this model, relit and emissive.
sed 's/"file": "lego.npt"/"file": "lego_relit.npt"/' .gpu/nerf_demo/scene.gltf >$demo/relit.gltf
sed 's/"file": "lego.npt"/"file": "lego_relit.npt", "shading": "emissive"/' .gpu/nerf_demo/scene.gltf \
    >$demo/emissive.gltf
grep -q '"lego_relit.npt"' $demo/relit.gltf ||
    { echo "relit_gpu: .gpu/nerf_demo/scene.gltf does not name lego.npt" | tee -a "$log" >&2; exit 1; }
for s in relit emissive; do
    echo "$s.gltf: $($bin/nerfpt info $demo/$s.gltf | grep -E '^ +shading')" | tee -a "$log"
done

bench() {  # label, frames, scene, then environment assignments for render_bench
    local label=$1 frames=$2 scene=$3
    shift 3
    echo "== $label" | tee -a "$log"
    env "$@" timeout 300 $bin/render_bench --backend optix --res 1920x1080 --spp 1 --repeats 3 --frames "$frames" \
        --scene-file "$scene" 2>&1 | tee -a "$log" | tee "$out/relit_gpu_$label.txt"
}
bench relit_wavefront 48 $demo/relit.gltf NERFPT_OPTIX_WAVEFRONT=1
bench relit_per_thread 8 $demo/relit.gltf NERFPT_OPTIX_WAVEFRONT=0
bench emissive_wavefront 48 $demo/emissive.gltf NERFPT_OPTIX_WAVEFRONT=1
echo "== relit, wavefront, NERFPT_WAVEFRONT_STATS=1 (one render; the extra synchronisation costs a little)" |
    tee -a "$log"
NERFPT_WAVEFRONT_STATS=1 timeout 120 $bin/render_bench --backend optix --res 1920x1080 --spp 1 --repeats 1 \
    --scene-file $demo/relit.gltf 2>&1 | grep -E "wavefront:" | tee -a "$log"

# The summary: the table's last column (frames/s) of each run.
echo "== summary (1920x1080, 1 spp, OptiX; target: relit wavefront >= 30 frames/s)" | tee -a "$log"
for label in relit_wavefront relit_per_thread emissive_wavefront; do
    fps=$(grep -E '^\| ' "$out/relit_gpu_$label.txt" | grep -v -E '^\| scene' | tail -1 | awk -F'|' '{print $(NF-1)}')
    echo "$label: ${fps:-?} frames/s" | tee -a "$log"
done
