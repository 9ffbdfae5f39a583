#!/usr/bin/env bash
# The poses benchmark of issue 16 (docs/benchmarks.md, "How fast COLMAP can be"): `nerfpt poses` with each
# --poses-quality on the two captures, one after the other, and a table of time per COLMAP step (wall and CPU,
# with the 1-minute load average at its start), features per frame, matches per pair, frames registered, path
# jumps and the pose errors:
#   beer  the 100 frames `nerfpt curate` keeps from ../shared/data/captures/beer/Beer.mp4 (720x1280), compared
#         piece by piece with the reference model shipped beside it (rotation / centre median per piece)
#   rich  the feature-rich synthetic turntable (tests/tools/make_turntable_capture.cpp --rich: 200 frames of
#         540x960, of which curate keeps 100), compared with its true poses (median and max)
#   handheld  the simulated handheld capture (scripts/make_handheld_capture.py: an object on a textured table
#         with props, one walk around it with hand shake, 100 frames of 540x960 rendered by Blender, encoded
#         with libx264, all kept by curate), compared with its true poses; needs blender
# Usage: scripts/bench_poses.sh [OUT_DIR (default build/bench_poses)] [QUALITY ...] (default: fast balanced best)
#   NERFPT_BENCH_CAPTURES="beer rich handheld" (the default), NERFPT_BENCH_THREADS (default: all cores).
# The frames are made once and kept in OUT_DIR (the synthetic renders take ~8 CPU-minutes each); each run's COLMAP
# folder and log stay in OUT_DIR/<capture>_<quality>/. Wall times are the target's measure and mean something
# only on a quiet machine: the load column says how quiet it was; CPU times compare runs on a busy one.
# Needs a Release build (nerfpt and nerfpt_make_turntable_capture), COLMAP and ffmpeg on PATH.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
out=${1:-$root/build/bench_poses}
shift || true
qualities=("$@")
[[ ${#qualities[@]} -gt 0 ]] || qualities=(fast balanced best)
captures=${NERFPT_BENCH_CAPTURES:-beer rich handheld}
threads=${NERFPT_BENCH_THREADS:-0}
nerfpt=$root/build/nerfpt
py=$(command -v /usr/bin/python3 || command -v python3)  # Debian's, with sqlite3
maker=$root/build/tests/nerfpt_make_turntable_capture
beer_video=$root/../shared/data/captures/beer/Beer.mp4
beer_reference=$root/../shared/data/captures/beer/sparse/0
mkdir -p "$out"
out=$(cd "$out" && pwd)
[[ -x $nerfpt ]] || { echo "bench_poses: $nerfpt is not built (cmake --build build --target nerfpt_cli)"; exit 1; }

frames_of() {  # capture name -> its frames folder, made when missing
    case $1 in
    beer)
        [[ -f $out/beer_frames/curate.json ]] ||
            "$nerfpt" -q curate "$beer_video" -o "$out/beer_frames" >&2
        echo "$out/beer_frames" ;;
    rich)
        if [[ ! -f $out/rich/truth.json ]]; then
            [[ -x $maker ]] || { echo "bench_poses: build nerfpt_make_turntable_capture first" >&2; exit 1; }
            echo "bench_poses: rendering the feature-rich turntable (200 frames of 540x960) ..." >&2
            "$maker" "$out/rich" --width 540 --height 960 --frames 200 --fov-y 60 --rich >&2
        fi
        [[ -f $out/rich_frames/curate.json ]] ||
            "$nerfpt" -q curate "$out/rich/turntable.mp4" -o "$out/rich_frames" >&2
        echo "$out/rich_frames" ;;
    handheld)
        if [[ ! -f $out/handheld/handheld.mp4 ]]; then
            echo "bench_poses: rendering the handheld capture (100 frames of 540x960, Blender) ..." >&2
            blender -b --factory-startup --python "$root/scripts/make_handheld_capture.py" -- "$out/handheld" \
                --frames 100 >"$out/handheld_render.log" 2>&1
            ffmpeg -loglevel error -y -framerate 30 -i "$out/handheld/render/frame_%05d.png" -c:v libx264 -crf 18 \
                -pix_fmt yuv420p "$out/handheld/handheld.mp4" >&2
        fi
        [[ -f $out/handheld_frames/curate.json ]] ||
            "$nerfpt" -q curate "$out/handheld/handheld.mp4" -o "$out/handheld_frames" --target-frames 100 >&2
        echo "$out/handheld_frames" ;;
    *) echo "bench_poses: unknown capture '$1' (beer, rich, handheld)" >&2; exit 2 ;;
    esac
}

