"""A Blender scene as a glTF that nerfpt renders: Blender's glTF exporter (extras, cameras, punctual lights,
modifiers applied), then the add-on's additions (gltf_post, area_lights): a `volume` cube per capture object, a
one-sided emissive polygon per area light, materials the exporter cannot map (Diffuse, Glossy, Glass, Emission
shaders), the Principled specular layer as Cycles renders it, the render settings and the world colour as scene
extras. Everything nerfpt would not render as Cycles does is collected as one list of warnings
(docs/blender.md has the mapping table).
"""

import json
import math
import os

import bpy
from mathutils import Matrix, Vector

from . import area_lights, gltf_post
from .nerfpt_cli import NerfptError, ignored_report

CUBE_BIN = "nerfpt_volumes.bin"
ANIMATION_NAME = "Animation"  # the one glTF animation of an export with animation
AREA_LIGHT_BIN = "nerfpt_area_lights.bin"

# Principled BSDF inputs nerfpt ignores, with the value at which they do nothing (3.x and 4.x names).
_IGNORED_PRINCIPLED = [
    (("Subsurface", "Subsurface Weight"), 0.0, "subsurface"),
    (("Sheen", "Sheen Weight"), 0.0, "sheen"),
    (("Clearcoat", "Coat Weight"), 0.0, "clearcoat"),
    (("Anisotropic",), 0.0, "anisotropy"),
    (("Alpha",), 1.0, "alpha"),
]


def _exporter_options(filepath, animation=False):
    """The exporter's keywords, under the names this Blender's exporter uses (3.4 and 4.x differ). With
    `animation`, the scene's animation too, as one glTF animation (every object's action merged: nerfpt plays
    one), sampled at every frame of the playback range (so constraints, drivers and Bezier easing come out as
    Blender evaluates them at whole frames)."""
    wanted = {
        "filepath": filepath,
        "check_existing": False,
        "export_format": "GLTF_SEPARATE",
        "use_selection": False,
        "use_visible": False,
        "use_renderable": True,
        "use_active_scene": True,
        "export_extras": True,
        "export_cameras": True,
        "export_lights": True,
        "export_apply": True,
        "export_yup": True,
        "export_animations": animation,
        "export_materials": "EXPORT",
        "will_save_settings": False,
        # W and W/m^2 divided by 4 pi for point and spot lights, not multiplied by 683 lm/W: the radiometric
        # intensity Cycles' lights have, which nerfpt's `intensity` is.
        ("export_import_convert_lighting_mode", "convert_lighting_mode"): "COMPAT",
    }
    if animation:
        wanted.update(
            {
                "export_frame_range": True,
                "export_frame_step": 1,
                "export_force_sampling": True,
                "export_nla_strips": False,
                "export_nla_strips_merged_animation_name": ANIMATION_NAME,
                "export_optimize_animation_size": False,
                ("export_anim_slide_to_zero",): False,  # 4.x: keep frame F at F / fps
            }
        )
    known = set(bpy.ops.export_scene.gltf.get_rna_type().properties.keys())
    options = {}
    for key, value in wanted.items():
        for name in key if isinstance(key, tuple) else (key,):
            if name in known:
                options[name] = value
                break
    return options


def renders(obj, view_layer):
    """Whether a final render shows obj: in the view layer, not disabled for rendering."""
    if obj.name not in view_layer.objects or obj.hide_render:
        return False
    return not any(c.hide_render for c in obj.users_collection)


def _linked_shader(socket):
    if not socket.is_linked:
        return None
    node = socket.links[0].from_node
    while node.type == "REROUTE" and node.inputs[0].is_linked:
        node = node.inputs[0].links[0].from_node
    return node


def _active_output(mat):
    outs = [n for n in mat.node_tree.nodes if n.type == "OUTPUT_MATERIAL"]
    for target in ("CYCLES", "ALL"):
        for n in outs:
            if n.is_active_output and n.target in (target,):
                return n
    return next((n for n in outs if n.is_active_output), outs[0] if outs else None)


