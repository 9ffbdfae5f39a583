"""What the add-on adds to the glTF that Blender's exporter wrote, as plain JSON edits (no bpy, testable alone):
the nerfpt `volume` cubes, materials the exporter cannot map, and the scene's render settings.

Axes: Blender is Z up, glTF Y up. The exporter maps a Blender point (x, y, z) to glTF (x, z, -y), i.e. the
matrix Y_UP below, and gives nodes C M C^-1. A volume cube's node gets Y_UP @ M_world instead: its LOCAL axes
stay Blender's, because a grid's (and a model's) coordinates are the Blender object's local coordinates.
"""

import struct

Y_UP = [[1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, -1.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]]

VOLUME_MATERIAL = "volume"  # nerfpt: a primitive with a material of this name is a volume cube

# glTF enums
_FLOAT, _USHORT = 5126, 5123
_ARRAY_BUFFER, _ELEMENT_ARRAY_BUFFER = 34962, 34963

# A box's 12 triangles, counter-clockwise seen from outside; corner i has x = bit 0, y = bit 1, z = bit 2.
# fmt: off
_BOX_TRIANGLES = [
    (0, 2, 3), (0, 3, 1), (4, 5, 7), (4, 7, 6),  # -z, +z
    (0, 1, 5), (0, 5, 4), (2, 6, 7), (2, 7, 3),  # -y, +y
    (0, 4, 6), (0, 6, 2), (1, 3, 7), (1, 7, 5),  # -x, +x
]
# fmt: on


def matmul(a, b):
    return [[sum(a[r][k] * b[k][c] for k in range(4)) for c in range(4)] for r in range(4)]


def column_major(m):
    return [float(m[r][c]) for c in range(4) for r in range(4)]


def gltf_node_matrix(blender_world):
    """glTF `matrix` for a volume cube whose Blender world matrix (4 rows) is given."""
    return column_major(matmul(Y_UP, [list(r) for r in blender_world]))


def to_gltf_point(p):
    return (p[0], p[2], -p[1])


def _scene(gltf):
    scenes = gltf.setdefault("scenes", [{"nodes": []}])
    return scenes[gltf.get("scene", 0)]


def add_volume_cubes(gltf, cubes, bin_uri):
    """Adds one node per cube: {'name', 'matrix' (glTF, column major), 'min', 'max' (local box), 'extras'}.
    Returns the bytes of the buffer that bin_uri must hold (b'' when there are no cubes)."""
    if not cubes:
        return b""
    materials = gltf.setdefault("materials", [])
    mat = next((i for i, m in enumerate(materials) if m.get("name") == VOLUME_MATERIAL), None)
    if mat is None:
        materials.append({"name": VOLUME_MATERIAL})
        mat = len(materials) - 1
    buffers = gltf.setdefault("buffers", [])
    views = gltf.setdefault("bufferViews", [])
    accessors = gltf.setdefault("accessors", [])
    meshes = gltf.setdefault("meshes", [])
    nodes = gltf.setdefault("nodes", [])
    buffer_index = len(buffers)
    data = bytearray()
    index_bytes = b"".join(struct.pack("<3H", *t) for t in _BOX_TRIANGLES)
    for cube in cubes:
        lo, hi = cube["min"], cube["max"]
        corners = [
            (hi[0] if i & 1 else lo[0], hi[1] if i & 2 else lo[1], hi[2] if i & 4 else lo[2])
            for i in range(8)
        ]
        pos_offset = len(data)
        data += b"".join(struct.pack("<3f", *c) for c in corners)
        idx_offset = len(data)
        data += index_bytes
        while len(data) % 4:
            data += b"\0"
        views.append(
            {"buffer": buffer_index, "byteOffset": pos_offset, "byteLength": 96, "target": _ARRAY_BUFFER}
        )
        accessors.append(
            {
                "bufferView": len(views) - 1,
                "componentType": _FLOAT,
                "count": 8,
                "type": "VEC3",
                "min": [float(v) for v in lo],
                "max": [float(v) for v in hi],
            }
        )
        pos_accessor = len(accessors) - 1
        views.append(
            {
                "buffer": buffer_index,
                "byteOffset": idx_offset,
                "byteLength": len(index_bytes),
                "target": _ELEMENT_ARRAY_BUFFER,
            }
        )
        accessors.append(
            {"bufferView": len(views) - 1, "componentType": _USHORT, "count": 36, "type": "SCALAR"}
        )
        meshes.append(
            {
                "name": cube["name"] + " (nerfpt volume cube)",
                "primitives": [
                    {"attributes": {"POSITION": pos_accessor}, "indices": len(accessors) - 1, "material": mat}
                ],
            }
        )
        nodes.append(
            {
                "name": cube["name"],
                "mesh": len(meshes) - 1,
                "matrix": cube["matrix"],
                "extras": cube["extras"],
            }
        )
        _scene(gltf).setdefault("nodes", []).append(len(nodes) - 1)
    buffers.append({"byteLength": len(data), "uri": bin_uri})
    return bytes(data)


