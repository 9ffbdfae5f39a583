"""Export round trip: a Blender scene with a mesh, a point light, a camera and an imported capture exports
(File > Export > nerfpt scene) to a glTF that `nerfpt info` reads back with the volume, the camera and the light
where Blender has them, the capture's extras pointing at its model (or its grid), the render settings as scene
extras and materials mapped as docs/blender.md says; what nerfpt does not render as Blender does is one warning
report, each thing listed once. Then F12 with the nerfpt engine: the image comes back, with nerfpt's progress in
Blender's render stats and the same one warning. Then render errors: nerfpt's own error (a model file that went
missing) reaches Blender as one readable line, not a traceback.

blender -b --factory-startup --python tests/blender/test_export.py -- --build BUILD --name export
"""

import json
import math
import os
import re
import sys

import bpy
from mathutils import Euler, Matrix, Vector

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import harness as h  # noqa: E402

a = h.args()
bpy.ops.wm.read_factory_settings(use_empty=True)
h.enable_addon(nerfpt=a.nerfpt)
model = h.copy_model(a)
sc = bpy.context.scene

obj = h.import_model(model, resolution=24)
obj.location = (0.4, -0.2, 0.7)
obj.rotation_euler = (0.0, 0.0, math.radians(30))
obj.scale = (0.5, 0.5, 0.5)
obj.nerfpt_volume.density_scale = 2.0
obj.nerfpt_volume.emission_scale = 1.5

# A mesh (a floor with a Diffuse BSDF), a point light and a camera.
floor = bpy.data.meshes.new("floor")
floor.from_pydata([(-2, -2, 0), (2, -2, 0), (2, 2, 0), (-2, 2, 0)], [], [(0, 1, 2, 3)])
floor.materials.append(h._material("floor_diffuse", (0.2, 0.4, 0.6)))
sc.collection.objects.link(bpy.data.objects.new("floor", floor))


def wall(name, make_material):
    """A quad whose material make_material(node_tree, output) builds (the mapping table of docs/blender.md)."""
    me = bpy.data.meshes.new(name)
    me.from_pydata([(-2, 2, 0), (2, 2, 0), (2, 2, 2), (-2, 2, 2)], [], [(0, 1, 2, 3)])
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    mat.node_tree.nodes.clear()
    out = mat.node_tree.nodes.new("ShaderNodeOutputMaterial")
    node = make_material(mat.node_tree)
    mat.node_tree.links.new(node.outputs[0], out.inputs["Surface"])
    me.materials.append(mat)
    sc.collection.objects.link(bpy.data.objects.new(name, me))


def principled(nt):
    n = nt.nodes.new("ShaderNodeBsdfPrincipled")
    n.inputs["Base Color"].default_value = (0.5, 0.5, 0.5, 1)
    n.inputs["Roughness"].default_value = 0.7
    n.inputs[next(k for k in ("Specular", "Specular IOR Level") if k in n.inputs)].default_value = 0.0
    return n


def glossy(nt):
    n = nt.nodes.new("ShaderNodeBsdfGlossy")
    n.inputs["Color"].default_value = (0.9, 0.6, 0.2, 1)
    n.inputs["Roughness"].default_value = 0.3
    return n


def emission(nt):
    n = nt.nodes.new("ShaderNodeEmission")
    n.inputs["Color"].default_value = (1.0, 0.5, 0.25, 1)
    n.inputs["Strength"].default_value = 4.0
    return n


def glass(nt):
    n = nt.nodes.new("ShaderNodeBsdfGlass")
    n.inputs["IOR"].default_value = 1.33
    return n


for name, make in (("principled", principled), ("glossy", glossy), ("emission", emission), ("glass", glass)):
    wall(name, make)
