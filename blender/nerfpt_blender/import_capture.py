"""File > Import > nerfpt model: a capture (.npt, baked with `nerfpt bake`, or a baked .vdb) becomes a Volume
object that Cycles and EEVEE render with nerfpt's semantics, marked so that an export writes the `volume` cube
nerfpt reads (docs/formats.md, "Volumes").

A .npt is placed where its training cameras saw it (model_file.placement), or, when it carries an object frame
(`nerfpt capture`), standing upright on the 3D cursor at its real size, cut to the object's box (the frame's
crop baked, the export's placement 'object'); a .vdb keeps its own coordinates
(the grid's space is the object's local space). The bake runs as a child process: in the UI a modal operator
shows its progress in the status bar (Esc cancels); in background mode it blocks and prints progress lines.
"""

import os
import secrets
import time

import bpy
from mathutils import Matrix
from bpy.props import (
    BoolProperty,
    EnumProperty,
    FloatProperty,
    FloatVectorProperty,
    IntProperty,
    StringProperty,
)
from bpy_extras.io_utils import ImportHelper

from . import child_process, model_file, preferences, volume_material
from .nerfpt_cli import NerfptError


def bake_folder(model_path):
    """Beside the model when that folder is writable, else in Blender's user data folder."""
    folder = os.path.dirname(os.path.abspath(model_path))
    if os.access(folder, os.W_OK):
        return folder
    return bpy.utils.user_resource("DATAFILES", path="nerfpt_bakes", create=True)


def bake_path(model_path, resolution, crop, albedo=False):
    stem = os.path.splitext(os.path.basename(model_path))[0]
    tag = f".{'albedo' if albedo else 'bake'}{resolution}"
    if crop:
        tag += "_crop_" + "_".join(f"{v:g}" for v in (*crop[0], *crop[1])).replace("-", "m")
    return os.path.join(bake_folder(model_path), stem + tag + ".vdb")


def create_capture(
    context, name, grid_path, model_path="", location=(0, 0, 0), scale=(1, 1, 1), settings=None, matrix=None
):
    """A Volume object for grid_path with the nerfpt material and settings; selected and active. The cube is at
    `location` with `scale`, or `matrix` (cube local -> world) when given. settings 'shading' RELIT: the grid
    holds a relightable model's albedo, shaded as a scattering volume."""
    volume = bpy.data.volumes.new(name)
    volume.filepath = grid_path
    if not volume.grids.load():
        msg = volume.grids.error_message or "cannot be read"
        bpy.data.volumes.remove(volume)
        raise NerfptError(f"{grid_path}: {msg}")
    grids = {g.name: g for g in volume.grids}
    density = grids.get("density")
    if density is None or density.data_type != "FLOAT":
        have = ", ".join(f"'{n}'" for n in grids) or "none"
        bpy.data.volumes.remove(volume)
        what = "no float grid 'density'" if density is None else "grid 'density' is not a float grid"
        raise NerfptError(f"{grid_path}: {what} (the file has: {have})")
    color = grids.get("color")
    has_color = color is not None and color.channels == 3
    volume_material.setup_volume_data(volume)
    relit = (settings or {}).get("shading") == "RELIT"
    volume.materials.append(volume_material.volume_material(white=not has_color, relit=relit and has_color))

    obj = bpy.data.objects.new(name, volume)
    context.collection.objects.link(obj)
    # The cube at `location` with `scale`; the object half a voxel off it (volume_material, "Voxel centres").
    h = volume_material.half_voxel(density)
    if matrix is not None:
        obj.matrix_world = matrix @ Matrix.Translation([-v for v in h])
    else:
        obj.location = [location[a] - scale[a] * h[a] for a in range(3)]
        obj.scale = scale
    s = obj.nerfpt_volume
    s.voxel_shift = h
    s.is_capture = True
    s.model_path = model_path
    s.source = "MODEL" if model_path else "GRID"
    for key, value in (settings or {}).items():
        setattr(s, key, value)
    if not model_path:
        # The cube nerfpt clips the field to: the grid's bounds (voxel centres) plus one voxel of trilinear
        # support. A .npt's cube is [-1, 1]^3 by definition (the bake fills exactly that).
        # Object bounds are in the object's space: the cube's local space is that minus h.
        m = density.matrix_object
        pad = [abs(m[r][0]) + abs(m[r][1]) + abs(m[r][2]) for r in range(3)]
        corners = [c[:] for c in obj.bound_box]
        s.cube_min = [min(c[a] for c in corners) - h[a] - pad[a] for a in range(3)]
        s.cube_max = [max(c[a] for c in corners) - h[a] + pad[a] for a in range(3)]

    for o in context.view_layer.objects:
        o.select_set(False)
    obj.select_set(True)
    context.view_layer.objects.active = obj
    return obj, has_color


