#!/usr/bin/env bash
# The viewer's H200 targets (issue 27) on the GPU machine: `nerfpt serve` of the NeRF demo scene (lego queried
# directly) with OptiX at 1280x720, driven by bench/serve_bench (a page that pans the camera and sends the next
# move as soon as the previous move's frame arrives). Targets: >= 30 frames/s while the camera moves, <= 50 ms at
# the server from a camera message to its first frame. Two runs: full resolution on every move (--preview 1,
# OptiX's default and the targets' setting: 1 spp a frame), then --preview 2 (640x360 while moving).
# There, after `scripts/gpu_check.sh bundle nerfpt serve_bench` here (carry .gpu/bundle.tar.xz, .gpu/nerf_demo,
# .gpu/nerf_synthetic): bench/serve_gpu.sh. MODEL=path/to/lego.npt skips the 60 s training. Logs in $OUT.
set -uo pipefail
cd "$(dirname "$0")/.."
out=${OUT:-/tmp/gpu_out}
mkdir -p "$out"
scripts/gpu_check.sh run --gtest_filter=NONE >/dev/null 2>&1  # unpacks the bundle (again when it changed)
export LD_LIBRARY_PATH=/tmp/nerfpt-gpu/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
bin=${BIN:-/tmp/nerfpt-gpu/bin}
demo=/tmp/nerf_serve
mkdir -p $demo
cp .gpu/nerf_demo/scene.gltf $demo/scene.gltf
if [[ -n ${MODEL:-} ]]; then
    cp "$MODEL" $demo/lego.npt
elif [[ ! -f $demo/lego.npt ]]; then
    timeout 120 $bin/nerfpt train .gpu/nerf_synthetic/lego -o $demo/lego.npt --backend cuda --time 60 -q --force
fi
log=$out/serve_gpu.log
nvidia-smi --query-gpu=name,driver_version,clocks.sm,clocks.max.sm --format=csv | tee "$log"
port=7123
for preview in 1 2; do
    args=(serve $demo/scene.gltf --backend optix --res 1280x720 --port $port --preview "$preview")
    echo "== nerfpt ${args[*]}" | tee -a "$log"
    $bin/nerfpt "${args[@]}" >"$out/serve_server_$preview.log" 2>&1 &
    server=$!
    for _ in $(seq 300); do  # OptiX compiles its modules at start-up: up to a minute
        (exec 3<>/dev/tcp/127.0.0.1/$port) 2>/dev/null && break
        sleep 0.2
    done
    timeout 150 $bin/serve_bench $port --seconds 10 2>&1 | tee -a "$log"  # OptiX's first compile: a minute
    kill $server 2>/dev/null
    wait $server 2>/dev/null
    port=$((port + 1))
done
