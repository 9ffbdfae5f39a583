#!/usr/bin/env bash
# Runs COLMAP's three poses steps on a folder of frames with the options under test, timing each step beside
# the machine's load, and prints features per image, matches per pair (scripts/colmap_db_stats.py), the
# registered frames and the camera-path jumps of the largest model: how the --poses-quality settings in
# docs/benchmarks.md ("How fast COLMAP can be") were chosen. nerfpt poses runs the same commands.
# Usage: EXTRACT="--SiftExtraction.first_octave 0" MATCH="..." MAP="..." \
#          scripts/colmap_settings_experiment.sh FRAMES_FOLDER OUT_FOLDER [FEATURES_DB]
#   FEATURES_DB: reuse that database's features (extraction skipped, matches dropped), to vary matching or
#   mapping alone. The pose error against a truth needs nerfpt: build/nerfpt pose-error OUT/sparse/N TRUTH.
set -euo pipefail
frames=${1:?FRAMES_FOLDER}; out=${2:?OUT_FOLDER}; reuse=${3:-}
frames=$(cd "$frames" && pwd)
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
rm -rf "$out"; mkdir -p "$out/sparse"
db="$out/database.db"
(cd "$frames" && ls | grep -Ei '\.(png|jpe?g)$' | grep -v '^contact_sheet.png$' | sort) >"$out/frames.txt"
load() { cut -d' ' -f1 /proc/loadavg; }
step() {  # name, log, command...
    local name=$1 log=$2; shift 2
    local l0 t0 t1; l0=$(load); t0=$(date +%s.%N)
    /usr/bin/time -f '%U %S' -o "$out/$log.cpu" "$@" >"$out/$log" 2>&1 ||
        { echo "$name failed, see $out/$log"; tail -3 "$out/$log"; exit 1; }
    t1=$(date +%s.%N)
    # CPU seconds (user + system) measure the work even on a busy machine; wall seconds only on a quiet one.
    printf '%s %.1f s wall, %.1f s CPU (load %s -> %s)\n' "$name" "$(echo "$t1 - $t0" | bc)" \
        "$(awk '{print $1 + $2}' "$out/$log.cpu")" "$l0" "$(load)" | tee -a "$out/times.txt"
}
if [[ -n "$reuse" ]]; then
    cp "$reuse" "$db"
    /usr/bin/python3 -c "import sqlite3,sys; c=sqlite3.connect(sys.argv[1]); c.execute('DELETE FROM matches'); c.execute('DELETE FROM two_view_geometries'); c.commit()" "$db"
    echo "extraction reused from $reuse" | tee -a "$out/times.txt"
else
    # shellcheck disable=SC2086
    step extraction extract.log colmap feature_extractor --database_path "$db" --image_path "$frames" \
        --image_list_path "$out/frames.txt" --ImageReader.single_camera 1 --ImageReader.camera_model OPENCV \
        --SiftExtraction.use_gpu 0 ${EXTRACT:-}
fi
# shellcheck disable=SC2086
step matching match.log colmap sequential_matcher --database_path "$db" --SiftMatching.use_gpu 0 \
    --SequentialMatching.quadratic_overlap 0 ${MATCH:-}
# shellcheck disable=SC2086
step mapping mapper.log colmap mapper --database_path "$db" --image_path "$frames" --output_path "$out/sparse" \
    --image_list_path "$out/frames.txt" ${MAP:-}
/usr/bin/python3 "$here/colmap_db_stats.py" "$db" | tee "$out/stats.txt"
best=""; best_n=0
for m in "$out"/sparse/*; do
    [[ -f "$m/images.bin" ]] || continue
    n=$(/usr/bin/python3 -c "import struct,sys; print(struct.unpack('<Q', open(sys.argv[1],'rb').read(8))[0])" "$m/images.bin")
    if (( n > best_n )); then best=$m; best_n=$n; fi
done
echo "registered $best_n of $(wc -l <"$out/frames.txt") frames in $best" | tee -a "$out/stats.txt"
[[ -n "$best" ]] && /usr/bin/python3 "$here/colmap_path_jumps.py" "$best" | tee -a "$out/stats.txt"
