"""Panels: the nerfpt engine's settings in Render Properties, a capture's settings in Object Data Properties."""

import bpy

from . import preferences


class RENDER_PT_nerfpt(bpy.types.Panel):
    bl_label = "nerfpt"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "render"
    COMPAT_ENGINES = {"NERFPT"}

    @classmethod
    def poll(cls, context):
        return context.engine in cls.COMPAT_ENGINES

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        s = context.scene.nerfpt
        layout.prop(s, "samples")
        layout.prop(s, "max_bounces")
        layout.prop(s, "seed")
        ok, line = preferences.status_line(context)
        layout.label(text=line, icon="CHECKMARK" if ok else "ERROR")


class DATA_PT_nerfpt_capture(bpy.types.Panel):
    bl_label = "nerfpt capture"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "data"

    @classmethod
    def poll(cls, context):
        obj = context.object
        return obj is not None and obj.type == "VOLUME" and obj.nerfpt_volume.is_capture

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        s = context.object.nerfpt_volume
        if s.model_path:
            layout.prop(s, "model_path")
            row = layout.row()
            row.enabled = False  # chosen at import: the grid holds the albedo or the radiance
            row.prop(s, "shading")
            row = layout.row()
            row.enabled = s.shading != "RELIT"  # a grid cannot be relit: nerfpt renders the model
            row.prop(s, "source")
        layout.prop(s, "density_scale")
        row = layout.row()
        row.enabled = s.shading != "RELIT"  # a relit capture emits nothing
        row.prop(s, "emission_scale")
        row = layout.row()
        row.enabled = not s.model_path  # a model's density is always per local (model) unit
        row.prop(s, "local_density")
        layout.prop(s, "casts_shadows")
        layout.prop(s, "step_voxels")
        if s.object_placement:
            layout.label(text="Object frame: stands where this object is, cut to its box")
        if s.use_crop:
            col = layout.column()
            col.enabled = False
            col.prop(s, "crop_min")
            col.prop(s, "crop_max")


classes = (RENDER_PT_nerfpt, DATA_PT_nerfpt_capture)


def register():
    for c in classes:
        bpy.utils.register_class(c)


def unregister():
    for c in reversed(classes):
        bpy.utils.unregister_class(c)
