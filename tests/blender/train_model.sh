#!/usr/bin/env bash
# Trains the tiny model the Blender add-on tests import: the NeRF tests' sphere data set (three shaded spheres,
# 20 views of 32x32, tests/nerf_test_scene.h) with their small config, 400 steps on the CPU (seconds).
# Then the same model made relightable (`--resume --relightable`: the relight stage added to the trained NeRF) for
# test_relit.py, with a small relight stage (150 steps over 1024 surface points and 4096 borrowing pixels): the test needs a relightable
# model, not a good one.
# And the plain model given an object frame, as `nerfpt capture` gives one (test_object.py): object space -> the
# training world turned 30 deg about Z after 10 deg about X, scaled 2 (one metre of object is 2 units of the
# capture), its origin at (0.1, -0.2, -0.5); the box 0.6 x 0.6 x 0.5 m above the origin.
# Usage: train_model.sh NERFPT MAKE_SPHERE_DATASET OUT_DIR SET_OBJECT_FRAME
#   -> OUT_DIR/spheres.npt, OUT_DIR/spheres_relit.npt, OUT_DIR/spheres_object.npt
set -euo pipefail
nerfpt=$1 make_dataset=$2 out=$3 set_frame=$4
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
    --relight-steps 150 --relight-points 1024 --relight-pixels 4096 -q
awk -v a="$start" -v b="$(date +%s.%N)" 'BEGIN { printf "relight stage in %.1f s\n", b - a }'
"$nerfpt" info "$out/spheres_relit.npt" | grep relight
cat >"$out/object_frame.json" <<'JSON'
{"version": 1, "metric": true,
 "object_to_world": [1.732050807569, -0.984807753012, 0.173648177667, 0.1,
                     1.0, 1.705737063905, -0.300767466361, -0.2,
                     0.0, 0.347296355334, 1.969615506024, -0.5,
                     0, 0, 0, 1],
 "box": {"min": [-0.3, -0.3, 0.0], "max": [0.3, 0.3, 0.5]}}
JSON
"$set_frame" "$out/spheres.npt" "$out/object_frame.json" "$out/spheres_object.npt"
"$nerfpt" info "$out/spheres_object.npt" | grep -i object
