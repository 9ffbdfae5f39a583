"""Installs the add-on from its zip as a user does (Preferences > Add-ons > Install), enables it and checks the
nerfpt binary preference: found without configuration (the build folder the zip names), its version checked
with `nerfpt --version`, and a clear one-line message when it is missing, broken or too old.

blender -b --factory-startup --python tests/blender/test_install.py -- --build BUILD --name install
(BLENDER_USER_SCRIPTS must point at the folder the add-on is installed into; ctest sets it.)
"""

import os
import shutil
import stat
import sys

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import harness as h  # noqa: E402

a = h.args()
scripts = os.environ.get("BLENDER_USER_SCRIPTS", "")
h.check(scripts and a.build in os.path.abspath(scripts), "BLENDER_USER_SCRIPTS must lie in the build folder")
h.check(os.path.isfile(a.zip), f"no add-on zip at {a.zip} (the blender.package fixture makes it)")

shutil.rmtree(os.path.join(scripts, "addons", "nerfpt_blender"), ignore_errors=True)  # a clean install
result = bpy.ops.preferences.addon_install(filepath=a.zip, overwrite=True)
h.check(result == {"FINISHED"}, f"addon_install returned {result}")
h.check(os.path.isfile(os.path.join(scripts, "addons", "nerfpt_blender", "__init__.py")), "not installed")
h.enable_addon(nerfpt="")  # no configured path: PATH, then the build folder
import nerfpt_blender  # noqa: E402
from nerfpt_blender import nerfpt_cli, preferences  # noqa: E402

h.check(
    os.path.dirname(nerfpt_blender.__file__).startswith(scripts), "the add-on did not load from the install"
)
h.check("NERFPT" in {e.bl_idname for e in bpy.types.RenderEngine.__subclasses__()}, "no nerfpt render engine")
h.check(hasattr(bpy.ops.import_scene, "nerfpt_model"), "no import operator")
h.check(hasattr(bpy.ops.export_scene, "nerfpt_gltf"), "no export operator")

ok, line = preferences.status_line()
h.log(f"binary without configuration: {line}")
h.check(ok, line)
path, version = preferences.binary()
# On PATH first, else the build folder that package_blender_addon.sh wrote into the zip.
h.check(path == shutil.which("nerfpt") or os.path.samefile(path, a.nerfpt), f"found {path}")
h.check(version >= nerfpt_cli.MIN_VERSION, f"version {version}")


def expect_error(configured, *fragments):
    prefs = bpy.context.preferences.addons["nerfpt_blender"].preferences
    prefs.nerfpt_path = configured
    preferences._checked.clear()
    ok, line = preferences.status_line()
    h.log(f"binary '{configured}': {line}")
    h.check(not ok, f"'{configured}' was accepted")
    h.check("\n" not in line and "Traceback" not in line, f"not one line: {line!r}")
    for f in fragments:
        h.check(f in line, f"'{f}' not in: {line}")
    try:  # the Check button: an ERROR report, which a script sees as RuntimeError
        bpy.ops.nerfpt.check_binary()
        raise AssertionError("check_binary accepted it")
    except RuntimeError as e:
        h.check(str(e).strip() == "Error: " + line, f"check_binary said {e}")


def fake(name, body):
    p = os.path.join(a.work, name)
    with open(p, "w") as f:
        f.write("#!/bin/sh\n" + body + "\n")
    os.chmod(p, os.stat(p).st_mode | stat.S_IXUSR)
    return p


expect_error(os.path.join(a.work, "missing", "nerfpt"), "does not exist", "Preferences")
expect_error(
    fake("old", "echo 'nerfpt 0.0.9'"), "0.0.9", "too old", nerfpt_cli.version_text(nerfpt_cli.MIN_VERSION)
)
expect_error(fake("other", "echo 'something else 1.0'"), "not a nerfpt binary")
expect_error(
    fake("broken", "echo 'nerfpt: error: cannot start' >&2; exit 1"), "not a nerfpt binary", "exit code 1"
)
not_exec = os.path.join(a.work, "not_exec")
open(not_exec, "w").close()
expect_error(not_exec, "not an executable")

prefs = bpy.context.preferences.addons["nerfpt_blender"].preferences
prefs.nerfpt_path = a.nerfpt
preferences._checked.clear()
h.check(bpy.ops.nerfpt.check_binary() == {"FINISHED"}, "check_binary failed on the real binary")
h.log("install: OK")