def _value(node, *names):
    for name in names:
        s = node.inputs.get(name)
        if s is not None:
            return s
    return None


def _constant(socket, what, notes):
    """A socket's own value; a linked socket (a texture) is noted and its unlinked value used."""
    if socket.is_linked:
        notes.append(f"{what} is linked (textures on this shader are ignored; its value is used)")
    v = socket.default_value
    return list(v) if hasattr(v, "__len__") else float(v)


def map_material(mat, notes):
    """A glTF material for shaders the exporter does not map, or None to keep the exporter's."""
    if not mat.use_nodes or mat.node_tree is None:
        return gltf_post.lambert(list(mat.diffuse_color))
    out = _active_output(mat)
    if out is None:
        notes.append("no Material Output node: black")
        return gltf_post.emitter([0, 0, 0], 0.0)
    if out.inputs["Volume"].is_linked:
        notes.append(
            "volume shaders on meshes are ignored (import captures with File > Import > nerfpt model)"
        )
    shader = _linked_shader(out.inputs["Surface"])
    if shader is None:
        notes.append("no surface shader: black")
        return gltf_post.emitter([0, 0, 0], 0.0)
    kind = shader.type
    if kind == "BSDF_PRINCIPLED":
        for names, neutral, label in _IGNORED_PRINCIPLED:
            s = _value(shader, *names)
            if s is not None and (s.is_linked or abs(float(s.default_value) - neutral) > 1e-6):
                notes.append(f"Principled {label} is ignored")
        return None
    if kind == "BSDF_DIFFUSE":
        rough = _constant(shader.inputs["Roughness"], "Diffuse Roughness", notes)
        if rough > 0:
            notes.append("Diffuse roughness (Oren-Nayar) is ignored: Lambert")
        return gltf_post.lambert(_constant(shader.inputs["Color"], "Diffuse Color", notes))
    if kind == "EMISSION":
        color = _constant(shader.inputs["Color"], "Emission Color", notes)
        return gltf_post.emitter(color, _constant(shader.inputs["Strength"], "Emission Strength", notes))
    if kind in ("BSDF_GLOSSY", "BSDF_ANISOTROPIC"):
        color = _constant(shader.inputs["Color"], "Glossy Color", notes)
        return gltf_post.metal(color, _constant(shader.inputs["Roughness"], "Glossy Roughness", notes))
    if kind == "BSDF_GLASS":
        color = _constant(shader.inputs["Color"], "Glass Color", notes)
        rough = _constant(shader.inputs["Roughness"], "Glass Roughness", notes)
        return gltf_post.glass(color, rough, _constant(shader.inputs["IOR"], "Glass IOR", notes))
    notes.append(
        f"surface shader '{shader.name}' ({shader.bl_label}) is not supported: the exporter's guess is used"
    )
    return None


def _principled(mat):
    """The Principled BSDF node a material's active output renders, or None."""
    if not mat.use_nodes or mat.node_tree is None:
        return None
    out = _active_output(mat)
    shader = _linked_shader(out.inputs["Surface"]) if out is not None else None
    return shader if shader is not None and shader.type == "BSDF_PRINCIPLED" else None


def _unlinked(node, name):
    """A socket's value, or None when it is linked (or missing)."""
    s = node.inputs.get(name)
    return None if s is None or s.is_linked else float(s.default_value)


def _world_background(world, notes):
    """Constant linear RGB radiance of the world, which nerfpt sees where rays leave the scene."""
    if world is None:
        return [0.0, 0.0, 0.0]
    if not world.use_nodes or world.node_tree is None:
        return list(world.color[:3])
    out = next((n for n in world.node_tree.nodes if n.type == "OUTPUT_WORLD" and n.is_active_output), None)
    bg = _linked_shader(out.inputs["Surface"]) if out else None
    if bg is None:
        return [0.0, 0.0, 0.0]
    if bg.type != "BACKGROUND":
        notes.append(f"world shader '{bg.bl_label}' is not supported: black")
        return [0.0, 0.0, 0.0]
    if bg.inputs["Color"].is_linked or bg.inputs["Strength"].is_linked:
        notes.append("world: only a constant background colour is used (environment textures are ignored)")
    strength = float(bg.inputs["Strength"].default_value)
    return [float(c) * strength for c in bg.inputs["Color"].default_value[:3]]


