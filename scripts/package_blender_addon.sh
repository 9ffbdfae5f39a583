#!/usr/bin/env bash
# Packs the Blender add-on (blender/nerfpt_blender) into a zip that Blender's "Install add-on" takes.
# Usage: scripts/package_blender_addon.sh [OUT.zip [BUILD_DIR]]   (defaults out/nerfpt_blender.zip, build)
# The zip's build_dirs.py names BUILD_DIR (this checkout's build/ folder), so that the add-on finds the nerfpt
# binary there when it is not on PATH (the add-on's preference overrides both).
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
out=${1:-$root/out/nerfpt_blender.zip}
build=$(realpath -m "${2:-$root/build}")
mkdir -p "$(dirname "$out")"
out=$(cd "$(dirname "$out")" && pwd)/$(basename "$out")

stage=$(mktemp -d)
trap 'rm -rf "$stage"' EXIT
mkdir "$stage/nerfpt_blender"
cp "$root"/blender/nerfpt_blender/*.py "$stage/nerfpt_blender/"
python3 - "$stage/nerfpt_blender/build_dirs.py" "$build" <<'PY'
import sys
path, build = sys.argv[1], sys.argv[2]
text = open(path).read().replace("BUILD_DIRS = []", "BUILD_DIRS = [%r]" % build)
open(path, "w").write(text)
PY
# A zip with fixed timestamps and order: the same sources give the same bytes.
python3 - "$stage" "$out.tmp" <<'PY'
import os, sys, zipfile
stage, out = sys.argv[1], sys.argv[2]
with zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as z:
    for name in sorted(os.listdir(os.path.join(stage, "nerfpt_blender"))):
        info = zipfile.ZipInfo("nerfpt_blender/" + name, date_time=(2024, 1, 1, 0, 0, 0))
        info.compress_type = zipfile.ZIP_DEFLATED
        info.external_attr = 0o644 << 16
        with open(os.path.join(stage, "nerfpt_blender", name), "rb") as f:
            z.writestr(info, f.read())
PY
mv "$out.tmp" "$out"
echo "wrote $out"
