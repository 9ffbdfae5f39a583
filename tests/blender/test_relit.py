"""A relightable capture in Blender (issue 24): imported, exported and rendered lit by the Blender scene's lights.

1. Import of a relightable model (the blender.model fixture's spheres_relit.npt, `nerfpt train --relightable`):
   the grid is the albedo bake (`nerfpt bake --colour albedo`, MODEL.albedo48.vdb), the material "nerfpt volume
   (relit)" a Principled Volume whose colour is the grid's colour, density our sigma, absorption colour black
   (extinction = sigma, single-scattering albedo = the albedo) and no density attribute of its own; the object
   is marked shading Relit, nerfpt renders the model. The same model imported with shading Emissive, and the
   plain model, import as before (radiance bake, the emission material).
2. The export keeps it relit: extras.volume is the .npt with "shading": "relit" (`nerfpt info` on the exported
   scene says "shading relit"), the area light is exported as an emissive polygon and nothing is warned.
3. Blender's lights reach it, in both engines: with the area light hidden (black world) the object's pixels
   are black (an emissive capture would glow), with it they are lit.
4. How close the Cycles preview is to the nerfpt render (docs/blender.md): the object's pixels (Cycles' alpha
   > 0.5 with the floor hidden) of both engines, two seeds each: channel means and relMSE (nerfpt compare's
   weight 1/(r^2 + 0.01)), with the part the noise explains. The preview is an approximation (isotropic
   scattering instead of a surface BSDF), so its agreement is measured, not bounded by the noise; the test only
   requires each channel's mean ratio within [1/3, 3], which a preview that is unlit or emissive fails.

blender -b --factory-startup --python tests/blender/test_relit.py -- --build BUILD --name relit
    [--res 64x48] [--spp 32] [--bake-res 48] [--relit-model PATH]
"""

import json
import math
import os
import shutil
import sys
import time

import bpy
from mathutils import Euler

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import harness as h  # noqa: E402

a = h.args(
    [
        ("--res", dict(default="64x48")),
        ("--spp", dict(type=int, default=32)),
        ("--bake-res", dict(type=int, default=48)),
        ("--relit-model", dict(default="")),
    ]
)
t_start = time.time()
width, height = (int(v) for v in a.res.split("x"))
relit_src = a.relit_model or os.path.join(a.root, "model", "spheres_relit.npt")
h.check(os.path.isfile(relit_src), f"no relightable model at {relit_src} (the blender.model fixture makes it)")
relit_model = os.path.join(a.work, "relit.npt")
shutil.copyfile(relit_src, relit_model)
plain_model = h.copy_model(a)

bpy.ops.wm.read_factory_settings(use_empty=True)
h.enable_addon(nerfpt=a.nerfpt)
sc = bpy.context.scene
sc.render.resolution_x, sc.render.resolution_y = width, height
sc.render.resolution_percentage = 100
sc.view_settings.view_transform = "Standard"
sc.view_settings.look = "None"


def material_nodes(obj):
    mat = obj.data.materials[0]
    return mat, {n.bl_idname: n for n in mat.node_tree.nodes}


# --- 1. import ---------------------------------------------------------------------------------------------
obj = h.import_model(relit_model, resolution=a.bake_res)
s = obj.nerfpt_volume
grid = os.path.basename(obj.data.filepath)
h.check(grid == f"relit.albedo{a.bake_res}.vdb", f"the relit import baked {grid}, not the albedo bake")
h.check(s.shading == "RELIT" and s.source == "MODEL", f"shading {s.shading}, source {s.source}")
mat, nodes = material_nodes(obj)
h.check(mat.name == "nerfpt volume (relit)", f"material '{mat.name}'")
pv = nodes.get("ShaderNodeVolumePrincipled")
h.check(pv is not None, f"no Principled Volume in '{mat.name}': {sorted(nodes)}")
h.check("ShaderNodeEmission" not in nodes, "the relit material emits")
h.check(tuple(pv.inputs["Absorption Color"].default_value[:3]) == (0.0, 0.0, 0.0), "absorption colour not black")
h.check(pv.inputs["Density Attribute"].default_value == "", "Principled Volume multiplies by a density grid again")
h.check(pv.inputs["Anisotropy"].default_value == 0.0 and pv.inputs["Emission Strength"].default_value == 0.0, "")
color_link = pv.inputs["Color"].links[0].from_node
h.check(color_link.bl_idname == "ShaderNodeAttribute" and color_link.attribute_name == "color", "colour input")
h.check(pv.inputs["Density"].is_linked, "density input not linked to sigma")
h.log(f"import: {grid}, material '{mat.name}'")

# The same model imported emissive, and a model that is not relightable: as before.
for path, options, bake in (
    (relit_model, dict(shading="EMISSIVE"), f"relit.bake{a.bake_res}.vdb"),
    (plain_model, {}, f"spheres.bake{a.bake_res}.vdb"),
):
    o = h.import_model(path, resolution=a.bake_res, **options)
    m, n = material_nodes(o)
    h.check(os.path.basename(o.data.filepath) == bake, f"{path} {options}: baked {o.data.filepath}")
    h.check(o.nerfpt_volume.shading == "EMISSIVE" and m.name == "nerfpt volume", f"{path}: {m.name}")
    h.check("ShaderNodeEmission" in n and "ShaderNodeVolumePrincipled" not in n, f"{path}: nodes {sorted(n)}")
    bpy.data.objects.remove(o)