def _scale_factors(matrix):
    return [math.sqrt(sum(matrix[r][c] ** 2 for r in range(3))) for c in range(3)]


def _volume_extras(obj, world, gltf_dir, absolute_paths, notes):
    s = obj.nerfpt_volume
    grid = os.path.abspath(bpy.path.abspath(obj.data.filepath))
    model = os.path.abspath(bpy.path.abspath(s.model_path)) if s.model_path else ""
    relit = s.shading == "RELIT" and model
    use_model = (s.source == "MODEL" or relit) and model
    if s.source == "MODEL" and not model:
        notes.append(f"capture '{obj.name}' has no model file: its grid is rendered")
    if relit and s.source == "GRID":
        notes.append(f"capture '{obj.name}' is relit: nerfpt renders its model (a grid cannot be relit)")
    path = model if use_model else grid
    if not os.path.isfile(path):
        raise NerfptError(f"capture '{obj.name}': file '{path}' not found")
    if not absolute_paths:
        try:
            path = os.path.relpath(path, gltf_dir)
        except ValueError:  # another drive
            pass
    density_scale = s.density_scale
    scales = _scale_factors(world)
    if not use_model and s.local_density:
        # nerfpt reads a grid's density per world unit; the grid holds it per local unit.
        mean = (scales[0] * scales[1] * scales[2]) ** (1.0 / 3.0)
        if max(scales) > 1.001 * min(scales):
            notes.append(
                f"capture '{obj.name}' is scaled unevenly: nerfpt renders its grid with the mean scale "
                "(exact for the model, source Model)"
            )
        density_scale = density_scale / mean if mean > 0 else density_scale
    volume = {
        "file": path.replace(os.sep, "/"),
        "density_scale": density_scale,
        "emission_scale": s.emission_scale,
        "casts_shadows": bool(s.casts_shadows),
        "step_voxels": s.step_voxels,
    }
    if use_model:
        # Said even where it is nerfpt's default (relit for a relightable model): the export means what the
        # Blender object shows, whatever the default becomes.
        volume["shading"] = "relit" if relit else "emissive"
    if use_model and s.object_placement:
        volume["placement"] = "object"  # the object frame: the node places the object (see _cube_of)
    elif use_model and s.use_crop:
        volume["crop"] = {"min": list(s.crop_min), "max": list(s.crop_max)}
    return {"volume": volume}


# nerfpt's object placement: the cube's local space is the object frame turned Y up, local (x, y, z) = object
# (x, z, -y) (docs/formats.md); this maps local back to the object frame.
_OBJECT_FROM_LOCAL = Matrix(((1, 0, 0, 0), (0, 0, -1, 0), (0, 1, 0, 0), (0, 0, 0, 1)))


def _cube_of(obj, world, extras):
    """The volume cube's glTF matrix, min and max. Object placement: the node maps the object frame (Y up) to the
    world, and the box is the object's; else the cube is the baked grid's."""
    s = obj.nerfpt_volume
    cube = world @ Matrix.Translation(s.voxel_shift)  # volume_material, "Voxel centres"
    if extras["volume"].get("placement") != "object":
        return gltf_post.gltf_node_matrix(cube), list(s.cube_min), list(s.cube_max)
    object_from_cube = Matrix([s.object_from_cube[4 * r : 4 * r + 4] for r in range(4)])
    node = cube @ object_from_cube.inverted() @ _OBJECT_FROM_LOCAL
    lo, hi = s.object_box_min, s.object_box_max
    return gltf_post.gltf_node_matrix(node), [lo[0], lo[2], -hi[1]], [hi[0], hi[2], -lo[1]]