light = bpy.data.lights.new("lamp", "POINT")
light.energy = 100.0
light.shadow_soft_size = 0.0
lo = bpy.data.objects.new("lamp", light)
sc.collection.objects.link(lo)
lo.location = (1.0, -1.5, 2.5)
cam = bpy.data.cameras.new("camera")
cam.sensor_fit = "VERTICAL"
cam.angle_y = math.radians(35)
co = bpy.data.objects.new("camera", cam)
sc.collection.objects.link(co)
co.location = (3.0, -4.0, 1.5)
co.rotation_euler = Euler((math.radians(80), 0.0, math.radians(35)))
sc.camera = co
sc.render.resolution_x, sc.render.resolution_y, sc.render.resolution_percentage = 160, 120, 50
sc.nerfpt.samples = 16
sc.nerfpt.max_bounces = 3
sc.world = bpy.data.worlds.new("grey")
sc.world.use_nodes = True
sc.world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.1, 0.2, 0.3, 1.0)
sc.world.node_tree.nodes["Background"].inputs["Strength"].default_value = 2.0
# What nerfpt does not render as Cycles does: an area light's narrow spread (it becomes a Lambertian emitter),
# and a Principled subsurface on a material that two meshes share (listed once all the same).
softbox = bpy.data.lights.new("softbox", "AREA")
softbox.spread = math.radians(90)
area = bpy.data.objects.new("softbox", softbox)
area.location = (0.0, 0.0, 6.0)  # out of view
sc.collection.objects.link(area)
skin = bpy.data.materials.new("skin")
skin.use_nodes = True
skin.node_tree.nodes.clear()
bsdf = skin.node_tree.nodes.new("ShaderNodeBsdfPrincipled")
skin.node_tree.links.new(bsdf.outputs[0], skin.node_tree.nodes.new("ShaderNodeOutputMaterial").inputs["Surface"])
bsdf.inputs[next(k for k in ("Subsurface", "Subsurface Weight") if k in bsdf.inputs)].default_value = 0.2
for i in range(2):
    me = bpy.data.meshes.new(f"skin{i}")
    me.from_pydata([(-2, -2, 5 + i), (2, -2, 5 + i), (2, 2, 5 + i)], [], [(0, 1, 2)])  # out of view
    me.materials.append(skin)
    sc.collection.objects.link(bpy.data.objects.new(f"skin{i}", me))
IGNORED = (
    "area light 'softbox': spread 90 deg is rendered as 180 deg",
    "material 'skin': Principled subsurface is ignored",
)


def check_ignored(printed, what):
    """One warning report (Blender prints reports as 'Warning: ...' in background mode), each thing once."""
    lines = [ln for ln in printed.splitlines() if "nerfpt ignores:" in ln]
    h.check(len(lines) == 1, f"{what}: {len(lines)} 'nerfpt ignores' reports, not one: {lines}")
    h.check(lines[0].startswith("Warning: nerfpt ignores: "), f"{what}: not a warning report: {lines[0]}")
    for note in IGNORED:
        h.check(lines[0].count(note) == 1, f"{what}: '{note}' listed {lines[0].count(note)} times: {lines[0]}")
    h.log(f"{what}: {lines[0]}")


gltf_path = os.path.join(a.work, "scene.gltf")
result, printed = h.console(lambda: bpy.ops.export_scene.nerfpt_gltf(filepath=gltf_path))
h.check(result == {"FINISHED"}, f"export returned {result}")
check_ignored(printed, "export")
info = h.nerfpt(a, "info", gltf_path).stdout
h.log("nerfpt info scene.gltf:\n" + info.rstrip())


def y_up(v):
    return Vector((v[0], v[2], -v[1]))


def vec(text):
    return Vector(float(x) for x in text.strip("()").split(","))


def near(p, q, tol):
    return (p - q).length <= tol


# Camera: position and forward (nerfpt prints 3 significant digits).
m = re.search(
    r"^camera\s+'camera'.* at (\([^)]*\)), forward (\([^)]*\)), up (\([^)]*\)), yfov ([\d.]+) deg", info, re.M
)
h.check(m, "no camera 'camera' in nerfpt info")
fwd = co.matrix_world.to_3x3() @ Vector((0, 0, -1))
h.check(
    near(vec(m.group(1)), y_up(co.location), 0.01),
    f"camera at {m.group(1)}, Blender {tuple(y_up(co.location))}",
)
h.check(near(vec(m.group(2)), y_up(fwd), 0.01), f"camera forward {m.group(2)}, Blender {tuple(y_up(fwd))}")
h.check(abs(float(m.group(4)) - 35.0) < 0.1, f"yfov {m.group(4)}")
# The point light, in W/(4 pi sr) as Cycles' point lights.
m = re.search(r"^\s+point\s+'lamp' at (\([^)]*\)), intensity (\([^)]*\))", info, re.M)
h.check(m, "no point light 'lamp' in nerfpt info")
h.check(near(vec(m.group(1)), y_up(lo.location), 0.01), f"light at {m.group(1)}")
h.check(near(vec(m.group(2)), Vector((100 / (4 * math.pi),) * 3), 0.01), f"intensity {m.group(2)}")
# The volume: world bounds = the cube's 8 corners through the object's transform, extras as set.
m = re.search(r"^\s+'spheres' world bounds (\([^)]*\)) \.\. (\([^)]*\)), translation (\([^)]*\))", info, re.M)
h.check(m, "no volume 'spheres' in nerfpt info")
cube = obj.matrix_world @ Matrix.Translation(obj.nerfpt_volume.voxel_shift)
corners = [y_up(cube @ Vector((x, y, z))) for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]
lo_b = Vector(min(c[i] for c in corners) for i in range(3))
hi_b = Vector(max(c[i] for c in corners) for i in range(3))
h.check(
    near(vec(m.group(1)), lo_b, 0.01) and near(vec(m.group(2)), hi_b, 0.01),
    f"bounds {m.group(1)} .. {m.group(2)}",
)
h.check(near(vec(m.group(3)), y_up(cube.translation), 0.01), f"translation {m.group(3)}")
extras = json.loads(re.search(r"^\s+extras (\{.*\})$", info, re.M).group(1))["volume"]
h.check(extras["file"] == "spheres.npt", f"extras file {extras['file']} (relative to the glTF)")
h.check(extras["density_scale"] == 2.0 and extras["emission_scale"] == 1.5, f"extras {extras}")
# The Diffuse BSDF as Lambert: no metal, no specular layer (docs/blender.md).
lambert = r"^\s+floor_diffuse\s+diffuse\s+base \(0\.2, 0\.4, 0\.6\), roughness 1, specular 0, double-sided$"
h.check(re.search(lambert, info, re.M), "the floor's Diffuse BSDF is not exported as Lambert")
for name, line in (
    (
        "principled",
        r"diffuse\s+base \(0\.5, 0\.5, 0\.5\), roughness 0\.7, specular 0\b",
    ),  # Specular 0: no layer
    ("glossy", r"metal\s+base \(0\.9, 0\.6, 0\.2\), roughness 0\.3, metallic 1\b"),
    ("emission", r"emissive emission \(4, 2, 1\), base \(0, 0, 0\)"),
    ("glass", r"glass\s+transmission 1, ior 1\.33\b"),
):
    h.check(
        re.search(r"^\s+" + name + r"\s+" + line, info, re.M),
        f"material '{name}' not mapped as docs/blender.md says",
    )
