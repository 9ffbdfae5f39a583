"""File > Import > nerfpt model: a trained .npt (baked with `nerfpt bake`), a crop of it, and the baked .vdb
itself become Volume objects with the nerfpt material, placed as the model's cube and marked for export; bad
inputs give one-line errors.

blender -b --factory-startup --python tests/blender/test_import.py -- --build BUILD --name import
"""

import glob
import os
import sys

import bpy
from mathutils import Matrix

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import harness as h  # noqa: E402

a = h.args()
h.enable_addon(nerfpt=a.nerfpt)
from nerfpt_blender import model_file, volume_material  # noqa: E402

model = h.copy_model(a)
bpy.ops.wm.read_factory_settings(use_empty=True)
h.enable_addon(nerfpt=a.nerfpt)


def close(x, y, tol=1e-5):
    return all(abs(p - q) <= tol * max(1.0, abs(q)) for p, q in zip(x, y))


# The model: baked at 48 voxels, placed where its training cameras saw it.
obj = h.import_model(model, resolution=48)
h.log(f"imported {obj.name}: location {tuple(obj.location)}, scale {tuple(obj.scale)}")
s = obj.nerfpt_volume
h.check(
    obj.type == "VOLUME" and s.is_capture and s.source == "MODEL", "not a capture volume with source MODEL"
)
h.check(os.path.samefile(s.model_path, model), f"model_path {s.model_path}")
grid = os.path.join(a.work, "spheres.bake48.vdb")
h.check(os.path.samefile(bpy.path.abspath(obj.data.filepath), grid), f"grid {obj.data.filepath}")
h.check(
    not glob.glob(os.path.join(a.work, "*partial*")) and not glob.glob(os.path.join(a.work, "*.tmp*")),
    "leftovers",
)
# The sphere data set: scale 0.33, offset 0.5, aabb_scale 1 -> the model's box is world [-0.5/0.33, 0.5/0.33]^3,
# and the cube fills it. The object is the cube moved by -1/2 voxel in local space (Cycles' voxel centres): the
# grid has 48 voxels over [-1, 1], index -> local scale 2/48, so h = 1/48.
h.check(close(s.voxel_shift, (1 / 48,) * 3), f"voxel shift {tuple(s.voxel_shift)}")
cube = obj.matrix_world @ Matrix.Translation(s.voxel_shift)
h.check(close(cube.translation, (0, 0, 0), 1e-6), f"cube centre {tuple(cube.translation)}")
h.check(close(obj.scale, (0.5 / 0.33,) * 3), f"scale {tuple(obj.scale)}")
h.check(close(s.cube_min, (-1, -1, -1)) and close(s.cube_max, (1, 1, 1)), "a model's cube is [-1, 1]^3")
names = {g.name: g for g in obj.data.grids}
h.check({"density", "color"} <= set(names), f"grids {list(names)}")
h.check(abs(names["density"].matrix_object[0][0] - 2 / 48) < 1e-6, "voxel size")
h.check(obj.data.materials[0].name == volume_material.MATERIAL_NAME, f"material {obj.data.materials[0].name}")
r = obj.data.render
h.check(r.space == "WORLD" and r.precision == "FULL" and r.clipping == 0.0, "volume render settings")

# A crop: the box fills the cube, placed where it lies in the training world.
crop = ((0.3, 0.25, 0.2), (0.7, 0.75, 0.6))
cropped = h.import_model(model, resolution=24, use_crop=True, crop_min=crop[0], crop_max=crop[1])
place = model_file.placement(model, crop)
# Model axes x, y, z are world y, z, x: the world half sizes are (0.2, 0.2, 0.25) / 0.33.
h.check(close(cropped.scale, (0.2 / 0.33, 0.2 / 0.33, 0.25 / 0.33)), f"crop scale {tuple(cropped.scale)}")
crop_cube = cropped.matrix_world @ Matrix.Translation(cropped.nerfpt_volume.voxel_shift)
h.check(close(crop_cube.translation, place["centre"], 1e-6), f"crop centre {tuple(crop_cube.translation)}")
h.check(
    cropped.nerfpt_volume.use_crop and close(cropped.nerfpt_volume.crop_max, crop[1]), "crop not recorded"
)
h.check(len(glob.glob(os.path.join(a.work, "spheres.bake24_crop_*.vdb"))) == 1, "crop bake missing")

# The baked grid itself: its own coordinates, rendered from the grid.
vdb = h.import_model(grid)
t = vdb.nerfpt_volume
h.check(t.is_capture and t.source == "GRID" and not t.model_path, "a .vdb import renders its grid")
vdb_cube = vdb.matrix_world @ Matrix.Translation(t.voxel_shift)
h.check(
    close(vdb_cube.translation, (0, 0, 0)) and close(vdb.scale, (1, 1, 1)), "a .vdb keeps its coordinates"
)
h.check(all(t.cube_min[i] < t.cube_max[i] for i in range(3)), f"cube {tuple(t.cube_min)} {tuple(t.cube_max)}")
h.check(all(-1.2 < t.cube_min[i] and t.cube_max[i] < 1.2 for i in range(3)), "cube beyond the bake's box")


def expect_import_error(path, fragment, **options):
    try:
        bpy.ops.import_scene.nerfpt_model(filepath=path, **options)
    except RuntimeError as e:
        msg = str(e).strip()
        h.log(f"import {os.path.basename(path)}: {msg}")
        h.check(fragment in msg, f"'{fragment}' not in: {msg}")
        h.check(len(msg.splitlines()) == 1 and "Traceback" not in msg, f"not one line: {msg!r}")
        return
    raise AssertionError(f"import of {path} did not fail")


expect_import_error(os.path.join(a.work, "gone.npt"), "file not found")
junk = os.path.join(a.work, "junk.npt")
with open(junk, "wb") as f:
    f.write(b"not a model at all")
expect_import_error(junk, "not a nerfpt model file")
expect_import_error(model, "crop must lie inside", use_crop=True, crop_min=(-1, 0, 0), crop_max=(1, 1, 1))
empty = os.path.join(a.work, "empty.vdb")
open(empty, "w").close()
expect_import_error(empty, "empty.vdb")
h.check(len(bpy.data.volumes) == 3, f"{len(bpy.data.volumes)} volumes: a failed import left one")
h.log("import: OK")