def _exported_area_light(obj):
    """Area lights become emitters unless they emit nothing (a portal, no power)."""
    light = obj.data
    return not getattr(getattr(light, "cycles", None), "is_portal", False) and light.energy > 0.0


def _camera_sees(scene, camera, points, facing):
    """Whether the camera may see points' polygon from its emitting side (facing: the emission direction).
    Conservative: a polygon partly behind the camera counts as seen."""
    from bpy_extras.object_utils import world_to_camera_view

    eye = camera.matrix_world.translation
    centre = sum(points, Vector()) / len(points)
    if (eye - centre).dot(facing) <= 0.0:
        return False
    ndc = [world_to_camera_view(scene, camera, p) for p in points]
    if any(v.z <= 0.0 for v in ndc):
        return True
    xs, ys = [v.x for v in ndc], [v.y for v in ndc]
    return max(xs) >= 0.0 and min(xs) <= 1.0 and max(ys) >= 0.0 and min(ys) <= 1.0


def _area_light_notes(scene, obj, camera, notes):
    """What of an area light the emissive polygon does not carry."""
    light = obj.data
    name = f"area light '{obj.name}'"
    if not _exported_area_light(obj):
        if light.energy > 0.0:
            notes.append(f"{name} is a portal: not exported")
        return
    spread = getattr(light, "spread", area_lights.FULL_SPREAD)
    if spread < area_lights.FULL_SPREAD - 1e-4:
        notes.append(f"{name}: spread {math.degrees(spread):.0f} deg is rendered as 180 deg")
    if light.use_nodes:
        notes.append(f"{name}: its node tree is ignored (colour x power is used)")
    cycles = getattr(light, "cycles", None)
    if cycles is not None and not getattr(cycles, "cast_shadow", True):
        notes.append(f"{name}: 'cast shadow' off is ignored (nerfpt's emitters always cast shadows)")
    hidden = [
        ray
        for ray in ("diffuse", "glossy", "transmission", "volume_scatter")
        if not getattr(obj, f"visible_{ray}", True)
    ]
    if hidden:
        notes.append(f"{name}: its ray visibility ({', '.join(hidden)} off) is ignored")
    if camera is not None and not getattr(obj, "visible_camera", True):
        world = obj.matrix_world
        points, _ = area_lights.emitter_mesh(light.shape, light.size, light.size_y, [list(r) for r in world])
        facing = -(world.to_3x3() @ Vector((0.0, 0.0, 1.0)))
        if _camera_sees(scene, camera, [Vector(p) for p in points], facing):
            notes.append(
                f"{name} is in view: nerfpt's camera sees it (Cycles' does not: Object > Visibility > Camera)"
            )


def _check_scene(scene, view_layer, camera, notes):
    r = scene.render
    if r.use_border:
        notes.append("render region (border) is ignored: the whole frame is rendered")
    if r.pixel_aspect_x != r.pixel_aspect_y:
        notes.append("non-square pixel aspect is ignored")
    if r.film_transparent:
        notes.append("transparent film is ignored: the world colour is the background")
    if r.use_motion_blur:
        notes.append("motion blur is ignored")
    if camera is not None:
        cam = camera.data
        if cam.type != "PERSP":
            notes.append(
                f"camera '{camera.name}' is {cam.type.lower()}: nerfpt renders perspective cameras only"
            )
        if cam.dof.use_dof:
            notes.append("depth of field is ignored")
        if cam.shift_x or cam.shift_y:
            notes.append("camera shift is ignored")
    for obj in scene.objects:
        if not renders(obj, view_layer):
            continue
        if obj.type == "LIGHT":
            light = obj.data
            if light.type == "AREA":
                _area_light_notes(scene, obj, camera, notes)
            elif getattr(light, "shadow_soft_size", 0) > 0 and light.type in ("POINT", "SPOT"):
                notes.append(f"light '{obj.name}': its radius is ignored (a point light: hard shadows)")
            elif light.type == "SUN" and light.angle > 0:
                notes.append(f"sun '{obj.name}': its angle is ignored (hard shadows)")
        elif obj.type == "VOLUME" and not obj.nerfpt_volume.is_capture:
            notes.append(
                f"volume '{obj.name}' is not a nerfpt capture (File > Import > nerfpt model): not exported"
            )
        elif obj.type in ("GPENCIL", "CURVES", "POINTCLOUD"):
            notes.append(f"{obj.type.lower()} object '{obj.name}' is not exported")
        if obj.type == "MESH":
            for ps in obj.particle_systems:
                if ps.settings.type == "HAIR":
                    notes.append(f"hair on '{obj.name}' is not exported")


