#!/usr/bin/env bash
# Re-runs COLMAP's matching and mapping with other matcher options on features already extracted by
# `nerfpt poses` (or `nerfpt capture`), and counts the jumps in the camera path: how the matcher settings in
# docs/benchmarks.md ("COLMAP poses for the curated beer frames") were compared.
# Usage: scripts/colmap_matching_experiment.sh WORK_FOLDER FRAMES_FOLDER OUT_FOLDER MATCHER [OPTIONS...]
#   e.g. scripts/colmap_matching_experiment.sh out/beer_capture/colmap out/beer_capture/frames out/exp_exh \
#        exhaustive_matcher
set -euo pipefail
work=${1:?WORK_FOLDER}; frames=${2:?FRAMES_FOLDER}; out=${3:?OUT_FOLDER}; shift 3
rm -rf "$out"; mkdir -p "$out/sparse"
cp "$work/database.db" "$out/database.db"
# Keep the features, drop the matches, so only the matcher under test decides.
/usr/bin/python3 - "$out/database.db" <<'PY'
import sqlite3, sys
c = sqlite3.connect(sys.argv[1]); c.execute("DELETE FROM matches"); c.execute("DELETE FROM two_view_geometries"); c.commit()
PY
t0=$(date +%s)
colmap "$@" --database_path "$out/database.db" --SiftMatching.use_gpu 0 >"$out/match.log" 2>&1
t1=$(date +%s)
colmap mapper --database_path "$out/database.db" --image_path "$frames" --output_path "$out/sparse" >"$out/mapper.log" 2>&1
t2=$(date +%s)
echo "matching $((t1 - t0)) s, mapping $((t2 - t1)) s"
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
for m in "$out"/sparse/*; do /usr/bin/python3 "$here/colmap_path_jumps.py" "$m"; done
