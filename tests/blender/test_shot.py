"""A shot made in Blender, rendered by Render Animation with the nerfpt engine, against Cycles frame by frame.

The test room (harness.build_room: Diffuse walls, Lambert in both renderers, an emissive ceiling lamp) with a
cube that slides, rises and turns (keyframes with Blender's default Bezier easing) and a camera that dollies in
and pans (location and rotation keyframes). Render Animation renders frames 1, 13 and 25 (frame step 12) with
each engine and two seeds; frame k of nerfpt against frame k of Cycles must agree within the noise
(harness.compare_within_noise, the statistic of test_render.py: the relMSE excess within 4 standard errors, the
channel means within 4 combined standard errors). The engine must export the scene once for the whole job (with
its animation, sampled at every frame), not once per frame; and the frames must differ (the shot moves).

blender -b --factory-startup --python tests/blender/test_shot.py -- --build BUILD --name shot
    [--res 64x48] [--spp 256]
"""

import math
import os
import sys
import time

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import harness as h  # noqa: E402

a = h.args([("--res", dict(default="64x48")), ("--spp", dict(type=int, default=256))])
t_start = time.time()
width, height = (int(v) for v in a.res.split("x"))
bpy.ops.wm.read_factory_settings(use_empty=True)
h.enable_addon(nerfpt=a.nerfpt)
import nerfpt_blender.engine as engine  # noqa: E402  (the installed add-on's module)

sc = bpy.context.scene
camera = h.build_room(width, height)
h.cycles_settings(4)
sc.render.fps, sc.render.fps_base = 24, 1.0
sc.frame_start, sc.frame_end, sc.frame_step = 1, 25, 12
FRAMES = (1, 13, 25)

# The moving cube: 0.4 m, yellowish Diffuse.
bpy.ops.mesh.primitive_cube_add(size=0.4, location=(-0.5, 0.2, 0.2))
cube = bpy.context.active_object
cube.name = "cube"
cube.data.materials.append(h._material("cube", (0.75, 0.6, 0.2)))
cube.keyframe_insert("location", frame=1)
cube.keyframe_insert("rotation_euler", frame=1)
cube.location = (0.45, -0.1, 0.45)
cube.rotation_euler = (0.3, 0.0, math.radians(70))
cube.keyframe_insert("location", frame=25)
cube.keyframe_insert("rotation_euler", frame=25)
# The camera dollies in and pans to follow it.
camera.keyframe_insert("location", frame=1)
camera.keyframe_insert("rotation_euler", frame=1)
camera.location = (0.3, -2.6, 1.1)
camera.rotation_euler = (math.radians(88), 0.0, math.radians(-8))
camera.keyframe_insert("location", frame=25)
camera.keyframe_insert("rotation_euler", frame=25)
sc.frame_set(1)

s = sc.render.image_settings
s.file_format, s.color_depth, s.color_mode, s.exr_codec = "OPEN_EXR", "32", "RGB", "ZIP"
out = {k: {} for k in FRAMES}  # frame -> {(engine, seed): pixels}
for eng in ("CYCLES", "NERFPT"):
    for seed in (1, 2):
        sc.render.engine = eng
        if eng == "CYCLES":
            sc.cycles.samples, sc.cycles.seed = a.spp // 2, seed
        else:
            sc.nerfpt.samples, sc.nerfpt.seed = a.spp // 2, seed
        sc.render.filepath = os.path.join(a.work, f"{eng.lower()}_{seed}_####")
        exports = engine.export_count
        t = time.time()
        result = bpy.ops.render.render(animation=True)
        h.check(result == {"FINISHED"}, f"Render Animation with {eng} returned {result}")
        h.log(f"{eng} seed {seed}: frames {FRAMES} in {time.time() - t:.1f} s")
        if eng == "NERFPT":
            h.check(engine.export_count == exports + 1,
                    f"the nerfpt engine exported {engine.export_count - exports} times for one Render Animation")
            h.check(not engine._animation, "the job's export was not removed when the job ended")
        for k in FRAMES:
            path = os.path.join(a.work, f"{eng.lower()}_{seed}_{k:04d}.exr")
            h.check(os.path.isfile(path), f"Render Animation with {eng} wrote no {path}")
            out[k][(eng, seed)] = h.read_exr(path)

failures = []
for k in FRAMES:
    f, m, r, _ = h.compare_within_noise(a, out[k], f"frame{k}")
    failures += f
    for name, px in (("cycles", r), ("nerfpt", m)):
        h.save_png(px, os.path.join(a.work, f"frame{k}_{name}.png"))
first, last = out[FRAMES[0]][("NERFPT", 1)], out[FRAMES[-1]][("NERFPT", 1)]
moved = float(abs(first - last).mean())
h.log(f"mean |frame {FRAMES[0]} - frame {FRAMES[-1]}| (nerfpt): {moved:.4f}")
h.check(moved > 0.02, f"nerfpt's frames {FRAMES[0]} and {FRAMES[-1]} barely differ ({moved:.4f}): the shot did not move")
h.log(f"shot: whole test {time.time() - t_start:.0f} s")
h.check(not failures, "; ".join(failures))
h.log("shot: OK")