def _notes_text(notes):
    seen = []
    for n in notes:
        if n not in seen:
            seen.append(n)
    return seen


def max_depth(scene):
    """nerfpt's --max-depth counts scattering events, so direct light alone is depth 1; Blender's (Cycles')
    "max bounces" counts bounces after the first hit, direct light alone being 0."""
    return scene.nerfpt.max_bounces + 1


def export(scene, view_layer, filepath, resolution=None, absolute_paths=False, animation=False):
    """Writes filepath (.gltf + .bin + textures beside it) with the scene's nerfpt render settings as scene
    extras. With `animation`, also the scene's animation (Render Animation exports once for all its frames):
    nerfpt's frame F is at F / fps seconds, as the exporter writes Blender's frame F, with fps the scene's
    (written as the `fps` extra). Returns the list of warnings. Raises NerfptError. Must run on the main
    thread (the exporter is an operator)."""
    gltf_dir = os.path.dirname(os.path.abspath(filepath))
    notes = []
    camera = scene.camera
    _check_scene(scene, view_layer, camera, notes)
    override = {"scene": scene, "view_layer": view_layer}
    wm = bpy.context.window_manager
    if wm.windows:
        override["window"] = wm.windows[0]
    try:
        with bpy.context.temp_override(**override):
            result = bpy.ops.export_scene.gltf(**_exporter_options(filepath, animation))
            # Final transforms (constraints, parents, drivers), as the exporter saw them.
            depsgraph = bpy.context.evaluated_depsgraph_get()
    except (RuntimeError, TypeError) as e:
        last = [ln for ln in str(e).strip().splitlines() if ln.strip()]
        raise NerfptError(
            "Blender's glTF export failed: " + (last[-1].strip() if last else "unknown error")
        ) from None
    if "FINISHED" not in result or not os.path.isfile(filepath):
        raise NerfptError("Blender's glTF export wrote nothing")

    with open(filepath) as f:
        gltf = json.load(f)

    # Materials the exporter cannot map.
    for i, m in enumerate(gltf.get("materials", [])):
        mat = bpy.data.materials.get(m.get("name", ""))
        if mat is None:
            continue
        mat_notes = []
        mapped = map_material(mat, mat_notes)
        if m.get("name") == gltf_post.VOLUME_MATERIAL:
            mat_notes.append("a material named 'volume' makes nerfpt treat its meshes as volume cubes")
        if mapped is not None:
            gltf_post.replace_material(gltf, i, mapped)
        else:
            principled = _principled(mat)
            if principled is not None and principled.inputs.get("Specular") is not None:  # Blender 3.x
                gltf_post.cycles_specular_layer(
                    gltf,
                    m,
                    _unlinked(principled, "Specular"),
                    _unlinked(principled, "Transmission"),
                )
        notes += [f"material '{mat.name}': {n}" for n in mat_notes]

    # The captures' volume cubes.
    cubes = []
    for obj in scene.objects:
        if obj.type != "VOLUME" or not obj.nerfpt_volume.is_capture or not renders(obj, view_layer):
            continue
        world = obj.evaluated_get(depsgraph).matrix_world
        extras = _volume_extras(obj, world, gltf_dir, absolute_paths, notes)
        matrix, lo, hi = _cube_of(obj, world, extras)
        cubes.append({"name": obj.name, "matrix": matrix, "min": lo, "max": hi, "extras": extras})
    if animation:
        # The add-on's own nodes are placed where the objects are now; they do not follow the animation.
        for obj in scene.objects:
            moving = obj.animation_data is not None and obj.animation_data.action is not None
            if moving and renders(obj, view_layer) and (
                (obj.type == "VOLUME" and obj.nerfpt_volume.is_capture)
                or (obj.type == "LIGHT" and obj.data.type == "AREA")
            ):
                notes.append(f"'{obj.name}' is animated: nerfpt renders it where it is at frame {scene.frame_current}")
    data = gltf_post.add_volume_cubes(gltf, cubes, CUBE_BIN)
    if data:
        with open(os.path.join(gltf_dir, CUBE_BIN), "wb") as f:
            f.write(data)

    # Area lights as one-sided emissive polygons (area_lights).
    emitters = []
    for obj in scene.objects:
        if obj.type != "LIGHT" or obj.data.type != "AREA" or not renders(obj, view_layer):
            continue
        if not _exported_area_light(obj):
            continue
        light = obj.data
        emitters.append(
            {
                "name": obj.name,
                "shape": light.shape,
                "size_x": light.size,
                "size_y": light.size_y,
                "world": [list(r) for r in obj.evaluated_get(depsgraph).matrix_world],
                "color": list(light.color),
                "power": light.energy,
            }
        )
    data = area_lights.add_emitters(gltf, emitters, AREA_LIGHT_BIN)
    if data:
        with open(os.path.join(gltf_dir, AREA_LIGHT_BIN), "wb") as f:
            f.write(data)

    r = scene.render
    width, height = resolution or (
        r.resolution_x * r.resolution_percentage // 100,
        r.resolution_y * r.resolution_percentage // 100,
    )
    gltf_post.set_scene_extras(
        gltf,
        width=max(1, width),
        height=max(1, height),
        spp=scene.nerfpt.samples,
        max_depth=max_depth(scene),
        background=_world_background(scene.world, notes),
    )
    if animation:
        gltf_post.set_scene_extras(gltf, fps=float(r.fps))  # the exporter's seconds are frame / r.fps
    tmp = filepath + ".tmp"
    with open(tmp, "w") as f:
        json.dump(gltf, f, indent=1)
    os.replace(tmp, filepath)
    return _notes_text(notes)


