#!/usr/bin/env bash
# Checks that Blender reads a baked grid (nerfpt bake -o MODEL.vdb): imports it as a Volume object and prints
# its grids and bounding box. Exits non-zero when the import fails or there is no 'density' grid.
# Usage: scripts/check_bake_blender.sh MODEL.vdb   (needs blender on PATH; not part of CI)
set -euo pipefail

vdb=${1:?usage: check_bake_blender.sh MODEL.vdb}
[[ -f $vdb ]] || { echo "check_bake_blender: '$vdb' not found" >&2; exit 1; }
command -v blender >/dev/null || { echo "check_bake_blender: blender is not installed" >&2; exit 1; }
vdb=$(realpath "$vdb")

# Blender exits 0 even when the Python expression raises, so the result travels through a marker line.
out=$(blender -b --factory-startup --python-exit-code 3 --python-expr "
import bpy, os, sys
from mathutils import Vector
path = sys.argv[sys.argv.index('--') + 1]
bpy.ops.object.volume_import(filepath=path, directory=os.path.dirname(path),
                             files=[{'name': os.path.basename(path)}])
obj = bpy.context.active_object
vol = obj.data
vol.grids.load()
print('BAKECHECK object', obj.name, 'type', obj.type, 'file', vol.filepath)
for g in vol.grids:
    print('BAKECHECK grid', repr(g.name), 'type', g.data_type, 'channels', g.channels, 'loaded', g.is_loaded)
corners = [obj.matrix_world @ Vector(c) for c in obj.bound_box]
lo = [min(c[i] for c in corners) for i in range(3)]
hi = [max(c[i] for c in corners) for i in range(3)]
print('BAKECHECK bbox min (%.4f, %.4f, %.4f) max (%.4f, %.4f, %.4f)' % (*lo, *hi))
names = [g.name for g in vol.grids]
print('BAKECHECK', 'OK' if 'density' in names else 'MISSING density')
" -- "$vdb" 2>&1) || { echo "$out"; echo "check_bake_blender: blender failed" >&2; exit 1; }
grep '^BAKECHECK' <<<"$out" | sed 's/^BAKECHECK //'
grep -q '^BAKECHECK OK$' <<<"$out" || { echo "check_bake_blender: no 'density' grid in $vdb" >&2; exit 1; }
