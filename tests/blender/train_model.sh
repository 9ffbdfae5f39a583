#!/usr/bin/env bash
# Trains the tiny model the Blender add-on tests import: the NeRF tests' sphere data set (three shaded spheres,
# 20 views of 32x32, tests/nerf_test_scene.h) with their small config, 400 steps on the CPU (seconds).
# Usage: train_model.sh NERFPT MAKE_SPHERE_DATASET OUT_DIR   -> OUT_DIR/spheres.npt
set -euo pipefail
nerfpt=$1 make_dataset=$2 out=$3
rm -rf "$out"
mkdir -p "$out"
"$make_dataset" "$out/data" 20 32
start=$(date +%s.%N)
"$nerfpt" train "$out/data" -o "$out/spheres.npt" --backend cpu --config "$out/data/config.json" --steps 400
awk -v a="$start" -v b="$(date +%s.%N)" 'BEGIN { printf "trained in %.1f s\n", b - a }'
"$nerfpt" info "$out/spheres.npt"