class NERFPT_OT_export_scene(bpy.types.Operator):
    """Export the scene as glTF for nerfpt: captures as `volume` cubes, render settings as scene extras"""

    bl_idname = "export_scene.nerfpt_gltf"
    bl_label = "Export nerfpt scene"
    bl_options = {"REGISTER"}

    filepath: bpy.props.StringProperty(subtype="FILE_PATH")
    filter_glob: bpy.props.StringProperty(default="*.gltf", options={"HIDDEN"})

    def invoke(self, context, event):
        if not self.filepath:
            blend = bpy.data.filepath
            self.filepath = (os.path.splitext(blend)[0] if blend else "scene") + ".gltf"
        context.window_manager.fileselect_add(self)
        return {"RUNNING_MODAL"}

    def execute(self, context):
        path = bpy.path.ensure_ext(bpy.path.abspath(self.filepath), ".gltf")
        try:
            notes = export(context.scene, context.view_layer, path)
        except NerfptError as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        warning = ignored_report(notes)
        if warning:
            self.report({"WARNING"}, warning)
        self.report(
            {"INFO"}, f"wrote {path} (render it with: nerfpt render {os.path.basename(path)} -o out.exr)"
        )
        return {"FINISHED"}


def menu_export(self, context):
    self.layout.operator(NERFPT_OT_export_scene.bl_idname, text="nerfpt scene (.gltf)")


def register():
    bpy.utils.register_class(NERFPT_OT_export_scene)
    bpy.types.TOPBAR_MT_file_export.append(menu_export)


def unregister():
    bpy.types.TOPBAR_MT_file_export.remove(menu_export)
    bpy.utils.unregister_class(NERFPT_OT_export_scene)
