#!/usr/bin/env bash
# Trains the tiny model the Blender add-on tests import: the NeRF tests' sphere data set (three shaded spheres,
# 20 views of 32x32, tests/nerf_test_scene.h) with their small config, 400 steps on the CPU (seconds).
# Then the same model made relightable (`--resume --relightable`: the relight stage added to the trained NeRF) for
# test_relit.py, with a small relight stage (150 steps over 1024 surface points): the test needs a relightable
# model, not a good one.
# Usage: train_model.sh NERFPT MAKE_SPHERE_DATASET OUT_DIR   -> OUT_DIR/spheres.npt, OUT_DIR/spheres_relit.npt
set -euo pipefail
nerfpt=$1 make_dataset=$2 out=$3
rm -rf "$out"
mkdir -p "$out"
"$make_dataset" "$out/data" 20 32
start=$(date +%s.%N)
"$nerfpt" train "$out/data" -o "$out/spheres.npt" --backend cpu --config "$out/data/config.json" --steps 400
awk -v a="$start" -v b="$(date +%s.%N)" 'BEGIN { printf "trained in %.1f s\n", b - a }'
"$nerfpt" info "$out/spheres.npt"
cp "$out/spheres.npt" "$out/spheres_relit.npt"
start=$(date +%s.%N)
"$nerfpt" train "$out/data" -o "$out/spheres_relit.npt" --backend cpu --steps 400 --resume --relightable \
    --relight-steps 150 --relight-points 1024 -q
awk -v a="$start" -v b="$(date +%s.%N)" 'BEGIN { printf "relight stage in %.1f s\n", b - a }'
"$nerfpt" info "$out/spheres_relit.npt" | grep relight
