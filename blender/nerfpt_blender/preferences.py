"""Add-on preferences: where the nerfpt binary is (checked with `nerfpt --version`) and which backend bakes."""

import os

import bpy
from bpy.props import EnumProperty, StringProperty

from . import build_dirs, nerfpt_cli

_checked = {}  # (path, mtime, size) -> version: `--version` runs once per binary, not on every redraw


def preferences(context=None):
    context = context or bpy.context
    addon = context.preferences.addons.get(__package__)
    return addon.preferences if addon else None


def binary(context=None):
    """(path, version) of a usable nerfpt; raises nerfpt_cli.NerfptError with a message for the user."""
    prefs = preferences(context)
    configured = prefs.nerfpt_path if prefs else ""
    path = nerfpt_cli.find_binary(bpy.path.abspath(configured) if configured else "", build_dirs.BUILD_DIRS)
    st = os.stat(path)
    key = (path, st.st_mtime_ns, st.st_size)
    if key not in _checked:
        _checked[key] = nerfpt_cli.check_version(path)
    return path, _checked[key]


def backend_args(context=None):
    prefs = preferences(context)
    choice = prefs.backend if prefs else "AUTO"
    return [] if choice == "AUTO" else ["--backend", choice.lower()]


def status_line(context=None):
    """One line for the UI: the binary and its version, or why there is none."""
    try:
        path, version = binary(context)
        return True, f"nerfpt {nerfpt_cli.version_text(version)}: {path}"
    except nerfpt_cli.NerfptError as e:
        return False, str(e)


class NERFPT_OT_check_binary(bpy.types.Operator):
    """Run `nerfpt --version` with the configured binary and report the result"""

    bl_idname = "nerfpt.check_binary"
    bl_label = "Check nerfpt"

    def execute(self, context):
        _checked.clear()
        ok, line = status_line(context)
        self.report({"INFO"} if ok else {"ERROR"}, line)
        return {"FINISHED"} if ok else {"CANCELLED"}


class NerfptPreferences(bpy.types.AddonPreferences):
    bl_idname = __package__

    nerfpt_path: StringProperty(
        name="nerfpt binary",
        subtype="FILE_PATH",
        description="The nerfpt executable; empty: found on PATH, else in the build folder the add-on was "
        "packaged from",
        default="",
    )
    backend: EnumProperty(
        name="Bake on",
        description="Where `nerfpt bake` evaluates the network (--backend)",
        items=[
            ("AUTO", "Automatic", "The GPU when this nerfpt has CUDA and a GPU is present, else the CPU"),
            ("CPU", "CPU", "All CPU cores"),
            ("CUDA", "GPU (CUDA)", "An NVIDIA GPU; an error when none is usable"),
        ],
        default="AUTO",
    )

    def draw(self, context):
        layout = self.layout
        layout.prop(self, "nerfpt_path")
        layout.prop(self, "backend")
        ok, line = status_line(context)
        row = layout.row()
        row.label(text=line, icon="CHECKMARK" if ok else "ERROR")
        row.operator(NERFPT_OT_check_binary.bl_idname, text="Check")


classes = (NERFPT_OT_check_binary, NerfptPreferences)


def register():
    for c in classes:
        bpy.utils.register_class(c)


def unregister():
    for c in reversed(classes):
        bpy.utils.unregister_class(c)
