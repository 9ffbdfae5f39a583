"""The Principled BSDF's Specular through the export says what Cycles 3.x renders (docs/blender.md, "Specular").

1. The file: Principled materials at Specular 0, 0.01, 0.1, 0.5, 1, IOR 1.3 at Specular 0.1, Specular 0 on a
   30% metal and on glass. Cycles reflects with the exact Fresnel of the index whose F0 is 0.08 Specular; the
   exported KHR_materials_specular must give F0 = specularFactor x specularColorFactor x F0(ior) = 0.08 Specular
   (to float precision) and specularFactor = min(1, 21 Favg - 20 F0), Favg the exact Fresnel's
   cosine-weighted average, integrated here independently (1e-3); glass keeps specularFactor 1.
2. A render of the specular layer alone: a black Principled sphere (Specular 0, roughness 0.5) in a white
   world, Cycles against the nerfpt engine, agreeing within the noise (harness.compare_within_noise: relMSE
   excess within 4 standard errors, channel means within 4 combined standard errors). Cycles' sphere is
   black; with specularFactor left at 1 nerfpt's has a grazing rim (measured: image mean +1.0%, 40 times the limit; relMSE excess 29 standard errors). (A room of
   Principled walls at Specular 0 is not compared here: Cycles' Principled diffuse is Burley's, whose
   difference from Lambert depends on the roughness, -6% to +5% over 0..1 in the test room; docs/blender.md.)

blender -b --factory-startup --python tests/blender/test_specular.py -- --build BUILD --name specular
    [--res 80x60] [--spp 128] [--specular 0] [--roughness 0.5]
"""

import json
import math
import os
import sys
import time

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import harness as h  # noqa: E402

a = h.args(
    [
        ("--res", dict(default="80x60")),
        ("--spp", dict(type=int, default=128)),
        ("--specular", dict(type=float, default=0.0, help="the sphere's Specular (for measuring others)")),
        ("--roughness", dict(type=float, default=0.5, help="the sphere's Roughness")),
    ]
)
t_start = time.time()
width, height = (int(v) for v in a.res.split("x"))
bpy.ops.wm.read_factory_settings(use_empty=True)
h.enable_addon(nerfpt=a.nerfpt)
sc = bpy.context.scene


def principled(name, base=(0.8, 0.8, 0.8), specular=0.5, metallic=0.0, transmission=0.0, ior=1.45, rough=0.5):
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    p = mat.node_tree.nodes["Principled BSDF"]
    p.inputs["Base Color"].default_value = (*base, 1.0)
    p.inputs["Specular"].default_value = specular
    p.inputs["Metallic"].default_value = metallic
    p.inputs["Transmission"].default_value = transmission
    p.inputs["IOR"].default_value = ior
    p.inputs["Roughness"].default_value = rough
    return mat


# 1. The file's values.
CASES = {  # name: (specular, metallic, transmission, ior)
    "s0": (0.0, 0.0, 0.0, 1.45),
    "s001": (0.01, 0.0, 0.0, 1.45),
    "s01": (0.1, 0.0, 0.0, 1.45),
    "s05": (0.5, 0.0, 0.0, 1.45),
    "s1": (1.0, 0.0, 0.0, 1.45),
    "s01_ior13": (0.1, 0.0, 0.0, 1.3),
    "s0_metal": (0.0, 0.3, 0.0, 1.45),
    "s0_glass": (0.0, 0.0, 1.0, 1.45),
}
for i, (name, (s, m, t, ior)) in enumerate(CASES.items()):
    h._quad(name, [(i, 10, 5), (i + 0.5, 10, 5), (i + 0.5, 10.5, 5), (i, 10.5, 5)],
            principled(name, specular=s, metallic=m, transmission=t, ior=ior))  # fmt: skip
gltf_path = os.path.join(a.work, "materials.gltf")
result = bpy.ops.export_scene.nerfpt_gltf(filepath=gltf_path)
h.check(result == {"FINISHED"}, f"export returned {result}")
with open(gltf_path) as f:
    gltf = json.load(f)
h.nerfpt(a, "info", gltf_path)  # nerfpt reads it