class ImportJob:
    """One import: checks, the bake command (None for a .vdb), and the object made at the end."""

    # Tests set this to a callable(child) -> bool to cancel a blocking bake mid-way (Esc in the UI).
    test_cancel = None

    def __init__(self, context, op):
        self.filepath = os.path.abspath(bpy.path.abspath(op.filepath))
        self.name = os.path.splitext(os.path.basename(self.filepath))[0]
        self.settings = {"density_scale": op.density_scale, "emission_scale": op.emission_scale}
        self.warnings = []
        if not os.path.isfile(self.filepath):
            raise NerfptError(f"'{self.filepath}': file not found")
        ext = os.path.splitext(self.filepath)[1].lower()
        self.command = None
        if ext == ".vdb":
            self.grid_path = self.filepath
            self.model_path = ""
            self.location, self.scale = (0, 0, 0), (1, 1, 1)
            return
        if ext != ".npt":
            raise NerfptError(f"'{self.filepath}': expected a nerfpt model (.npt) or a baked grid (.vdb)")
        crop = (tuple(op.crop_min), tuple(op.crop_max)) if op.use_crop else None
        self.matrix = None
        try:
            frame = model_file.object_frame(self.filepath) if op.stand_at_cursor and not crop else None
            if frame:
                crop = model_file.object_crop(self.filepath, frame)
            place = model_file.placement(self.filepath, crop)
        except model_file.ModelFileError as e:
            raise NerfptError(str(e)) from None
        self.model_path = self.filepath
        self.location, self.scale = place["centre"], place["half_size"]
        if frame:
            self._stand_on_cursor(context, frame, place)
        try:
            relit = op.shading == "RELIT" and model_file.is_relightable(self.filepath)
        except model_file.ModelFileError as e:
            raise NerfptError(str(e)) from None
        # A relit capture: nerfpt renders the model relit (a grid cannot be); Cycles and EEVEE its albedo.
        self.settings["shading"] = "RELIT" if relit else "EMISSIVE"
        self.settings["source"] = "MODEL" if relit else op.source
        if crop:
            # With an object frame the crop is only the bake's: the export cuts the model to the object's box.
            self.settings.update(use_crop=not frame, crop_min=crop[0], crop_max=crop[1])
        self.grid_path = bake_path(self.filepath, op.resolution, crop, albedo=relit)
        # The bake goes to a temporary name, renamed at the end: a cancelled or failed bake never replaces
        # (or deletes) a grid that another object uses.
        root, _ = os.path.splitext(self.grid_path)
        self.partial_path = f"{root}.partial-{secrets.token_hex(4)}.vdb"
        binary, _ = preferences.binary(context)
        self.command = [binary, "bake", self.filepath, "-o", self.partial_path, "--res", str(op.resolution)]
        self.command += preferences.backend_args(context)
        if crop:
            self.command += ["--crop", ",".join(f"{v:.9g}" for v in (*crop[0], *crop[1]))]
        if relit:
            self.command += ["--colour", "albedo"]

    def _stand_on_cursor(self, context, frame, place):
        """The cube placed so that the object frame's origin (the base centre on its supporting plane) is on the
        3D cursor, its up along +Z, one object unit a metre."""
        cube_to_world = Matrix.Translation(place["centre"]) @ Matrix.Diagonal((*place["half_size"], 1.0))
        object_from_cube = Matrix(frame["object_to_world"]).inverted() @ cube_to_world
        self.matrix = Matrix.Translation(context.scene.cursor.location) @ object_from_cube
        self.settings.update(
            object_placement=True,
            object_from_cube=[v for row in object_from_cube for v in row],
            object_box_min=frame["box"][0],
            object_box_max=frame["box"][1],
        )
        if not frame["metric"]:
            self.warnings.append(
                f"{os.path.basename(self.filepath)}: the capture was not given the object's height "
                "(nerfpt capture --height): one unit of the capture is one metre here"
            )

    def bake_done(self, child):
        """After the child ended: raises NerfptError on failure, removes what a cancel left."""
        if child.cancelled or child.returncode != 0:
            if os.path.exists(self.partial_path):
                os.remove(self.partial_path)
            if child.cancelled:
                return False
            raise NerfptError("nerfpt bake failed: " + child.failure())
        os.replace(self.partial_path, self.grid_path)
        self.warnings += child.warnings()
        return True

    def run_blocking(self):
        """Background mode: the bake with progress lines on stdout. False when cancelled."""
        last = [-1]

        def on_line(child, stream, line):
            if child.progress * 100 >= last[0] + 10 or (stream == "err" and "error" in line):
                last[0] = int(child.progress * 100)
                print(f"nerfpt bake: {last[0]}%", flush=True)

        cancel = ImportJob.test_cancel or (lambda child: False)
        child = child_process.run(self.command, should_cancel=cancel, on_line=on_line)
        self.child = child
        return self.bake_done(child)

    def finish(self, context):
        obj, has_color = create_capture(
            context, self.name, self.grid_path, self.model_path, self.location, self.scale, self.settings,
            getattr(self, "matrix", None),
        )
        if not has_color:
            self.warnings.append(
                f"{os.path.basename(self.grid_path)} has no 'color' grid: rendered white, as nerfpt does"
            )
        return obj


