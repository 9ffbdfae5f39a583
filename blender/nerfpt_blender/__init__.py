"""nerfpt in Blender: import NeRF captures (nerfpt models, baked OpenVDB grids) as volumes that Cycles and
EEVEE render with nerfpt's emission-absorption semantics, and render scenes with nerfpt (the "nerfpt" render
engine: F12). Needs the nerfpt binary (Edit > Preferences > Add-ons > nerfpt). docs/blender.md in the nerfpt
repository describes it all.
"""

bl_info = {
    "name": "nerfpt",
    "author": "the nerfpt project",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "File > Import > nerfpt model; Render Properties > Render Engine > nerfpt",
    "description": "Import NeRF captures as volumes and render scenes with the nerfpt path tracer",
    "category": "Render",
}


def _modules():
    # Imported here, not at the top: the modules without bpy (nerfpt_cli, child_process, model_file, gltf_post,
    # main_thread) can then be imported, and tested, outside Blender.
    from . import engine, export_scene, import_capture, main_thread, preferences, properties, ui

    return (properties, preferences, import_capture, export_scene, engine, ui, main_thread)


def register():
    for m in _modules():
        m.register()


def unregister():
    for m in reversed(_modules()):
        m.unregister()
