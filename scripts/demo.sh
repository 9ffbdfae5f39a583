#!/usr/bin/env bash
# From a fresh clone to a picture: installs what is missing, builds Release in build/ (only what changed) and
# renders the example scene to out/demo.exr (linear) and out/demo.png (sRGB). Extra arguments go to
# `nerfpt render` (e.g. scripts/demo.sh --spp 16 --res 320x240 for a quick look).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

scripts/configure.sh >/dev/null
# The demo needs only the nerfpt binary, not the tests or benchmarks.
cmake --build build -j "${NERFPT_JOBS:-$(nproc)}" --target nerfpt_cli

mkdir -p out
build/nerfpt render scenes/example/scene.gltf -o out/demo.exr "$@"
echo "demo: open $(pwd)/out/demo.png (the linear image is $(pwd)/out/demo.exr)"
