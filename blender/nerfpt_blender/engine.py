"""The "nerfpt" render engine: F12 exports the scene (export_scene), runs `nerfpt render` with the scene's
resolution, samples, max bounces, seed and camera, shows its progress, and loads its EXR into the render result.
Esc stops the child process; the temporary folder (glTF, textures, EXR) is removed in every case.
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

    def _render(self, depsgraph, scene):
        width, height = _image_size(scene)
        binary, _ = preferences.binary()
        settings = scene.nerfpt
        camera = scene.camera
        if camera is None:
            raise NerfptError("the scene has no camera")
        tmp = tempfile.mkdtemp(prefix="nerfpt-render-")
        try:
            gltf = os.path.join(tmp, "scene.gltf")
            exr = os.path.join(tmp, "render.exr")
            self.update_stats("", "nerfpt: exporting the scene")
            # Blender's scene, not the render's copy: the exporter is an operator and reads bpy.data.
            original = bpy.data.scenes[scene.name]
            view_layer = original.view_layers[depsgraph.view_layer.name]
            notes = main_thread.call(
                lambda: export_scene.export(
                    original,
                    view_layer,
                    gltf,
                    resolution=(width, height),
                    absolute_paths=True,
                ),
                should_cancel=self.test_break,
            )
            if notes is None or self._cancelled():
                return
            cmd = [binary, "render", gltf, "-o", exr, "--res", f"{width}x{height}"]
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
            warning = ignored_report(notes, child.warnings(), gltf)
            if warning:
                self.report({"WARNING"}, warning)
            self.update_progress(1.0)
        finally:
            shutil.rmtree(tmp, ignore_errors=True)


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
    for p in _compatible_panels():
        p.COMPAT_ENGINES.add(NerfptRenderEngine.bl_idname)


def unregister():
    for p in _compatible_panels():
        p.COMPAT_ENGINES.discard(NerfptRenderEngine.bl_idname)
    bpy.utils.unregister_class(NerfptRenderEngine)