def fresnel(c, eta):
    s2 = (1 - c * c) / eta**2
    ct = np.sqrt(np.maximum(0.0, 1 - s2))
    rp = (eta * c - ct) / (eta * c + ct)
    rs = (c - eta * ct) / (c + eta * ct)
    return np.where(s2 >= 1, 1.0, 0.5 * (rp * rp + rs * rs))


def expected_factor(s):
    if s == 0:
        return 0.0
    q = math.sqrt(0.08 * s)
    mu = (np.arange(20000) + 0.5) / 20000
    avg = float(2 * (fresnel(mu, (1 + q) / (1 - q)) * mu).mean())
    return min(1.0, 21 * avg - 20 * 0.08 * s)


failures = []
for mat in gltf["materials"]:
    name = mat["name"]
    if name not in CASES:
        continue
    s, m, t, ior_blender = CASES[name]
    spec = mat.get("extensions", {}).get("KHR_materials_specular", {})
    ior = mat.get("extensions", {}).get("KHR_materials_ior", {}).get("ior", 1.5)
    sf = spec.get("specularFactor", 1.0)
    color = spec.get("specularColorFactor", [1.0, 1.0, 1.0])
    f0 = [sf * min(c * ((ior - 1) / (ior + 1)) ** 2, 1.0) for c in color]
    want_sf = 1.0 if t == 1.0 else expected_factor(s)
    h.log(f"{name}: specularFactor {sf:.4f} (expected {want_sf:.4f}), F0 {f0[0]:.5f} (Cycles {0.08 * s:.5f})")
    if abs(sf - want_sf) > 1e-3:
        failures.append(f"{name}: specularFactor {sf:.4f}, expected {want_sf:.4f}")
    if t == 0.0 and max(abs(v - 0.08 * s) for v in f0) > 1e-6:
        failures.append(f"{name}: F0 {f0}, Cycles' is {0.08 * s}")
h.check(not failures, "; ".join(failures))
for name in CASES:
    bpy.data.objects.remove(bpy.data.objects[name])

# 2. The specular layer alone: a sphere, black Principled (no diffuse in either renderer) at Specular
# a.specular, in a white world (radiance 1): a white furnace, where each pixel is the layer's directional
# albedo. At Specular 0 Cycles' sphere is black; a layer left at specularFactor 1 shows a bright rim.
for mat in list(bpy.data.materials):
    bpy.data.materials.remove(mat)
bpy.ops.mesh.primitive_uv_sphere_add(segments=48, ring_count=24, radius=1.0, location=(0, 0, 0))
sphere = bpy.context.active_object
bpy.ops.object.shade_smooth()
sphere.data.materials.append(principled("sphere", (0, 0, 0), specular=a.specular, rough=a.roughness))
cam = bpy.data.cameras.new("camera")
cam.sensor_fit = "VERTICAL"
cam.angle_y = math.radians(30)
co = bpy.data.objects.new("camera", cam)
sc.collection.objects.link(co)
co.location = (0.0, -5.0, 0.0)
co.rotation_euler = (math.pi / 2, 0.0, 0.0)
sc.camera = co
sc.world = bpy.data.worlds.new("white")
sc.world.use_nodes = True
sc.world.node_tree.nodes["Background"].inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
sc.render.resolution_x, sc.render.resolution_y, sc.render.resolution_percentage = width, height, 100
sc.view_settings.view_transform = "Standard"
h.cycles_settings(8)
out = h.render_halves(a, "sphere", a.spp)
failures, m, r, _ = h.compare_within_noise(a, out, "sphere")
inside = r.mean(axis=2) < 0.999  # the sphere's pixels (the world is 1 in both)
h.log(f"sphere: mean over its pixels: nerfpt {m[inside].mean():.5f}, Cycles {r[inside].mean():.5f}")
for name, px in (("cycles", r), ("nerfpt", m)):
    h.save_png(px, os.path.join(a.work, f"sphere_{name}.png"))
h.log(f"specular: whole test {time.time() - t_start:.0f} s")
h.check(not failures, "; ".join(failures))
h.log("specular: OK")
