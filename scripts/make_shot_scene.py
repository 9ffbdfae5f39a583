#!/usr/bin/env python3
"""Writes scenes/shot/scene.gltf: a small animated shot for `nerfpt render --frames` (docs/formats.md, Animation).

A grey floor, a white ceiling panel that emits, a red cube that slides (LINEAR), turns in steps (STEP) and
stretches (CUBICSPLINE on its scale), and a camera on a rig that swings about +Y (slerp) while it dollies in
(LINEAR). Two seconds at 24 fps: frames 1-48. Small on purpose (64x48, 16 spp in the scene's extras) so that tests and CI render it
in seconds. Usage: scripts/make_shot_scene.py [OUT.gltf]
"""
import base64
import json
import math
import struct
import sys

buf = bytearray()
views, accessors = [], []


def add(values, fmt, type_, count, component=5126, minmax=None):
    while len(buf) % 4:
        buf.append(0)
    offset = len(buf)
    buf.extend(struct.pack("<" + fmt * len(values), *values))
    views.append({"buffer": 0, "byteOffset": offset, "byteLength": len(buf) - offset})
    acc = {"bufferView": len(views) - 1, "componentType": component, "count": count, "type": type_}
    if minmax:
        acc["min"], acc["max"] = minmax
    accessors.append(acc)
    return len(accessors) - 1


def mesh_box(lo, hi):
    """A box as 6 quads with outward normals (24 vertices)."""
    pos, nrm, idx = [], [], []
    for axis in range(3):
        for side in (0, 1):
            n = [0.0, 0.0, 0.0]
            n[axis] = 1.0 if side else -1.0
            u, v = (axis + 1) % 3, (axis + 2) % 3
            base = len(pos) // 3
            for a, b in ((0, 0), (1, 0), (1, 1), (0, 1)):
                p = [0.0] * 3
                p[axis] = hi[axis] if side else lo[axis]
                p[u] = hi[u] if a else lo[u]
                p[v] = hi[v] if b else lo[v]
                pos += p
                nrm += n
            quad = [base, base + 1, base + 2, base, base + 2, base + 3]
            if not side:
                quad = [base, base + 2, base + 1, base, base + 3, base + 2]
            idx += quad
    return pos, nrm, idx


def primitive(pos, nrm, idx, material):
    n = len(pos) // 3
    lo = [min(pos[k::3]) for k in range(3)]
    hi = [max(pos[k::3]) for k in range(3)]
    return {"attributes": {"POSITION": add(pos, "f", "VEC3", n, minmax=(lo, hi)),
                           "NORMAL": add(nrm, "f", "VEC3", n)},
            "indices": add(idx, "I", "SCALAR", len(idx), component=5125), "material": material}


floor = mesh_box([-3, -0.1, -3], [3, 0, 3])
cube = mesh_box([-0.4, -0.4, -0.4], [0.4, 0.4, 0.4])
panel = mesh_box([-1, 2.4, -1], [1, 2.5, 1])

fps, seconds = 24.0, 2.0
key_times = [0.0, 1.0, 2.0]
times = add(key_times, "f", "SCALAR", 3, minmax=([0.0], [2.0]))
# The rig swings from -30 to +30 degrees about +Y (LINEAR: slerp between unit quaternions).
rig_rot = []
for deg in (-30, 0, 30):
    h = math.radians(deg) / 2
    rig_rot += [0.0, math.sin(h), 0.0, math.cos(h)]
rig_rotation = add(rig_rot, "f", "VEC4", 3)
# The camera dollies in along its own -Z (its rest translation is (0, 1.2, 4)).
cam_translation = add([0, 1.2, 4.5, 0, 1.2, 4.0, 0, 1.2, 3.5], "f", "VEC3", 3)
# The cube slides along X (LINEAR) and hops (CUBICSPLINE: in-tangent, value, out-tangent per key).
cube_translation = add([-1.0, 0.4, 0, 0.0, 0.4, 0, 1.0, 0.4, 0], "f", "VEC3", 3)
hop_times = add([0.0, 2.0], "f", "SCALAR", 2, minmax=([0.0], [2.0]))
cube_scale = add([0, 0, 0, 1, 1, 1, 0, 0.5, 0,   0, -0.5, 0, 1, 1, 1, 0, 0, 0], "f", "VEC3", 6)
turn = []
for deg in (0, 90, 180):
    h = math.radians(deg) / 2
    turn += [0.0, math.sin(h), 0.0, math.cos(h)]
cube_rotation = add(turn, "f", "VEC4", 3)
# Camera look-down: a fixed rotation of -12 degrees about +X.
tilt = math.radians(-12) / 2

doc = {
    "asset": {"version": "2.0", "generator": "nerfpt scripts/make_shot_scene.py"},
    "scene": 0,
    "scenes": [{"nodes": [0, 1, 2, 4], "extras": {"width": 64, "height": 48, "spp": 16, "max_depth": 4,
                                               "fps": fps}}],
    "nodes": [
        {"name": "floor", "mesh": 0},
        {"name": "cube", "mesh": 1, "translation": [-1.0, 0.4, 0]},
        {"name": "panel", "mesh": 2},
        {"name": "camera", "camera": 0, "translation": [0, 1.2, 4.5],
         "rotation": [math.sin(tilt), 0, 0, math.cos(tilt)]},
        {"name": "rig", "children": [3]},
    ],
    "meshes": [{"name": "floor", "primitives": [primitive(*floor, 0)]},
               {"name": "cube", "primitives": [primitive(*cube, 1)]},
               {"name": "panel", "primitives": [primitive(*panel, 2)]}],
    "materials": [
        {"name": "grey", "pbrMetallicRoughness": {"baseColorFactor": [0.6, 0.6, 0.6, 1], "metallicFactor": 0,
                                                  "roughnessFactor": 1}},
        {"name": "red", "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.15, 0.1, 1], "metallicFactor": 0,
                                                 "roughnessFactor": 0.5}},
        {"name": "light", "emissiveFactor": [1, 1, 1], "extensions": {"KHR_materials_emissive_strength":
                                                                    {"emissiveStrength": 4.0}}},
    ],
    "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.05}}],
    "extensionsUsed": ["KHR_materials_emissive_strength"],
    "animations": [{
        "name": "shot",
        "samplers": [
            {"input": times, "output": rig_rotation, "interpolation": "LINEAR"},
            {"input": times, "output": cam_translation, "interpolation": "LINEAR"},
            {"input": times, "output": cube_translation, "interpolation": "LINEAR"},
            {"input": hop_times, "output": cube_scale, "interpolation": "CUBICSPLINE"},
            {"input": times, "output": cube_rotation, "interpolation": "STEP"},
        ],
        "channels": [
            {"sampler": 0, "target": {"node": 4, "path": "rotation"}},
            {"sampler": 1, "target": {"node": 3, "path": "translation"}},
            {"sampler": 2, "target": {"node": 1, "path": "translation"}},
            {"sampler": 3, "target": {"node": 1, "path": "scale"}},
            {"sampler": 4, "target": {"node": 1, "path": "rotation"}},
        ],
    }],
}
doc["bufferViews"] = views
doc["accessors"] = accessors
doc["buffers"] = [{"byteLength": len(buf),
                   "uri": "data:application/octet-stream;base64," + base64.b64encode(bytes(buf)).decode()}]
out = sys.argv[1] if len(sys.argv) > 1 else "scenes/shot/scene.gltf"
with open(out, "w") as f:
    json.dump(doc, f, indent=1)
    f.write("\n")
