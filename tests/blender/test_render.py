"""The same scene rendered by Cycles and by the nerfpt engine agrees within the noise: the test that the
add-on's volume material reproduces nerfpt's emission-absorption semantics in Cycles, and that the export
(camera, materials, lamp, the capture's cube, its density scale) gives nerfpt the scene Blender has.

Scene: a small Cornell room (Diffuse BSDF walls, which both render as Lambert; an emissive lamp; black world)
with the trained sphere model imported at 48 voxels, at half its training size (its grid's density is per local
unit, so the export scales it), standing on the floor, casting a shadow.

Tolerance (the derivation of tests/parity/cornell_reference_test.cpp, with both sides noisy). Each engine renders
two halves with seeds 1 and 2 (a, b: nerfpt; c, d: Cycles); m = (a + b)/2, r = (c + d)/2. Per pixel and channel,
with w = 1/(r^2 + 0.01) (nerfpt compare's weight), E[(m - r)^2] = Var(m) + Var(r) + bias^2, and (a - b)^2/4,
(c - d)^2/4 are unbiased estimates of Var(m), Var(r). So e = (m - r)^2 w - (a - b)^2 w/4 - (c - d)^2 w/4 has
expectation bias^2 w; we require mean(e) <= 4 SE(e) (SE over the pixels). The image means per channel must agree
within 4 combined standard errors. `nerfpt compare m r` must print the relative MSE we compute.
Also rendered, not compared within noise: nerfpt querying the model itself (the default), which differs from
the 48-voxel bake by the bake's resolution; its relative MSE against Cycles is printed and bounded loosely.

blender -b --factory-startup --python tests/blender/test_render.py -- --build BUILD --name render
    [--res 80x60] [--spp 64] [--bake-res 48] [--model-path M.npt] [--placement X,Y,Z,SIZE,YAW] [--step VOXELS]
    [--images DIR]
    The README's images (lego trained 4 min on the CPU: nerfpt train lego -o out/lego.npt --downscale 2 --time 240):
    --model-path out/lego.npt --res 240x180 --spp 128 --bake-res 128 --placement 0,0,0.25,0.7,35 --images docs/images
    (14 min on 2 cores; the images are written before the checks, which lego fails by 0.2%: docs/blender.md, "Limits")
"""

import os
import shutil
import sys
import time

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import harness as h  # noqa: E402

a = h.args(
    [
        ("--res", dict(default="80x60")),
        ("--spp", dict(type=int, default=64, help="per engine, split in two halves")),
        ("--bounces", dict(type=int, default=6)),
        ("--bake-res", dict(type=int, default=48)),
        ("--model-path", dict(default=None, help="another model instead of the trained spheres")),
        ("--images", dict(default=None, help="copy the Cycles and nerfpt PNGs here")),
        ("--placement", dict(default="0,0.1,0.23,0.5,0", help="x,y,z,size,yaw_deg (harness.place_capture)")),
        ("--step", dict(type=float, default=0.25, help="ray-marching step in voxels, Cycles and nerfpt")),
    ]
)
t_start = time.time()
width, height = (int(v) for v in a.res.split("x"))
bpy.ops.wm.read_factory_settings(use_empty=True)
h.enable_addon(nerfpt=a.nerfpt)
model = h.copy_model(a) if not a.model_path else a.model_path
obj = h.import_model(model, resolution=a.bake_res, source="GRID")
h.place_capture(obj, *(float(v) for v in a.placement.split(",")))
h.build_room(width, height)
h.cycles_settings(a.bounces)
bpy.context.scene.cycles.volume_step_rate = a.step
obj.nerfpt_volume.step_voxels = a.step
h.log(f"scene ready: {width}x{height}, capture '{obj.name}' scale {obj.scale[0]:.3f}")

half = a.spp // 2
out = h.render_halves(a, "grid", a.spp)
failures, m, r, noise = h.compare_within_noise(a, out, "grid")
r_path = os.path.join(a.work, "grid_cycles.exr")

# The default: nerfpt queries the network, Cycles shows the bake.
obj.nerfpt_volume.source = "MODEL"
model_path = os.path.join(a.work, "nerfpt_model.exr")
t_model = h.render(model_path, "NERFPT", half, 3)
printed = h.nerfpt(a, "compare", model_path, r_path).stdout
model_rel = float(printed.split()[1])
h.log(
    f"model queried directly, {half} spp: {t_model:.1f} s, relMSE against Cycles {model_rel:.4g} (noise {noise:.4g})"
)
# Not within the noise: the bake's resolution differs. Measured 0.0030 at 80x60 and 32 spp (noise alone ~0.0022
# here, more for a half-spp render); 0.01 catches a model placed, turned or scaled unlike its bake.
if not a.model_path and model_rel > 0.01:
    failures.append(f"the model's render is far from its bake's: relMSE {model_rel:.3g} > 0.01")

for name, px in (("cycles", r), ("nerfpt", h.read_exr(model_path)), ("nerfpt_grid", m)):
    h.save_png(px, os.path.join(a.work, f"blender_{name}.png"))
if a.images:
    os.makedirs(a.images, exist_ok=True)
    for name in ("cycles", "nerfpt"):
        shutil.copyfile(
            os.path.join(a.work, f"blender_{name}.png"), os.path.join(a.images, f"blender_{name}.png")
        )
h.log(f"render: whole test {time.time() - t_start:.0f} s")
h.check(not failures, "; ".join(failures))
h.log("render: OK")