# --- the scene: a floor, one area light, the capture standing on the floor ----------------------------------
floor = h._quad("floor", [(-3, -3, 0), (3, -3, 0), (3, 3, 0), (-3, 3, 0)], h._material("floor", (0.8, 0.8, 0.8)))
h.place_capture(obj, y=0.0)
light = bpy.data.lights.new("softbox", "AREA")
light.shape, light.size, light.energy = "SQUARE", 1.0, 150.0
lobj = bpy.data.objects.new("softbox", light)
lobj.location = (1.2, -1.0, 1.8)
lobj.rotation_euler = Euler((math.radians(40), 0.0, math.radians(50)))  # -Z towards the capture
sc.collection.objects.link(lobj)
cam = bpy.data.cameras.new("camera")
cam.sensor_fit = "VERTICAL"
cam.angle_y = math.radians(30)
cobj = bpy.data.objects.new("camera", cam)
cobj.location = (0.0, -2.8, 1.1)
cobj.rotation_euler = Euler((math.radians(72), 0.0, 0.0))
sc.collection.objects.link(cobj)
sc.camera = cobj
sc.world = bpy.data.worlds.new("black")
sc.world.use_nodes = True
sc.world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)
h.cycles_settings(4)

# --- 2. export ----------------------------------------------------------------------------------------------
gltf_path = os.path.join(a.work, "scene.gltf")
result, printed = h.console(lambda: bpy.ops.export_scene.nerfpt_gltf(filepath=gltf_path))
h.check(result == {"FINISHED"}, f"export returned {result}")
h.check("nerfpt ignores" not in printed, f"the export warned: {printed}")
g = json.load(open(gltf_path))
vols = [n["extras"]["volume"] for n in g["nodes"] if "volume" in n.get("extras", {})]
h.check(len(vols) == 1, f"{len(vols)} volume cubes exported")
vol = vols[0]
h.check(vol["file"].endswith("relit.npt") and vol.get("shading") == "relit", f"extras.volume {vol}")
emitters = [m for m in g["materials"] if m.get("emissiveFactor") and "softbox" in m.get("name", "")]
meshes = [n for n in g["nodes"] if "softbox" in n.get("name", "")]
h.check(meshes and emitters, f"the area light is not an emissive polygon: nodes {[n.get('name') for n in g['nodes']]}")
info = h.nerfpt(a, "info", gltf_path).stdout
h.check("    shading relit\n" in info, f"nerfpt info does not say relit:\n{info}")
h.log("export: relit .npt, the area light as an emissive polygon")

# --- 3 and 4: renders ---------------------------------------------------------------------------------------
import numpy as np  # noqa: E402


def object_mask():
    """Cycles' alpha with the floor hidden and a transparent film: the capture's coverage."""
    floor.hide_render = True
    sc.render.film_transparent = True
    sc.render.engine = "CYCLES"
    sc.cycles.samples = 16
    s = sc.render.image_settings
    s.file_format, s.color_depth, s.color_mode = "OPEN_EXR", "32", "RGBA"
    path = os.path.join(a.work, "mask.exr")
    sc.render.filepath = path
    bpy.ops.render.render(write_still=True)
    img = bpy.data.images.load(path, check_existing=False)
    w, hh = img.size
    alpha = np.array(img.pixels[:], dtype=np.float64).reshape(hh, w, 4)[::-1, :, 3]
    bpy.data.images.remove(img)
    floor.hide_render = False
    sc.render.film_transparent = False
    return alpha > 0.5


mask = object_mask()
n_obj = int(mask.sum())
h.check(n_obj >= 0.05 * width * height, f"the capture covers {n_obj} pixels only")

# Lights off: black in both engines (relit captures emit nothing).
lobj.hide_render = True
for engine in ("NERFPT", "CYCLES"):
    path = os.path.join(a.work, f"dark_{engine.lower()}.exr")
    h.render(path, engine, 4, 1)
    dark = float(h.read_exr(path)[mask].mean())
    h.log(f"light hidden: {engine} object mean {dark:.3g}")
    h.check(dark < 1e-4, f"{engine}: the capture is not black without lights (mean {dark:.3g}): it emits")
lobj.hide_render = False

out = h.render_halves(a, "relit", a.spp)
na, nb = out[("NERFPT", 1)][mask], out[("NERFPT", 2)][mask]
ca, cb = out[("CYCLES", 1)][mask], out[("CYCLES", 2)][mask]
m, r = (na + nb) / 2, (ca + cb) / 2
w = 1.0 / (r * r + 0.01)
rel_mse = float(((m - r) ** 2 * w).mean())
noise = float((((na - nb) ** 2 + (ca - cb) ** 2) * w / 4).mean())
h.log(f"object's pixels ({n_obj}): relMSE {rel_mse:.4g}, of which the noise explains {noise:.4g}")
failures = []
for k, name in enumerate("RGB"):
    mn, mc = float(m[:, k].mean()), float(r[:, k].mean())
    h.log(f"object mean {name}: nerfpt {mn:.5f}, Cycles preview {mc:.5f}, Cycles / nerfpt {mc / mn:.3f}")
    if not (mn > 0 and 1 / 3 <= mc / mn <= 3):
        failures.append(f"mean {name}: Cycles {mc:.4g} against nerfpt {mn:.4g}")
h.save_png((out[("NERFPT", 1)] + out[("NERFPT", 2)]) / 2, os.path.join(a.work, "relit_nerfpt.png"))
h.save_png((out[("CYCLES", 1)] + out[("CYCLES", 2)]) / 2, os.path.join(a.work, "relit_cycles.png"))
h.check(not failures, "; ".join(failures))
h.log(f"passed in {time.time() - t_start:.0f} s")