table=$out/table.md
{
    echo "| capture | quality | features/frame | matches/pair (verified pairs, inliers/pair) | extraction s wall / CPU (load) | matching | mapping | loops | total wall / CPU | registered | jumps | rotation median / max (deg) | centre median / max (%) |"
    echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|"
} >"$table"
for cap in $captures; do
    frames=$(frames_of "$cap")
    for q in "${qualities[@]}"; do
        run=$out/${cap}_$q
        rm -rf "$run"
        mkdir -p "$run"
        echo "bench_poses: $cap, --poses-quality $q (load $(cut -d' ' -f1-3 /proc/loadavg)) ..." >&2
        if ! "$nerfpt" poses "$frames" -o "$run/transforms.json" --poses-quality "$q" --threads "$threads" \
            >"$run/poses.log" 2>&1; then
            echo "bench_poses: nerfpt poses failed, see $run/poses.log" >&2
            tail -3 "$run/poses.log" >&2
            continue
        fi
        if [[ $cap == beer ]]; then
            "$nerfpt" pose-error "$run/transforms.json" "$beer_reference" --match rate --known-rate 10 0 --pieces \
                --json "$run/pose_error.json" >"$run/pose_error.txt" 2>&1 || true
        else
            "$nerfpt" pose-error "$run/transforms.json" "$out/$cap/truth.json" --json "$run/pose_error.json" \
                >"$run/pose_error.txt" 2>&1 || true
        fi
        "$py" "$root/scripts/colmap_db_stats.py" "$run/colmap/database.db" --json >"$run/db_stats.json"
        "$py" - "$cap" "$q" "$run" >>"$table" <<'EOF'
import json, re, sys
cap, q, run = sys.argv[1:4]
log = open(f"{run}/poses.log").read()
steps = {m[0]: (float(m[1]), float(m[2]), m[3]) for m in
         re.findall(r"^\s+(extraction|matching|mapping|loops)\s+([\d.]+) s wall,\s+([\d.]+) s CPU \(load ([\d.]+)", log, re.M)}
reg = re.search(r"registered (\d+) of (\d+) frames", log)
jumps = re.search(r"the camera path jumps (\d+) time", log)
db = json.load(open(f"{run}/db_stats.json"))
try:
    pe = json.load(open(f"{run}/pose_error.json"))
except (OSError, ValueError):
    pe = None
cell = lambda s: f"{steps[s][0]:.0f} / {steps[s][1]:.0f} ({steps[s][2]})" if s in steps else "-"
wall = sum(v[0] for v in steps.values()); cpu = sum(v[1] for v in steps.values())
if pe is None:
    rot = centre = "n/a"
elif cap == "beer":  # one row per continuous piece of the reference
    rot = ", ".join(f"{p['rotation_deg']['median']:.2f}" for p in pe["pieces"])
    centre = ", ".join(f"{p['centre_percent']['median']:.2f}" for p in pe["pieces"])
else:
    rot = f"{pe['rotation_deg']['median']:.3f} / {pe['rotation_deg']['max']:.3f}"
    centre = f"{pe['centre_percent']['median']:.3f} / {pe['centre_percent']['max']:.3f}"
f, m, v = db["features_per_image"], db["matches_per_pair"], db["inliers_per_verified_pair"]
print(f"| {cap} | {q} | {f['mean']:.0f} | {m['mean']:.0f} ({v['count']}, {v['mean']:.0f}) | {cell('extraction')} | {cell('matching')} | "
      f"{cell('mapping')} | {cell('loops')} | {wall:.0f} / {cpu:.0f} | {reg[1]} of {reg[2]} | {jumps[1] if jumps else 0} | {rot} | {centre} |")
EOF
        tail -1 "$table" >&2
    done
done
echo
echo "nerfpt poses on $(nproc) cores ($(uname -n), $(colmap help 2>&1 | sed -n 1p | sed 's/ --.*//')), $(date -u +%F); beer: rotation and centre medians per reference piece"
cat "$table"
