#!/usr/bin/env bash
# From a fresh clone to a picture: installs what is missing, builds Release in build/ (only what changed), then
#  - with the team's data (../shared/data/nerf_synthetic/lego): trains a NeRF of lego on the CPU for 3 minutes
#    (kept in out/nerf_demo/lego.npt and reused by later runs), places it on a pedestal in a Cornell box next to
#    a mirror sphere (scripts/make_nerf_demo_scene.py) and path-traces it to out/demo.exr / out/demo.png;
#  - without it: renders the example scene (scenes/example) instead.
# Extra arguments go to `nerfpt render` (e.g. scripts/demo.sh --spp 8 for a quick look).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

scripts/configure.sh >/dev/null
# The demo needs only the nerfpt binary, not the tests or benchmarks.
cmake --build build -j "${NERFPT_JOBS:-$(nproc)}" --target nerfpt_cli

mkdir -p out
lego="${NERFPT_SHARED_DATA:-../shared/data}/nerf_synthetic/lego"
if [[ -f "$lego/transforms_train.json" ]]; then
    mkdir -p out/nerf_demo
    python3 scripts/make_nerf_demo_scene.py out/nerf_demo/scene.gltf
    if [[ ! -f out/nerf_demo/lego.npt ]]; then
        echo "demo: training lego at 200x200 for 3 minutes (out/nerf_demo/lego.npt)"
        build/nerfpt train "$lego" -o out/nerf_demo/lego.train.npt --downscale 2 --time 180 --force
        mv out/nerf_demo/lego.train.npt out/nerf_demo/lego.npt
    fi
    build/nerfpt render out/nerf_demo/scene.gltf -o out/demo.exr --res 400x400 --spp 32 "$@"
else
    echo "demo: $lego not found; rendering the example scene instead of the NeRF demo"
    build/nerfpt render scenes/example/scene.gltf -o out/demo.exr "$@"
fi
echo "demo: open $(pwd)/out/demo.png (the linear image is $(pwd)/out/demo.exr)"
