"""The "nerfpt" render engine: F12 exports the scene (export_scene), runs `nerfpt render` with the scene's
resolution, samples, max bounces, seed and camera, shows its progress, and loads its EXR into the render result.
Esc stops the child process; the temporary folder (glTF, textures, EXR) is removed in every case.

Render Animation calls the engine once per frame. The scene is exported once for the whole job, with its
animation (export_scene.export(animation=True)), at the job's first frame; each frame then runs
`nerfpt render --frames F` on that file, so nerfpt poses the scene itself (frame F at F / fps seconds, the
seed derived from the seed and F). The export lives until the job ends (render_complete / render_cancel).
"""

import os
import shutil
import tempfile
import traceback

import bpy

from . import child_process, export_scene, main_thread, preferences
from .nerfpt_cli import NerfptError, ignored_report


def _threads(scene):
    r = scene.render
    return r.threads if r.threads_mode == "FIXED" else 0


def _image_size(scene):
    r = scene.render
    return max(1, r.resolution_x * r.resolution_percentage // 100), max(
        1, r.resolution_y * r.resolution_percentage // 100
    )


# The running Render Animation job's export: {"key", "tmp", "gltf", "notes"}; empty between jobs.
_animation = {}
# Exports made (tests count them: one per Render Animation job).
export_count = 0


def _drop_animation_export(*_args):
    if _animation.get("tmp"):
        shutil.rmtree(_animation["tmp"], ignore_errors=True)
    _animation.clear()


def _animation_key(scene, view_layer_name, width, height):
    """What the export depends on beyond the scene's contents (which a job does not change)."""
    r = scene.render
    return (scene.name, view_layer_name, scene.frame_start, scene.frame_end, r.fps, width, height)


