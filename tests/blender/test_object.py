"""A capture that knows its object (issue 25: `nerfpt capture`'s object frame) imports standing on the 3D cursor.

The blender.model fixture's spheres_object.npt is the sphere model given an object frame (train_model.sh: turned
30 deg about Z after 10 deg about X, 2 capture units a metre, the box 0.6 x 0.6 x 0.5 m above the base centre).
1. Import with the cursor at C: every corner of the object's box, taken through the frame into the training
   world, then into the cube's local space (model_file.placement of the baked crop) and through the Blender
   object's cube matrix, lands on C + the corner in metres (upright, real size); the bake is of the crop that
   holds the box (model_file.object_crop), and the volume is marked for object placement.
2. The export: extras.volume.placement "object" and no crop; the node is a pure translation to C (glTF Y up)
   and the cube is the object's box in the frame turned Y up; `nerfpt render` reads the exported scene.
3. With "Stand at the 3D cursor" off it imports as any model, where its cameras saw it (no rotation).

blender -b --factory-startup --python tests/blender/test_object.py -- --build BUILD --name object
"""

import json
import os
import shutil
import sys

import bpy
from mathutils import Matrix, Vector

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import harness as h  # noqa: E402

a = h.args()
h.enable_addon(nerfpt=a.nerfpt)
from nerfpt_blender import model_file  # noqa: E402

src = os.path.join(os.path.dirname(a.model), "spheres_object.npt")
h.check(os.path.isfile(src), f"no model with an object frame at {src} (the blender.model fixture makes it)")
model = os.path.join(a.work, "spheres_object.npt")
shutil.copyfile(src, model)
bpy.ops.wm.read_factory_settings(use_empty=True)
h.enable_addon(nerfpt=a.nerfpt)

frame = model_file.object_frame(model)
h.check(frame is not None and frame["metric"], f"object frame {frame}")
h.check(model_file.object_frame(os.path.join(os.path.dirname(a.model), "spheres.npt")) is None,
        "a model without OBJF has no object frame")
lo, hi = frame["box"]
corners = [Vector((hi[0] if i & 1 else lo[0], hi[1] if i & 2 else lo[1], hi[2] if i & 4 else lo[2]))
           for i in range(8)]


def close(x, y, tol=1e-4):
    return all(abs(p - q) <= tol * max(1.0, abs(q)) for p, q in zip(x, y))


# 1. Standing on the cursor.
cursor = Vector((1.0, 2.0, 0.5))
bpy.context.scene.cursor.location = cursor
obj = h.import_model(model, resolution=32)
s = obj.nerfpt_volume
h.check(s.object_placement and not s.use_crop, "not marked for object placement")
crop = model_file.object_crop(model, frame)
h.check(close(s.crop_min, crop[0]) and close(s.crop_max, crop[1]), f"bake crop {tuple(s.crop_min)}")
place = model_file.placement(model, crop)
cube_to_world = Matrix.Translation(place["centre"]) @ Matrix.Diagonal((*place["half_size"], 1.0))
cube = obj.matrix_world @ Matrix.Translation(s.voxel_shift)
object_to_world = Matrix(frame["object_to_world"])
worst = 0.0
for c in corners:
    local = cube_to_world.inverted() @ (object_to_world @ c)
    got = cube @ local
    worst = max(worst, (got - (cursor + c)).length)
h.log(f"object box corners off their place on the cursor by at most {worst:.2e} m")
h.check(worst < 1e-4, f"the object does not stand on the cursor: a corner is {worst} m off")
grids = [f for f in os.listdir(a.work) if f.startswith("spheres_object.bake32_crop_") and f.endswith(".vdb")]
h.check(len(grids) == 1, f"crop bake missing: {os.listdir(a.work)}")

# 2. The export places the object frame, not the crop.
gltf_path = os.path.join(a.work, "scene.gltf")
cam = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
bpy.context.scene.collection.objects.link(cam)
cam.location = (1.0, -1.0, 1.0)
cam.rotation_euler = (1.2, 0.0, 0.0)
bpy.context.scene.camera = cam
bpy.context.scene.render.resolution_x, bpy.context.scene.render.resolution_y = 32, 24
bpy.ops.export_scene.nerfpt_gltf(filepath=gltf_path)
with open(gltf_path) as f:
    gltf = json.load(f)
nodes = [n for n in gltf["nodes"] if "volume" in n.get("extras", {})]
h.check(len(nodes) == 1, f"{len(nodes)} volume nodes")
vol = nodes[0]["extras"]["volume"]
h.check(vol.get("placement") == "object" and "crop" not in vol, f"extras.volume {vol}")
m = nodes[0]["matrix"]  # column major
expect = [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, cursor.x, cursor.z, -cursor.y, 1]
h.check(close(m, expect), f"node matrix {m}, expected a translation to the cursor {expect[12:15]}")
acc = gltf["accessors"][gltf["meshes"][nodes[0]["mesh"]]["primitives"][0]["attributes"]["POSITION"]]
h.check(close(acc["min"], [lo[0], lo[2], -hi[1]]) and close(acc["max"], [hi[0], hi[2], -lo[1]]),
        f"cube {acc['min']} .. {acc['max']}")
out = h.nerfpt(a, "render", gltf_path, "-o", os.path.join(a.work, "render.exr"), "--spp", "1", "-q")
h.check(os.path.isfile(os.path.join(a.work, "render.exr")), "nerfpt render wrote nothing")

# 3. Off: where its cameras saw it.
plain = h.import_model(model, resolution=32, stand_at_cursor=False)
h.check(not plain.nerfpt_volume.object_placement, "marked for object placement with the option off")
whole = model_file.placement(model)
plain_cube = plain.matrix_world @ Matrix.Translation(plain.nerfpt_volume.voxel_shift)
h.check(close(plain_cube.translation, whole["centre"]) and close(plain.scale, whole["half_size"]),
        f"placed at {tuple(plain_cube.translation)}, scale {tuple(plain.scale)}")
h.log("object: OK")
