"""The material and modifier that make Cycles and EEVEE render a baked capture as nerfpt renders it.

nerfpt's volumes are emission-absorption fields (docs/formats.md, "Volumes: how they are rendered"): along a ray,
L = integral of T sigma c dt, with sigma = density_scale x density (an extinction coefficient) and
c = emission_scale x color (linear RGB). In Cycles, Volume Absorption with a black colour has the absorption
coefficient of its Density input, and Emission inside a volume is radiance per unit length, so
Absorption(sigma) + Emission(colour c, strength sigma) integrates exactly that (the construction of
../shared/data/scenes/cycles_reference.py, checked there against our renders).

Units. A grid baked by `nerfpt bake` holds sigma per LOCAL unit of the cube (a model's opacity does not depend
on the cube's size in the scene). The volume uses space WORLD (sigma per world unit, exact in Cycles) and the
material multiplies the density by |L^-1 d|, the local length per world length along the ray (d the ray
direction, L the object's linear transform: Geometry > Incoming through a world-to-object Vector Transform), so
scaling the object, even unevenly, keeps the object's opacity exactly. With "Density per local unit" off the
factor is 1 (sigma per world unit, as nerfpt reads other OpenVDB files).

Voxel centres. Cycles (measured in 3.4.1, ../shared/data/scenes/README.md, test B) samples a VDB grid as if voxel
i were centred at index i + 1/2, OpenVDB (and nerfpt) at i. As in ../shared/data/scenes/cycles_reference.py, the
object's transform is the nerfpt cube's followed by a shift of -1/2 voxel in local space (h below, kept in the
object's settings): matrix_world = cube @ T(-h), so the export writes cube = matrix_world @ T(h), whatever the
user does to the object later. (A geometry-nodes Transform of the grids would keep the object's transform clean,
but in Blender 3.4 it moves the original grids too, again at every evaluation.)
"""

import bpy

MATERIAL_NAME = "nerfpt volume"
MATERIAL_NAME_WHITE = "nerfpt volume (no colour grid)"
MATERIAL_NAME_RELIT = "nerfpt volume (relit)"
PROP = "nerfpt_volume"


def _math(nt, op, a, b, location):
    n = nt.nodes.new("ShaderNodeMath")
    n.operation = op
    n.location = location
    for i, v in enumerate((a, b)):
        if isinstance(v, (int, float)):
            n.inputs[i].default_value = v
        else:
            nt.links.new(v, n.inputs[i])
    return n.outputs[0]


def _attribute(nt, name, kind, location):
    n = nt.nodes.new("ShaderNodeAttribute")
    n.attribute_type = kind
    n.attribute_name = name
    n.location = location
    return n


def _sigma(nt):
    """The extinction coefficient per world unit: density x density_scale x |L^-1 d| (see "Units")."""
    density = _attribute(nt, "density", "GEOMETRY", (-800, 200))
    ds = _attribute(nt, PROP + ".density_scale", "OBJECT", (-800, 0))
    local = _attribute(nt, PROP + ".local_density", "OBJECT", (-800, -400))

    # |L^-1 d|: local units per world unit along the ray.
    geo = nt.nodes.new("ShaderNodeNewGeometry")
    geo.location = (-1000, -600)
    vt = nt.nodes.new("ShaderNodeVectorTransform")
    vt.vector_type = "VECTOR"
    vt.convert_from = "WORLD"
    vt.convert_to = "OBJECT"
    vt.location = (-800, -600)
    nt.links.new(geo.outputs["Incoming"], vt.inputs[0])
    length = nt.nodes.new("ShaderNodeVectorMath")
    length.operation = "LENGTH"
    length.location = (-600, -600)
    nt.links.new(vt.outputs[0], length.inputs[0])
    # factor = 1 + local * (|L^-1 d| - 1)
    factor = _math(
        nt,
        "ADD",
        _math(
            nt,
            "MULTIPLY",
            local.outputs["Fac"],
            _math(nt, "SUBTRACT", length.outputs["Value"], 1.0, (-400, -600)),
            (-200, -500),
        ),
        1.0,
        (0, -500),
    )
    return _math(
        nt,
        "MULTIPLY",
        _math(nt, "MULTIPLY", density.outputs["Fac"], ds.outputs["Fac"], (-400, 150)),
        factor,
        (200, 100),
    )


