#!/usr/bin/env bash
# Renders what ../shared/data/relight/score.py scores (issue 24) for a relightable model:
#   PRED/relit/LIGHT/r_N.exr  the 20 test views under `sunset` and `studio` (the lighting's emissive quads and sky,
#                             the model in the training world's box, --transparent), 400x400
#   PRED/aov/{albedo,normal}_N.exr  the first-event AOVs of the sunset renders (world normals, +Y up)
#   PRED/scene/render.exr     the room scene (scene/scene.json with the model), 320x240 at ROOM_SPP
# Usage: BIN=build MODEL=dev.npt DATA=../shared/data/relight/dev PRED=out/pred bench/relight_dev.sh render
# Options by variable: SPP (relit views, default 64), ROOM_SPP (default 1024), BACKEND (cpu|optix, default the
# renderer's own choice), VIEWS (default all 20), SHADING (relit or emissive: the volume's "shading", default the
# model's own). Then: score.py DATA PRED.
# The skies are the linear ones of lights.json's stops (bench/relight_skies.py: the dev set's env.exr files are
# sRGB-encoded, not the sky Cycles rendered the truth with).
set -euo pipefail
mode=${1:-render}
[[ $mode == render ]] || { echo "usage: relight_dev.sh render (with BIN MODEL DATA PRED set)" >&2; exit 2; }
: "${BIN:?BIN: the folder holding nerfpt}" "${MODEL:?MODEL: the .npt}" "${DATA:?DATA: relight/dev}" "${PRED:?PRED}"
spp=${SPP:-64}
room_spp=${ROOM_SPP:-1024}
backend=${BACKEND:+--backend $BACKEND}
model=$(realpath "$MODEL")
data=$(realpath "$DATA")
scenes=$(mktemp -d)
trap 'rm -rf "$scenes"' EXIT
py=python3  # one with numpy (a pyenv shim here may lack it, the system one there)
for p in python3 /usr/bin/python3; do "$p" -c 'import numpy' 2>/dev/null && { py=$p; break; }; done
"$py" -c 'import OpenImageIO' 2>/dev/null ||
    export PYTHONPATH="$(realpath "$(dirname "$0")/../scripts/exr_shim")${PYTHONPATH:+:$PYTHONPATH}"
"$py" "$(dirname "$0")/relight_skies.py" "$data" "$scenes/skies"
python3 - "$data" "$model" "$scenes" "${VIEWS:-}" "${SHADING:-}" <<'PY'
import json, os, sys
data, model, out, views, shading = sys.argv[1:6]
volume = {"name": "capture", "file": model, "translation": [0, 0, 0],
          "rotation": [-0.7071067811865476, 0, 0, 0.7071067811865476], "scale": [1.5151515151515151] * 3}
if shading:
    volume["shading"] = shading
for light in ("sunset", "studio"):
    frames = json.load(open(os.path.join(data, "relit", light, "transforms.json")))["frames"]
    keep = range(len(frames)) if not views else [int(v) for v in views.split(",")]
    for k in keep:
        cam = frames[k]["nerfpt_camera"]
        scene = {"include": [os.path.join(data, "lights", light, "scene.gltf")],
                 "camera": {"position": cam["position"], "look_at": cam["look_at"], "up": cam["up"],
                            "yfov_deg": cam["yfov_deg"]},
                 "environment": {"file": os.path.join(out, "skies", light + ".exr"), "strength": 1.0},
                 "volumes": [volume],
                 "render": {"width": 400, "height": 400, "spp": 64, "max_depth": 8}}
        json.dump(scene, open(os.path.join(out, "%s_%d.json" % (light, k)), "w"), indent=1)
room = json.load(open(os.path.join(data, "scene", "scene.json")))
room["include"] = [os.path.join(data, "scene", f) for f in room["include"]]
room["environment"]["file"] = os.path.join(out, "skies", "room.exr")
for v in room["volumes"]:
    v["file"] = model
    if shading:
        v["shading"] = shading
json.dump(room, open(os.path.join(out, "room.json"), "w"), indent=1)
PY
mkdir -p "$PRED/relit/sunset" "$PRED/relit/studio" "$PRED/aov" "$PRED/scene"
for f in "$scenes"/sunset_*.json "$scenes"/studio_*.json; do
    name=$(basename "$f" .json)
    light=${name%_*}
    k=${name##*_}
    start=$(date +%s.%N)
    if [[ $light == sunset ]]; then
        "$BIN/nerfpt" render "$f" -o "$PRED/relit/$light/r_$k.exr" --transparent --spp "$spp" $backend -q \
            --aov albedo,normal --aov-files
        mv "$PRED/relit/$light/r_$k.albedo.exr" "$PRED/aov/albedo_$k.exr"
        mv "$PRED/relit/$light/r_$k.normal.exr" "$PRED/aov/normal_$k.exr"
    else
        "$BIN/nerfpt" render "$f" -o "$PRED/relit/$light/r_$k.exr" --transparent --spp "$spp" $backend -q
    fi
    echo "$light view $k: $(awk "BEGIN {print $(date +%s.%N) - $start}") s"
done
start=$(date +%s.%N)
"$BIN/nerfpt" render "$scenes/room.json" -o "$PRED/scene/render.exr" --spp "$room_spp" $backend -q
echo "room: $(awk "BEGIN {print $(date +%s.%N) - $start}") s at $room_spp spp"
