"""Blender area lights through the export agree with Cycles within the noise: a diffuse floor (Diffuse BSDF,
Lambert in both) lit by a rectangle (tilted, turned, scaled unevenly along its x) and a tilted disc area light
(coloured, black world), rendered by Cycles and by the nerfpt engine (the add-on's one-sided emissive polygons
facing the light's -Z, radiance P / (4 A)). The statistic is test_render.py's (harness.compare_within_noise:
the relMSE excess within 4 standard errors, the channel means within 4 combined standard errors; at the
default 256 spp the mean limits are about 0.5-0.7%). A wrong convention (P / (pi A): +27%), a light facing the
wrong way (black), the scale left out of the area (-33% on the rectangle) or a disc's area taken as its
bounding square fail by far more; so did nerfpt before its shadow rays were aimed from their offset origin
(a tilted light's grazing emission was lost: the means -0.9%, the excess 58 standard errors at 1024 spp).
Measured at 1024 spp: means within 0.13% (limits 0.17%), excess 7e-7 +- 1.4e-6.

The lights are above the camera's view: Cycles does not show lights to the camera (Object > Visibility >
Camera is off for lights), nerfpt's emitters are surfaces; the export must not warn about anything.

blender -b --factory-startup --python tests/blender/test_area_lights.py -- --build BUILD --name area_lights
    [--res 80x60] [--spp 256]
"""

import math
import os
import sys
import time

import bpy
from mathutils import Euler

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import harness as h  # noqa: E402

a = h.args([("--res", dict(default="80x60")), ("--spp", dict(type=int, default=256))])
t_start = time.time()
width, height = (int(v) for v in a.res.split("x"))
bpy.ops.wm.read_factory_settings(use_empty=True)
h.enable_addon(nerfpt=a.nerfpt)
sc = bpy.context.scene
floor = h._material("floor", (0.8, 0.8, 0.8))
h._quad("floor", [(-3, -3, 0), (3, -3, 0), (3, 3, 0), (-3, 3, 0)], floor)


def area_light(name, shape, size, power, color, location, rotation_deg, scale=(1, 1, 1), size_y=None):
    light = bpy.data.lights.new(name, "AREA")
    light.shape, light.size, light.energy, light.color = shape, size, power, color
    if size_y is not None:
        light.size_y = size_y
    obj = bpy.data.objects.new(name, light)
    obj.location, obj.scale = location, scale
    obj.rotation_euler = Euler([math.radians(d) for d in rotation_deg])
    sc.collection.objects.link(obj)
    return obj


# The rectangle tilted, turned and scaled unevenly (Cycles divides by the scaled area), the disc tilted 30
# degrees: floor points near their planes see them at grazing angles (88 degrees from the normal at the image's
# bottom), where nerfpt's shadow rays used to stop on the emitter itself (docs/blender.md). Placed so that
# neither card hides the other from the visible floor (the line through both meets the floor at x = 3.6):
# nerfpt's emitters are surfaces, Cycles' lights are not.
area_light("softbox", "RECTANGLE", 1.2, 80.0, (1.0, 0.8, 0.6), (-0.9, 0.3, 1.2), (20, 0, 25), (1.5, 1, 1), 0.4)
area_light("disc", "DISK", 0.6, 30.0, (0.6, 0.8, 1.0), (0.9, 0.9, 0.8), (0, -30, 0))
cam = bpy.data.cameras.new("camera")
cam.sensor_fit = "VERTICAL"
cam.angle_y = math.radians(35)
co = bpy.data.objects.new("camera", cam)
sc.collection.objects.link(co)
co.location = (0.0, -3.0, 0.6)
co.rotation_euler = Euler((math.radians(90 - 28), 0.0, 0.0))  # 28 degrees down: the lights are above the view
sc.camera = co
sc.world = bpy.data.worlds.new("black")
sc.world.use_nodes = True
sc.world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)
sc.render.resolution_x, sc.render.resolution_y, sc.render.resolution_percentage = width, height, 100
sc.view_settings.view_transform = "Standard"
h.cycles_settings(1)

# The export: two one-sided emitters, no warning.
gltf_path = os.path.join(a.work, "scene.gltf")
result, printed = h.console(lambda: bpy.ops.export_scene.nerfpt_gltf(filepath=gltf_path))
h.check(result == {"FINISHED"}, f"export returned {result}")
h.check("nerfpt ignores" not in printed, f"the export warned: {printed}")
info = h.nerfpt(a, "info", gltf_path).stdout
h.log("nerfpt info scene.gltf:\n" + info.rstrip())

out = h.render_halves(a, "area", a.spp)
failures, m, r, _ = h.compare_within_noise(a, out, "area")
for name, px in (("cycles", r), ("nerfpt", m)):
    h.save_png(px, os.path.join(a.work, f"area_{name}.png"))
h.log(f"area lights: whole test {time.time() - t_start:.0f} s")
h.check(not failures, "; ".join(failures))
h.log("area lights: OK")