def _new_material(name):
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    nt = mat.node_tree
    nt.nodes.clear()
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    out.location = (900, 0)
    return mat, nt, out


def build_material(name, white=False):
    """The shared volume material; every value it needs per object comes from the object's nerfpt_volume
    settings (Attribute nodes of type Object), so one material serves every capture."""
    mat, nt, out = _new_material(name)
    sigma = _sigma(nt)
    es = _attribute(nt, PROP + ".emission_scale", "OBJECT", (-800, -200))

    absorb = nt.nodes.new("ShaderNodeVolumeAbsorption")
    absorb.inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)
    absorb.location = (450, 200)
    nt.links.new(sigma, absorb.inputs["Density"])
    emit = nt.nodes.new("ShaderNodeEmission")
    emit.location = (450, -100)
    if white:
        emit.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    else:
        color = _attribute(nt, "color", "GEOMETRY", (200, -250))
        nt.links.new(color.outputs["Color"], emit.inputs["Color"])
    nt.links.new(_math(nt, "MULTIPLY", sigma, es.outputs["Fac"], (250, -50)), emit.inputs["Strength"])
    add = nt.nodes.new("ShaderNodeAddShader")
    add.location = (700, 0)
    nt.links.new(absorb.outputs[0], add.inputs[0])
    nt.links.new(emit.outputs[0], add.inputs[1])
    nt.links.new(add.outputs[0], out.inputs["Volume"])
    return mat


def build_relit_material(name):
    """A relightable capture for Cycles and EEVEE: a scattering volume whose single-scattering albedo is the
    baked albedo grid (`nerfpt bake --colour albedo`) and whose extinction is nerfpt's sigma. Principled Volume
    with a black Absorption Color has scattering sigma x color and absorption sigma x (1 - color), so its
    extinction is sigma on every channel, as in nerfpt (the same transmittance, the same shadows). What differs
    is the event: nerfpt shades it with a surface BSDF (the albedo, roughness and normal of the intrinsic
    field), Cycles volumes can only scatter isotropically (anisotropy 0), many times inside the object's skin.
    The albedo is used as the single-scattering albedo as it is: mapping it to the single-scattering albedo
    whose dense isotropic medium reflects as much (van de Hulst) made the preview twice as bright as nerfpt's
    render, the albedo itself 10-15% darker (docs/blender.md, "Relightable captures")."""
    mat, nt, out = _new_material(name)
    sigma = _sigma(nt)
    color = _attribute(nt, "color", "GEOMETRY", (200, -250))
    pv = nt.nodes.new("ShaderNodeVolumePrincipled")
    pv.location = (550, 0)
    # Our sigma already holds the density grid: no attribute multiplies it again.
    pv.inputs["Density Attribute"].default_value = ""
    pv.inputs["Color Attribute"].default_value = ""
    pv.inputs["Temperature Attribute"].default_value = ""
    pv.inputs["Absorption Color"].default_value = (0.0, 0.0, 0.0, 1.0)
    pv.inputs["Anisotropy"].default_value = 0.0
    pv.inputs["Emission Strength"].default_value = 0.0
    pv.inputs["Blackbody Intensity"].default_value = 0.0
    nt.links.new(sigma, pv.inputs["Density"])
    nt.links.new(color.outputs["Color"], pv.inputs["Color"])
    nt.links.new(pv.outputs[0], out.inputs["Volume"])
    return mat


def volume_material(white=False, relit=False):
    name = MATERIAL_NAME_RELIT if relit else MATERIAL_NAME_WHITE if white else MATERIAL_NAME
    mat = bpy.data.materials.get(name)
    if mat is None or mat.library is not None:
        mat = build_relit_material(name) if relit else build_material(name, white)
    return mat


def half_voxel(grid):
    """1/2 of the grid's voxel diagonal in the object's local space (grid.matrix_object maps index to local)."""
    m = grid.matrix_object
    return tuple(0.5 * (m[r][0] + m[r][1] + m[r][2]) for r in range(3))


def setup_volume_data(volume):
    """Render settings that make Cycles integrate the grid as nerfpt does."""
    volume.render.space = "WORLD"  # sigma per world unit; the material applies the local-unit factor
    volume.render.precision = "FULL"  # no half-float or lossy grid conversion
    volume.render.clipping = 0.0  # keep thin densities
    volume.render.step_size = 0.0  # automatic: the voxel size times the scene's step rate