h.check(re.search(r"^render\s+80x60, 16 spp, max depth 4\b", info, re.M), "render settings")
h.check(re.search(r"^\s+environment constant \(0\.2, 0\.4, 0\.6\)", info, re.M), "world colour x strength")

# F12 with the nerfpt engine: the image comes back, nerfpt's progress reaches Blender's progress and stats, and
# what nerfpt ignores is one warning. (nerfpt prints progress lines after 2 s only: a render this short shows
# its final 100%.)
f12 = os.path.join(a.work, "f12.exr")
seconds, printed = h.console(lambda: h.render(f12, "NERFPT", 16, 1))
check_ignored(printed, "F12")
h.check(
    re.search(r"\| nerfpt: rendering 80x60, 16 spp: 100%$", printed, re.M),
    "nerfpt's progress did not reach Blender's render stats",
)
px = h.read_exr(f12)
h.check(px.shape == (60, 80, 3) and px.mean() > 0.01, f"the F12 image: shape {px.shape}, mean {px.mean():.4g}")
h.log(f"F12: {seconds:.1f} s, image mean {px.mean():.4g}")

# The grid instead of the model: its density is per local unit, the export makes it per world unit.
obj.nerfpt_volume.source = "GRID"
bpy.ops.export_scene.nerfpt_gltf(filepath=gltf_path)
g = json.load(open(gltf_path))
node = next(n for n in g["nodes"] if n.get("name") == "spheres" and "mesh" in n)
v = node["extras"]["volume"]
h.check(v["file"] == "spheres.bake24.vdb", f"grid file {v['file']}")
# Density per local unit, the object at scale 0.5: per world unit it is twice the grid's, times the user's 2.
h.check(abs(v["density_scale"] - 2.0 / 0.5) < 1e-5, f"grid density_scale {v['density_scale']}")
h.nerfpt(a, "info", gltf_path)

# A render error: the model went missing. One line in Blender, naming the file.
obj.nerfpt_volume.source = "MODEL"
os.rename(model, model + ".away")
sc.render.engine = "NERFPT"
try:
    bpy.ops.render.render(write_still=False)
    raise AssertionError("the render of a scene whose model is missing did not fail")
except RuntimeError as e:
    msg = str(e).strip()
h.log(f"render error: {msg}")
h.check("spheres.npt" in msg and "not found" in msg, f"unexpected message: {msg}")
h.check(len(msg.splitlines()) == 1 and "Traceback" not in msg, f"not one line: {msg!r}")
os.rename(model + ".away", model)

# nerfpt's own error: a corrupt model file.
with open(model, "r+b") as f:
    f.seek(200)
    f.write(b"\xff" * 64)
try:
    bpy.ops.render.render(write_still=False)
    raise AssertionError("the render of a corrupt model did not fail")
except RuntimeError as e:
    msg = str(e).strip()
h.log(f"render error: {msg}")
h.check("nerfpt render failed" in msg and "spheres.npt" in msg, f"unexpected message: {msg}")
h.check(len(msg.splitlines()) == 1 and "Traceback" not in msg, f"not one line: {msg!r}")
h.log("export: OK")
# Blender's exit code is 1 after any render that reported an error (right for `blender -b -f`); these errors were
# the point of the test, so the code must say it passed.
sys.exit(0)
