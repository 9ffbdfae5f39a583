"""What the add-on adds to the glTF that Blender's exporter wrote, as plain JSON edits (no bpy, testable alone):
the nerfpt `volume` cubes, materials the exporter cannot map, and the scene's render settings.

Axes: Blender is Z up, glTF Y up. The exporter maps a Blender point (x, y, z) to glTF (x, z, -y), i.e. the
matrix Y_UP below, and gives nodes C M C^-1. A volume cube's node gets Y_UP @ M_world instead: its LOCAL axes
stay Blender's, because a grid's (and a model's) coordinates are the Blender object's local coordinates.
"""

import math
import struct

Y_UP = [[1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, -1.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]]

VOLUME_MATERIAL = "volume"  # nerfpt: a primitive with a material of this name is a volume cube

# glTF enums
_FLOAT, _USHORT, _UINT = 5126, 5123, 5125
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


def scene_of(gltf):
    scenes = gltf.setdefault("scenes", [{"nodes": []}])
    return scenes[gltf.get("scene", 0)]


def append_mesh(gltf, data, buffer_index, name, positions, triangles, material):
    """Appends positions (float32 VEC3) and triangles (uint16 or uint32 indices) to data (a bytearray that
    becomes buffer buffer_index), with their views, accessors and a one-primitive mesh. Returns the mesh index."""
    views = gltf.setdefault("bufferViews", [])
    accessors = gltf.setdefault("accessors", [])
    meshes = gltf.setdefault("meshes", [])
    pos_offset = len(data)
    data += b"".join(struct.pack("<3f", *p) for p in positions)
    wide = len(positions) > 65535
    idx_offset = len(data)
    data += b"".join(struct.pack("<3I" if wide else "<3H", *t) for t in triangles)
    while len(data) % 4:
        data += b"\0"
    views.append(
        {
            "buffer": buffer_index,
            "byteOffset": pos_offset,
            "byteLength": 12 * len(positions),
            "target": _ARRAY_BUFFER,
        }
    )
    accessors.append(
        {
            "bufferView": len(views) - 1,
            "componentType": _FLOAT,
            "count": len(positions),
            "type": "VEC3",
            "min": [float(min(p[k] for p in positions)) for k in range(3)],
            "max": [float(max(p[k] for p in positions)) for k in range(3)],
        }
    )
    pos_accessor = len(accessors) - 1
    views.append(
        {
            "buffer": buffer_index,
            "byteOffset": idx_offset,
            "byteLength": (12 if wide else 6) * len(triangles),
            "target": _ELEMENT_ARRAY_BUFFER,
        }
    )
    accessors.append(
        {
            "bufferView": len(views) - 1,
            "componentType": _UINT if wide else _USHORT,
            "count": 3 * len(triangles),
            "type": "SCALAR",
        }
    )
    meshes.append(
        {
            "name": name,
            "primitives": [
                {"attributes": {"POSITION": pos_accessor}, "indices": len(accessors) - 1, "material": material}
            ],
        }
    )
    return len(meshes) - 1


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
    nodes = gltf.setdefault("nodes", [])
    buffer_index = len(buffers)
    data = bytearray()
    for cube in cubes:
        lo, hi = cube["min"], cube["max"]
        corners = [
            (hi[0] if i & 1 else lo[0], hi[1] if i & 2 else lo[1], hi[2] if i & 4 else lo[2])
            for i in range(8)
        ]
        mesh = append_mesh(
            gltf, data, buffer_index, cube["name"] + " (nerfpt volume cube)", corners, _BOX_TRIANGLES, mat
        )
        nodes.append({"name": cube["name"], "mesh": mesh, "matrix": cube["matrix"], "extras": cube["extras"]})
        scene_of(gltf).setdefault("nodes", []).append(len(nodes) - 1)
    buffers.append({"byteLength": len(data), "uri": bin_uri})
    return bytes(data)


def set_scene_extras(gltf, **settings):
    """Render settings nerfpt reads from the scene's extras (width, height, spp, max_depth, background)."""
    scene_of(gltf).setdefault("extras", {}).update(settings)


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


def _fresnel_dielectric(c, eta):
    s2 = (1.0 - c * c) / (eta * eta)
    if s2 >= 1.0:
        return 1.0
    ct = math.sqrt(1.0 - s2)
    rp = (eta * c - ct) / (eta * c + ct)
    rs = (c - eta * ct) / (c + eta * ct)
    return 0.5 * (rp * rp + rs * rs)


def cycles_specular_factor(specular):
    """glTF specularFactor for Blender 3.x's Principled Specular (docs/blender.md, "Specular").
    Cycles reflects with the exact dielectric Fresnel of the index eta whose F0 is 0.08 Specular; glTF with
    specularFactor (F0' + (1 - F0') (1 - cos)^5). F0 = specularFactor F0' matches through specularColorFactor;
    specularFactor is chosen so that the cosine-weighted hemispherical averages match too (what a white
    furnace sees): sf = 21 Favg(eta) - 20 F0, below 1 for Specular < 0.27 and 0 at Specular 0 (Cycles then has
    no reflection at all); above, Schlick's average is the smaller one and 1 is the closest glTF allows."""
    if specular <= 0.0:
        return 0.0
    f0 = 0.08 * min(specular, 1.0)
    q = math.sqrt(f0)
    eta = (1.0 + q) / (1.0 - q)
    n = 512
    avg = 2.0 * sum(_fresnel_dielectric((i + 0.5) / n, eta) * (i + 0.5) / n for i in range(n)) / n
    return max(0.0, min(1.0, 21.0 * avg - 20.0 * f0))


def cycles_specular_layer(gltf, material, specular, transmission):
    """Makes a Principled material's KHR_materials_specular say what Cycles 3.x renders: Blender's exporter
    writes specularColorFactor for F0 = 0.08 Specular and leaves specularFactor 1 (at Specular 0: F0 = 0 and a
    full grazing layer, where Cycles reflects nothing). Scales the layer by cycles_specular_factor (blended
    with 1, the glass's own Fresnel, by Transmission) and divides specularColorFactor by the same factor so
    that F0 stays. specular, transmission: the node's unlinked values, None when linked (nothing changes)."""
    if specular is None or transmission is None:
        return
    factor = (1.0 - transmission) * cycles_specular_factor(specular) + transmission
    if factor >= 1.0:
        return
    spec = material.setdefault("extensions", {}).setdefault("KHR_materials_specular", {})
    spec["specularFactor"] = factor
    if factor > 0.0 and "specularColorFactor" in spec:
        spec["specularColorFactor"] = [c / factor for c in spec["specularColorFactor"]]
    use_extension(gltf, "KHR_materials_specular")


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
