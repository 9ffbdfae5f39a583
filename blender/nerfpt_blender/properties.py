"""The add-on's settings stored in .blend files: per capture object (Object.nerfpt_volume) and per scene
(Scene.nerfpt, the render settings of the nerfpt engine)."""

import bpy
from bpy.props import (
    BoolProperty,
    EnumProperty,
    FloatProperty,
    FloatVectorProperty,
    IntProperty,
    StringProperty,
)


def _sync_shadows(self, context):
    # Cycles' per-object shadow visibility follows the setting nerfpt reads from the extras.
    obj = self.id_data
    if hasattr(obj, "visible_shadow"):
        obj.visible_shadow = self.casts_shadows


def _redraw(self, context):
    # The material reads these values through Attribute (Object) nodes; a tag makes the viewport update.
    obj = self.id_data
    obj.update_tag()


class NerfptVolumeSettings(bpy.types.PropertyGroup):
    """A capture imported by File > Import > nerfpt model: a Volume object holding the baked grid that Cycles
    and EEVEE render, marked so that an export writes the `volume` cube nerfpt reads (docs/formats.md)."""

    is_capture: BoolProperty(
        name="nerfpt capture",
        description="Exported as a nerfpt `volume` cube (set by File > Import > nerfpt model)",
        default=False,
    )
    model_path: StringProperty(
        name="Model",
        subtype="FILE_PATH",
        description="The nerfpt model (.npt) the grid was baked from; empty for an imported .vdb",
    )
    source: EnumProperty(
        name="nerfpt renders",
        items=[
            (
                "MODEL",
                "Model (.npt)",
                "nerfpt queries the network directly: full detail and view-dependent colour (Cycles and EEVEE "
                "show the baked grid)",
            ),
            ("GRID", "Baked grid (.vdb)", "nerfpt renders the same grid as Cycles and EEVEE"),
        ],
        default="MODEL",
    )
    shading: EnumProperty(
        name="Shading",
        items=[
            (
                "EMISSIVE",
                "Emissive",
                "The capture's own light, baked in: an emission-absorption volume (nerfpt's \"emissive\")",
            ),
            (
                "RELIT",
                "Relit",
                "A relightable model lit by the scene's lights: nerfpt shades it with its intrinsic BSDF; "
                "Cycles and EEVEE scatter light with its baked albedo (chosen at import)",
            ),
        ],
        default="EMISSIVE",
    )
    density_scale: FloatProperty(
        name="Density scale",
        description="Multiplies the density (absorption coefficient); nerfpt's extras.volume.density_scale",
        default=1.0,
        min=0.0,
        soft_max=10.0,
        update=_redraw,
    )
    emission_scale: FloatProperty(
        name="Emission scale",
        description="Multiplies the colour (radiance); nerfpt's extras.volume.emission_scale",
        default=1.0,
        min=0.0,
        soft_max=10.0,
        update=_redraw,
    )
    local_density: BoolProperty(
        name="Density per local unit",
        description="The grid's density is per unit of the object's local space, so scaling the object keeps "
        "its opacity (nerfpt bakes and models); off: per world unit, as nerfpt reads other OpenVDB files",
        default=True,
        update=_redraw,
    )
    casts_shadows: BoolProperty(
        name="Casts shadows",
        description="Shadow rays are attenuated by the volume (Cycles: the object's shadow visibility)",
        default=True,
        update=_sync_shadows,
    )
    step_voxels: FloatProperty(
        name="Step (voxels)",
        description="nerfpt's ray-marching step as a fraction of a voxel (extras.volume.step_voxels)",
        default=0.25,
        min=0.01,
        max=4.0,
    )
    use_crop: BoolProperty(
        name="Crop", description="Only this part of the model fills the cube", default=False
    )
    crop_min: FloatVectorProperty(name="Crop min", size=3, default=(0.0, 0.0, 0.0), description="Model space")
    crop_max: FloatVectorProperty(name="Crop max", size=3, default=(1.0, 1.0, 1.0), description="Model space")
    voxel_shift: FloatVectorProperty(
        name="Voxel shift",
        size=3,
        default=(0.0, 0.0, 0.0),
        description="Half a voxel (local space): the nerfpt cube is the object's transform moved by this "
        "(Cycles centres voxels half a voxel off OpenVDB's convention)",
    )
    object_placement: BoolProperty(
        name="Object placement",
        description="The model's object frame (nerfpt capture) is placed: the object stands where this object "
        "puts it, nerfpt cuts it to the object's box (extras.volume.placement 'object')",
        default=False,
    )
    object_from_cube: FloatVectorProperty(
        name="Object from cube",
        size=16,
        default=(1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1),
        description="Row-major: the cube's local space (the baked crop) -> the object frame (Z up)",
    )
    object_box_min: FloatVectorProperty(name="Object box min", size=3, description="Object frame, Z up")
    object_box_max: FloatVectorProperty(name="Object box max", size=3, description="Object frame, Z up")
    cube_min: FloatVectorProperty(
        name="Cube min", size=3, default=(-1.0, -1.0, -1.0), description="The nerfpt volume cube, local space"
    )
    cube_max: FloatVectorProperty(
        name="Cube max", size=3, default=(1.0, 1.0, 1.0), description="The nerfpt volume cube, local space"
    )


class NerfptRenderSettings(bpy.types.PropertyGroup):
    """What `nerfpt render` gets besides the scene: the image size comes from Output Properties."""

    samples: IntProperty(
        name="Samples", description="Samples per pixel (--spp)", default=64, min=1, max=1 << 20
    )
    max_bounces: IntProperty(
        name="Max bounces",
        description="Bounces after the first hit, as in Cycles: 0 is direct light only (nerfpt's --max-depth "
        "is this plus 1)",
        default=16,
        min=0,
        max=1023,
    )
    seed: IntProperty(
        name="Seed", description="Random seed (--seed): same seed, same image", default=0, min=0
    )


classes = (NerfptVolumeSettings, NerfptRenderSettings)


def register():
    for c in classes:
        bpy.utils.register_class(c)
    bpy.types.Object.nerfpt_volume = bpy.props.PointerProperty(type=NerfptVolumeSettings)
    bpy.types.Scene.nerfpt = bpy.props.PointerProperty(type=NerfptRenderSettings)


def unregister():
    del bpy.types.Scene.nerfpt
    del bpy.types.Object.nerfpt_volume
    for c in reversed(classes):
        bpy.utils.unregister_class(c)