class NERFPT_OT_import_model(bpy.types.Operator, ImportHelper):
    """Import a NeRF capture as a Volume object: a nerfpt model (.npt, baked to a grid for Cycles and EEVEE with
    nerfpt bake) or a baked OpenVDB grid (.vdb)"""

    bl_idname = "import_scene.nerfpt_model"
    bl_label = "Import nerfpt model"
    bl_options = {"REGISTER", "UNDO"}

    filename_ext = ".npt"
    filter_glob: StringProperty(default="*.npt;*.vdb", options={"HIDDEN"})
    resolution: IntProperty(
        name="Bake resolution",
        description="Voxels along the longest side of the model's box in the grid Cycles and EEVEE render "
        "(nerfpt bake --res); nerfpt itself renders the model at full detail",
        default=128,
        min=8,
        max=1024,
    )
    source: EnumProperty(
        name="nerfpt renders",
        items=[
            ("MODEL", "Model (.npt)", "nerfpt queries the network directly (view-dependent colour)"),
            ("GRID", "Baked grid (.vdb)", "nerfpt renders the grid Cycles and EEVEE show"),
        ],
        default="MODEL",
    )
    shading: EnumProperty(
        name="Shading",
        description="For a relightable model (nerfpt train --relightable; others are always emissive)",
        items=[
            (
                "RELIT",
                "Relit",
                "Lit by the scene's lights: nerfpt shades the model with its intrinsic BSDF; Cycles and EEVEE "
                "scatter light with its albedo, baked (nerfpt bake --colour albedo)",
            ),
            ("EMISSIVE", "Emissive", "The capture's own light, baked in (as a model that is not relightable)"),
        ],
        default="RELIT",
    )
    density_scale: FloatProperty(name="Density scale", default=1.0, min=0.0, soft_max=10.0)
    emission_scale: FloatProperty(name="Emission scale", default=1.0, min=0.0, soft_max=10.0)
    stand_at_cursor: BoolProperty(
        name="Stand at the 3D cursor",
        description="A capture that knows its object (nerfpt capture: supporting plane, up, box) stands upright "
        "on the 3D cursor at its real size, cut to the object's box; off: placed where its cameras saw it",
        default=True,
    )
    use_crop: BoolProperty(
        name="Crop",
        description="Import only a box of the model (model space, e.g. the object without its room; "
        "`nerfpt info MODEL` says where the content lies)",
        default=False,
    )
    crop_min: FloatVectorProperty(name="Min", size=3, default=(0.0, 0.0, 0.0))
    crop_max: FloatVectorProperty(name="Max", size=3, default=(1.0, 1.0, 1.0))

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        layout.prop(self, "resolution")
        layout.prop(self, "shading")
        row = layout.row()
        row.enabled = self.shading != "RELIT"
        row.prop(self, "source")
        layout.prop(self, "density_scale")
        layout.prop(self, "emission_scale")
        layout.prop(self, "stand_at_cursor")
        layout.prop(self, "use_crop")
        col = layout.column()
        col.enabled = self.use_crop
        col.prop(self, "crop_min")
        col.prop(self, "crop_max")

    def _report_done(self, job, obj):
        for w in job.warnings:
            self.report({"WARNING"}, w)
        self.report({"INFO"}, f"imported '{obj.name}' from {os.path.basename(job.filepath)}")

    def execute(self, context):
        try:
            job = ImportJob(context, self)
            if job.command is not None:
                if bpy.app.background or context.window is None:
                    if not job.run_blocking():
                        self.report({"WARNING"}, "import cancelled")
                        return {"CANCELLED"}
                else:
                    return self._start_modal(context, job)
            obj = job.finish(context)
        except NerfptError as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        self._report_done(job, obj)
        return {"FINISHED"}

    # The bake in the UI: a timer polls the child, the status bar shows its progress, Esc cancels.
    def _start_modal(self, context, job):
        self._job = job
        self._child = child_process.ChildProcess(job.command)
        self._started = time.time()
        wm = context.window_manager
        self._timer = wm.event_timer_add(0.1, window=context.window)
        wm.progress_begin(0, 100)
        wm.modal_handler_add(self)
        self._status(context, "starting")
        return {"RUNNING_MODAL"}

    def _status(self, context, text):
        context.workspace.status_text_set(f"nerfpt bake of {self._job.name}: {text} (Esc to cancel)")

    def _cleanup(self, context):
        wm = context.window_manager
        wm.event_timer_remove(self._timer)
        wm.progress_end()
        context.workspace.status_text_set(None)

    def modal(self, context, event):
        if event.type == "ESC":
            self._child.cancel()
            self._job.bake_done(self._child)
            self._cleanup(context)
            self.report({"WARNING"}, "import cancelled: the bake was stopped")
            return {"CANCELLED"}
        if event.type != "TIMER":
            return {"PASS_THROUGH"}
        self._child.poll()
        pct = int(self._child.progress * 100)
        context.window_manager.progress_update(pct)
        self._status(context, f"{pct}%, {time.time() - self._started:.0f} s")
        if self._child.running():
            return {"PASS_THROUGH"}
        self._child.finish()
        self._cleanup(context)
        try:
            self._job.bake_done(self._child)
            obj = self._job.finish(context)
        except NerfptError as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        self._report_done(self._job, obj)
        return {"FINISHED"}

    def cancel(self, context):
        # Blender ends the modal operator (a file is loaded, the window closes): stop the child too.
        self._child.cancel()
        self._job.bake_done(self._child)
        self._cleanup(context)


def menu_import(self, context):
    self.layout.operator(NERFPT_OT_import_model.bl_idname, text="nerfpt model (.npt, .vdb)")


def register():
    bpy.utils.register_class(NERFPT_OT_import_model)
    bpy.types.TOPBAR_MT_file_import.append(menu_import)


def unregister():
    bpy.types.TOPBAR_MT_file_import.remove(menu_import)
    bpy.utils.unregister_class(NERFPT_OT_import_model)