class NerfptRenderEngine(bpy.types.RenderEngine):
    bl_idname = "NERFPT"
    bl_label = "nerfpt"
    bl_use_preview = False
    bl_use_postprocess = True
    bl_use_eevee_viewport = True  # the viewport's Material Preview and Rendered modes use EEVEE
    bl_use_shading_nodes_custom = False

    # Tests set this to a callable(child) -> bool to cancel mid-way as Esc does (test_break cannot be set from
    # a script in background mode).
    test_cancel = None

    def render(self, depsgraph):
        scene = depsgraph.scene
        try:
            self._render(depsgraph, scene)
        except NerfptError as e:
            self._fail(str(e))
        except Exception as e:  # a bug in the add-on: still one line in Blender, the details on the console
            traceback.print_exc()
            self._fail(f"nerfpt add-on: unexpected {type(e).__name__}: {e}")

    def _fail(self, message):
        self.report({"ERROR"}, message)
        self.error_set(message)

    def _cancelled(self, child=None):
        if self.test_break():
            return True
        hook = NerfptRenderEngine.test_cancel
        return bool(hook and child is not None and hook(child))

    def _export(self, depsgraph, scene, gltf, width, height, animation):
        """The scene to `gltf` on Blender's main thread; its notes, or None when cancelled."""
        global export_count
        self.update_stats("", "nerfpt: exporting the scene" + (" and its animation" if animation else ""))
        # Blender's scene, not the render's copy: the exporter is an operator and reads bpy.data.
        original = bpy.data.scenes[scene.name]
        view_layer = original.view_layers[depsgraph.view_layer.name]
        export_count += 1
        return main_thread.call(
            lambda: export_scene.export(
                original,
                view_layer,
                gltf,
                resolution=(width, height),
                absolute_paths=True,
                animation=animation,
            ),
            should_cancel=self.test_break,
        )

    def _render(self, depsgraph, scene):
        width, height = _image_size(scene)
        binary, _ = preferences.binary()
        settings = scene.nerfpt
        camera = scene.camera
        if camera is None:
            raise NerfptError("the scene has no camera")
        tmp = tempfile.mkdtemp(prefix="nerfpt-render-")
        try:
            exr = os.path.join(tmp, "render.exr")
            animation = self.is_animation
            key = _animation_key(scene, depsgraph.view_layer.name, width, height)
            if animation and _animation.get("key") == key:
                gltf, notes = _animation["gltf"], _animation["notes"]  # this job's export
            else:
                if animation:
                    _drop_animation_export()
                    export_dir = tempfile.mkdtemp(prefix="nerfpt-animation-")
                    _animation.update(tmp=export_dir, gltf=os.path.join(export_dir, "scene.gltf"))
                    gltf = _animation["gltf"]
                else:
                    gltf = os.path.join(tmp, "scene.gltf")
                notes = self._export(depsgraph, scene, gltf, width, height, animation)
                if notes is None or self._cancelled():
                    _drop_animation_export()
                    return
                if animation:
                    _animation.update(key=key, notes=notes)  # the job's other frames use it
            cmd = [binary, "render", gltf, "-o", exr, "--res", f"{width}x{height}"]
            if animation and scene.frame_current < 0:
                raise NerfptError(f"frame {scene.frame_current}: nerfpt renders frames 0 and later")
            if animation:
                # nerfpt's sequence of one frame: it poses the scene at F / fps and seeds the frame by F.
                exr = os.path.join(tmp, "frame.#######.exr")
                cmd = [binary, "render", gltf, "-o", exr, "--res", f"{width}x{height}"]
                cmd += ["--frames", str(scene.frame_current), "--fps", repr(float(scene.render.fps)), "--overwrite"]
                cmd += ["--animation", export_scene.ANIMATION_NAME] if _has_animation(gltf) else []
                exr = os.path.join(tmp, f"frame.{scene.frame_current:07d}.exr")
            cmd += ["--spp", str(settings.samples), "--max-depth", str(export_scene.max_depth(scene))]
            cmd += ["--seed", str(settings.seed), "--camera", camera.name, "--threads", str(_threads(scene))]

            def on_line(child, stream, line):
                if stream == "err" and child.progress is not None:
                    self.update_progress(child.progress)
                    self.update_stats(
                        "",
                        f"nerfpt: rendering {width}x{height}, {settings.samples} spp: {int(child.progress * 100)}%",
                    )

            self.update_stats("", "nerfpt: starting")
            child = child_process.run(cmd, should_cancel=self._cancelled, on_line=on_line)
            if child.cancelled:
                return
            if child.returncode != 0:
                # The temporary glTF's path means nothing to the user: it is "the scene".
                raise NerfptError("nerfpt render failed: " + child.failure().replace(gltf + ": ", "scene: "))
            if not os.path.isfile(exr):
                raise NerfptError(f"nerfpt render wrote no image ({exr})")
            result = self.begin_result(0, 0, width, height)
            try:
                result.layers[0].load_from_file(exr)
            finally:
                self.end_result(result)
            child_warnings = [w for w in child.warnings() if "the scene has no animation" not in w]
            warning = ignored_report(notes, child_warnings, gltf)
            if warning:
                self.report({"WARNING"}, warning)
            self.update_progress(1.0)
        finally:
            shutil.rmtree(tmp, ignore_errors=True)


def _has_animation(gltf):
    import json

    with open(gltf) as f:
        return any(a.get("name") == export_scene.ANIMATION_NAME for a in json.load(f).get("animations", []))


def _compatible_panels():
    """Blender's own panels that work with any engine (output, material, light, world): those that list the
    internal 'BLENDER_RENDER' engine, as Blender's RenderEngine template does."""
    hidden = {"VIEWLAYER_PT_filter", "VIEWLAYER_PT_layer_passes"}
    return [
        p
        for p in bpy.types.Panel.__subclasses__()
        if "BLENDER_RENDER" in getattr(p, "COMPAT_ENGINES", ()) and p.__name__ not in hidden
    ]


def register():
    bpy.utils.register_class(NerfptRenderEngine)
    for handlers in (bpy.app.handlers.render_init, bpy.app.handlers.render_complete, bpy.app.handlers.render_cancel):
        if _drop_animation_export not in handlers:
            handlers.append(_drop_animation_export)
    for p in _compatible_panels():
        p.COMPAT_ENGINES.add(NerfptRenderEngine.bl_idname)


def unregister():
    _drop_animation_export()
    for handlers in (bpy.app.handlers.render_init, bpy.app.handlers.render_complete, bpy.app.handlers.render_cancel):
        if _drop_animation_export in handlers:
            handlers.remove(_drop_animation_export)
    for p in _compatible_panels():
        p.COMPAT_ENGINES.discard(NerfptRenderEngine.bl_idname)
    bpy.utils.unregister_class(NerfptRenderEngine)
