"""Cancelling a nerfpt render (F12, then Esc) and a bake (the import's progress, then Esc) mid-way stops the
child process at once and leaves nothing behind: no nerfpt process, no temporary folder or file, no image.

Esc reaches the add-on as RenderEngine.test_break() (render) and an ESC event (the import's modal operator),
which a background script cannot produce; the add-on's test hooks (NerfptRenderEngine.test_cancel,
ImportJob.test_cancel) are polled at the same place and take the same path.

blender -b --factory-startup --python tests/blender/test_cancel.py -- --build BUILD --name cancel
"""

import glob
import os
import sys
import tempfile
import time

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import harness as h  # noqa: E402

a = h.args()
bpy.ops.wm.read_factory_settings(use_empty=True)
h.enable_addon(nerfpt=a.nerfpt)
from nerfpt_blender import child_process, engine, import_capture  # noqa: E402

tmp = os.path.join(a.work, "tmp")
os.makedirs(tmp)
tempfile.tempdir = tmp  # where the engine makes its temporary folder
model = h.copy_model(a)


def children_of_blender():
    """Processes whose parent is this Blender (nerfpt renders and bakes are its direct children)."""
    found = []
    for stat in glob.glob("/proc/[0-9]*/stat"):
        try:
            with open(stat) as f:
                fields = f.read().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[1]) == os.getpid() and fields[0] != "Z":
            found.append(stat.split("/")[2])
    return found


class Canceller:
    """Cancels once the child has run `after` seconds; remembers the child."""

    def __init__(self, after):
        self.after, self.child, self.t0, self.at = after, None, None, None

    def __call__(self, child):
        if self.child is None:
            self.child, self.t0 = child, time.time()
        h.check(child_process.process_exists(child.pid), "the child is not running while polled")
        if time.time() - self.t0 >= self.after:
            self.at = time.time()
            return True
        return False


# A bake that would take long: cancelled after 1 s.
cancel = Canceller(1.0)
import_capture.ImportJob.test_cancel = cancel
result = bpy.ops.import_scene.nerfpt_model(filepath=model, resolution=700)
import_capture.ImportJob.test_cancel = None
h.check(result == {"CANCELLED"}, f"the cancelled import returned {result}")
h.check(
    cancel.child is not None and cancel.child.cancelled,
    "the bake was not cancelled (it finished within 1 s?)",
)
h.log(f"bake cancelled; it ended {time.time() - cancel.at:.2f} s after the cancel")
h.check(not child_process.process_exists(cancel.child.pid), "the nerfpt bake process is still there")
left = sorted(os.listdir(a.work))
h.check(left == ["spheres.npt", "tmp"], f"the cancelled bake left {left}")
h.check(not any(o.type == "VOLUME" for o in bpy.data.objects), "a cancelled import made an object")

# A render that would take long: cancelled after 1.5 s of nerfpt.
obj = h.import_model(model, resolution=24)
h.place_capture(obj)
h.build_room(64, 48)
sc = bpy.context.scene
sc.render.engine = "NERFPT"
sc.nerfpt.samples = 1 << 16
cancel = Canceller(1.5)
engine.NerfptRenderEngine.test_cancel = cancel
t0 = time.time()
bpy.ops.render.render(write_still=False)
engine.NerfptRenderEngine.test_cancel = None
h.check(cancel.child is not None and cancel.child.cancelled, "the render was not cancelled")
h.log(
    f"render cancelled after {cancel.at - t0:.1f} s; render() returned {time.time() - cancel.at:.2f} s later"
)
h.check(time.time() - cancel.at < 5.0, "the render did not stop within 5 s of the cancel")
h.check(not child_process.process_exists(cancel.child.pid), "the nerfpt render process is still there")
h.check(children_of_blender() == [], f"child processes left: {children_of_blender()}")
h.check(os.listdir(tmp) == [], f"the render left {os.listdir(tmp)} in the temporary folder")
h.log("cancel: OK")