def set_scene_extras(gltf, **settings):
    """Render settings nerfpt reads from the scene's extras (width, height, spp, max_depth, background)."""
    _scene(gltf).setdefault("extras", {}).update(settings)


def material_index(gltf, name):
    for i, m in enumerate(gltf.get("materials", [])):
        if m.get("name") == name:
            return i
    return None


def use_extension(gltf, name):
    used = gltf.setdefault("extensionsUsed", [])
    if name not in used:
        used.append(name)


def replace_material(gltf, index, material):
    """Replaces material `index` (keeping its name and doubleSided) by `material`, registering its extensions."""
    old = gltf["materials"][index]
    new = dict(material)
    new["name"] = old.get("name", "")
    if "doubleSided" in old and "doubleSided" not in new:
        new["doubleSided"] = old["doubleSided"]
    gltf["materials"][index] = new
    for ext in new.get("extensions", {}):
        use_extension(gltf, ext)


def no_specular_when_black(material):
    """Principled Specular 0 comes out of Blender's exporter as specularColorFactor 0 (F0 = 0), which still
    leaves Schlick's grazing term (1 - cos)^5; specularFactor 0 removes the layer, as Blender does."""
    spec = material.get("extensions", {}).get("KHR_materials_specular")
    if spec is not None and spec.get("specularColorFactor") == [0.0, 0.0, 0.0]:
        spec["specularFactor"] = 0.0


def lambert(color):
    """Exactly albedo/pi in nerfpt: no metal, no specular layer (Cycles' Diffuse BSDF with roughness 0)."""
    return {
        "pbrMetallicRoughness": {
            "baseColorFactor": [*color[:3], 1.0],
            "metallicFactor": 0.0,
            "roughnessFactor": 1.0,
        },
        "extensions": {"KHR_materials_specular": {"specularFactor": 0.0}},
    }


def emitter(color, strength):
    """Radiance color x strength, black otherwise (Cycles' Emission shader on a surface)."""
    peak = max(color[:3]) if max(color[:3]) > 0 else 1.0
    return {
        "pbrMetallicRoughness": {"baseColorFactor": [0.0, 0.0, 0.0, 1.0], "metallicFactor": 0.0},
        "emissiveFactor": [c / peak for c in color[:3]],
        "extensions": {
            "KHR_materials_emissive_strength": {"emissiveStrength": strength * peak},
            "KHR_materials_specular": {"specularFactor": 0.0},
        },
    }


def metal(color, roughness):
    """glTF metal (Schlick Fresnel with F0 = colour; Cycles' Glossy BSDF has none). Both use alpha = roughness^2."""
    return {
        "pbrMetallicRoughness": {
            "baseColorFactor": [*color[:3], 1.0],
            "metallicFactor": 1.0,
            "roughnessFactor": float(roughness),
        }
    }


def glass(color, roughness, ior):
    return {
        "pbrMetallicRoughness": {
            "baseColorFactor": [*color[:3], 1.0],
            "metallicFactor": 0.0,
            "roughnessFactor": float(roughness),
        },
        "extensions": {
            "KHR_materials_transmission": {"transmissionFactor": 1.0},
            "KHR_materials_ior": {"ior": float(ior)},
        },
    }
