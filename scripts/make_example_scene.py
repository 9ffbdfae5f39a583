#!/usr/bin/env python3
"""Writes scenes/example/scene.gltf: the example scene that scripts/demo.sh renders.

A small room (checkered floor, grey back wall, red left and green right walls, ceiling) lit by an emissive quad
under the ceiling and a spot light, holding a rough metal sphere, a glass sphere, a diffuse box and a `volume`
cube filled with a raw instant-ngp-style grid (a glowing cloud, where a captured NeRF will sit). Python standard library only; the output is deterministic, so
re-running it gives a byte-identical file. glTF conventions: +Y up, metres, counter-clockwise front faces
(here all facing into the room or out of the objects), cameras look down their local -Z.

Usage: scripts/make_example_scene.py [OUTPUT]   (default: scenes/example/scene.gltf beside this script's repo)
"""
import base64
import json
import math
import os
import struct
import sys
import zlib

CLOUD_N = 32
CLOUD_FILE = "%dx%dx%d_cloud.bin" % (CLOUD_N, CLOUD_N, CLOUD_N)


def cloud_grid(n=CLOUD_N):
    """A glowing cloud as instant-ngp writes raw grids: float32 R, G, B (sRGB), sigma per voxel, x fastest, the
    first row at the TOP (y flipped). sigma is in instant-ngp units (per unit cube; nerfpt divides by the cube's
    longest world side), peaking near 20, so the core is opaque and the rim translucent."""
    out = bytearray()
    for k in range(n):
        for jr in range(n):
            j = n - 1 - jr  # y flipped: file row 0 is the top
            for i in range(n):
                x, y, z = [2.0 * (c + 0.5) / n - 1.0 for c in (i, j, k)]
                r = math.sqrt(x * x + y * y + z * z)
                wobble = 0.12 * math.sin(5.0 * x + 1.3) * math.sin(4.0 * y + 0.7) * math.sin(6.0 * z + 2.1)
                shell = max(0.0, 1.0 - (r + wobble) / 0.85)
                sigma = 20.0 * shell ** 1.5
                h = 0.5 * (y + 1.0)
                rgb = (0.95 - 0.6 * h, 0.45 + 0.3 * h, 0.15 + 0.8 * h)
                out += struct.pack("<4f", *rgb, sigma)
    return bytes(out)


class Builder:
    """Collects binary data, buffer views and accessors for one embedded buffer."""

    def __init__(self):
        self.data = bytearray()
        self.views = []
        self.accessors = []

    def _view(self, payload, target):
        while len(self.data) % 4:
            self.data.append(0)
        self.views.append({"buffer": 0, "byteOffset": len(self.data), "byteLength": len(payload), "target": target})
        self.data += payload
        return len(self.views) - 1

    def floats(self, rows, kind):
        flat = [c for r in rows for c in r]
        view = self._view(struct.pack("<%df" % len(flat), *flat), 34962)
        acc = {"bufferView": view, "componentType": 5126, "count": len(rows), "type": kind}
        if kind == "VEC3":  # POSITION needs min/max (glTF 2.0 §3.6.2.4); harmless for the others
            acc["min"] = [min(r[i] for r in rows) for i in range(3)]
            acc["max"] = [max(r[i] for r in rows) for i in range(3)]
        self.accessors.append(acc)
        return len(self.accessors) - 1

    def indices(self, idx):
        view = self._view(struct.pack("<%dH" % len(idx), *idx), 34963)
        self.accessors.append({"bufferView": view, "componentType": 5123, "count": len(idx), "type": "SCALAR"})
        return len(self.accessors) - 1


def sub(a, b):
    return [a[i] - b[i] for i in range(3)]


def cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def normalize(v):
    n = math.sqrt(sum(c * c for c in v))
    return [c / n for c in v]


def quad(origin, u, v, uv_scale=1.0):
    """Quad origin, origin+u, origin+u+v, origin+v; its front face (CCW) is the side cross(u, v) points to."""
    p = [origin, [origin[i] + u[i] for i in range(3)], [origin[i] + u[i] + v[i] for i in range(3)],
         [origin[i] + v[i] for i in range(3)]]
    n = normalize(cross(u, v))
    uvs = [[0, 0], [uv_scale, 0], [uv_scale, uv_scale], [0, uv_scale]]
    return p, [n] * 4, uvs, [0, 1, 2, 0, 2, 3]


def box(half):
    """Axis-aligned cube of half-size `half` centred at the origin, faces pointing outwards."""
    pos, nor, uvs, idx = [], [], [], []
    h = half
    faces = [  # (origin, u, v) with cross(u, v) = the outward normal
        ([h, -h, h], [0, 0, -2 * h], [0, 2 * h, 0]),    # +X
        ([-h, -h, -h], [0, 0, 2 * h], [0, 2 * h, 0]),   # -X
        ([-h, h, h], [2 * h, 0, 0], [0, 0, -2 * h]),    # +Y
        ([-h, -h, -h], [2 * h, 0, 0], [0, 0, 2 * h]),   # -Y
        ([-h, -h, h], [2 * h, 0, 0], [0, 2 * h, 0]),    # +Z
        ([h, -h, -h], [-2 * h, 0, 0], [0, 2 * h, 0]),   # -Z
    ]
    for o, u, v in faces:
        p, n, t, i = quad(o, u, v)
        centre_to_face = [o[k] + 0.5 * (u[k] + v[k]) for k in range(3)]
        assert sum(n[0][k] * centre_to_face[k] for k in range(3)) > 0, "box face points inwards"
        base = len(pos)
        pos += p
        nor += n
        uvs += t
        idx += [base + k for k in i]
    return pos, nor, uvs, idx


def sphere(radius, rings=24, segments=48):
    """UV sphere with smooth normals; triangles wound CCW seen from outside."""
    pos, nor, uvs, idx = [], [], [], []
    for r in range(rings + 1):
        theta = math.pi * r / rings
        for s in range(segments + 1):
            phi = 2 * math.pi * s / segments
            n = [math.sin(theta) * math.sin(phi), math.cos(theta), math.sin(theta) * math.cos(phi)]
            pos.append([radius * c for c in n])
            nor.append(n)
            uvs.append([s / segments, r / rings])
    row = segments + 1
    for r in range(rings):
        for s in range(segments):
            a, b = r * row + s, (r + 1) * row + s
            if r > 0:
                idx += [a, b, a + 1]
            if r < rings - 1:
                idx += [a + 1, b, b + 1]
    # Check the winding on one triangle: its geometric normal must agree with the outward normal.
    t = idx[3:6] if len(idx) > 6 else idx[:3]
    g = cross(sub(pos[t[1]], pos[t[0]]), sub(pos[t[2]], pos[t[0]]))
    assert sum(g[k] * pos[t[0]][k] for k in range(3)) > 0, "sphere winding is clockwise"
    return pos, nor, uvs, idx


def checker_png(size=64, checks=8):
    """An RGB PNG of a two-tone checkerboard, encoded by hand (zlib + CRC chunks)."""
    cell = size // checks
    rows = bytearray()
    for y in range(size):
        rows.append(0)  # filter type: none
        for x in range(size):
            v = 200 if ((x // cell) + (y // cell)) % 2 == 0 else 70
            rows += bytes((v, v, v))

    def chunk(kind, payload):
        return struct.pack(">I", len(payload)) + kind + payload + struct.pack(">I", zlib.crc32(kind + payload))

    header = struct.pack(">IIBBBBB", size, size, 8, 2, 0, 0, 0)  # 8-bit RGB
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(bytes(rows), 9)) + \
        chunk(b"IEND", b"")


def quat_from_minus_z(direction):
    """Rotation taking the node's -Z (where glTF lights and cameras point) onto `direction`."""
    d = normalize(direction)
    f = [0.0, 0.0, -1.0]
    axis = cross(f, d)
    s = math.sqrt(sum(c * c for c in axis))
    angle = math.atan2(s, sum(f[i] * d[i] for i in range(3)))
    if s < 1e-9:
        return [0.0, 0.0, 0.0, 1.0] if angle < 1 else [1.0, 0.0, 0.0, 0.0]
    axis = [c / s for c in axis]
    h = math.sin(angle / 2)
    return [axis[0] * h, axis[1] * h, axis[2] * h, math.cos(angle / 2)]


def rnd(v):
    return [round(c, 6) for c in v]


def main():
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(root, "scenes", "example", "scene.gltf")
    b = Builder()

    def pbr(name, color, metallic=0.0, roughness=1.0, **extra):
        m = {"name": name, "pbrMetallicRoughness": {"baseColorFactor": color + [1.0], "metallicFactor": metallic,
                                                    "roughnessFactor": roughness}}
        m.update(extra)
        return m

    materials = [
        pbr("floor", [1.0, 1.0, 1.0], roughness=0.8),
        pbr("back_wall", [0.75, 0.75, 0.72]),
        pbr("red_wall", [0.63, 0.07, 0.05]),
        pbr("green_wall", [0.12, 0.48, 0.10]),
        pbr("ceiling", [0.8, 0.8, 0.8]),
        pbr("light", [0.0, 0.0, 0.0], emissiveFactor=[1.0, 0.85, 0.7],
            extensions={"KHR_materials_emissive_strength": {"emissiveStrength": 12.0}}),
        pbr("rough_metal", [0.92, 0.78, 0.55], metallic=1.0, roughness=0.35),
        pbr("glass", [1.0, 1.0, 1.0], roughness=0.0,
            extensions={"KHR_materials_transmission": {"transmissionFactor": 1.0}, "KHR_materials_ior": {"ior": 1.5}}),
        pbr("box", [0.8, 0.55, 0.25], roughness=0.9),
        pbr("volume", [1.0, 1.0, 1.0]),
    ]
    materials[0]["pbrMetallicRoughness"]["baseColorTexture"] = {"index": 0}
    mat = {m["name"]: i for i, m in enumerate(materials)}

    meshes, nodes = [], []

    def add_mesh(name, geometry, material, node_extra=None, shared=None):
        if shared is None:
            pos, nor, uvs, idx = geometry
            shared = {"POSITION": b.floats(pos, "VEC3"), "NORMAL": b.floats(nor, "VEC3"),
                      "TEXCOORD_0": b.floats(uvs, "VEC2")}, b.indices(idx)
        attrs, indices = shared
        meshes.append({"name": name, "primitives": [{"attributes": attrs, "indices": indices,
                                                      "material": mat[material], "mode": 4}]})
        node = {"name": name, "mesh": len(meshes) - 1}
        node.update(node_extra or {})
        nodes.append(node)
        return shared

    # The room: x in [-2, 2], y in [0, 3], z in [-2, 3]; open at z = 3 where the camera stands. Every quad must
    # face the inside of the room (the light faces down), which is checked against the room's centre.
    room = [
        ("floor", quad([-2, 0, -2], [0, 0, 5], [4, 0, 0], uv_scale=4.0), "floor"),
        ("back_wall", quad([-2, 0, -2], [4, 0, 0], [0, 3, 0]), "back_wall"),
        ("left_wall", quad([-2, 0, -2], [0, 3, 0], [0, 0, 5]), "red_wall"),
        ("right_wall", quad([2, 0, -2], [0, 0, 5], [0, 3, 0]), "green_wall"),
        ("ceiling", quad([-2, 3, -2], [4, 0, 0], [0, 0, 5]), "ceiling"),
        ("area_light", quad([-0.5, 2.98, -0.5], [1, 0, 0], [0, 0, 1]), "light"),
    ]
    for name, geometry, material in room:
        to_centre = sub([0.0, 1.5, 0.5], geometry[0][0])
        assert sum(geometry[1][0][k] * to_centre[k] for k in range(3)) > 0, name + " faces out of the room"
        add_mesh(name, geometry, material)
    ball = add_mesh("metal_sphere", sphere(1.0), "rough_metal",
                    {"translation": [-0.75, 0.6, -0.8], "scale": [0.6, 0.6, 0.6]})
    add_mesh("glass_sphere", None, "glass", {"translation": [0.7, 0.5, 0.0], "scale": [0.5, 0.5, 0.5]},
             shared=ball)
    yaw = math.radians(25)
    add_mesh("box", box(0.35), "box",
             {"translation": [0.45, 0.35, -1.45], "rotation": [0.0, math.sin(yaw / 2), 0.0, math.cos(yaw / 2)]})
    add_mesh("nerf_volume", box(1.0), "volume",
             {"translation": [-0.1, 0.36, 0.6], "scale": [0.35, 0.35, 0.35],
              "extras": {"volume": {"file": CLOUD_FILE, "density_scale": 1.0, "emission_scale": 2.5}}})

    spot_pos = [1.3, 2.7, 1.4]
    spot_target = [0.7, 0.5, 0.0]
    nodes.append({"name": "spot", "translation": spot_pos,
                  "rotation": rnd(quat_from_minus_z(sub(spot_target, spot_pos))),
                  "extensions": {"KHR_lights_punctual": {"light": 0}}})
    nodes.append({"name": "camera", "translation": [0.0, 1.55, 2.95],
                  "rotation": rnd([math.sin(math.radians(-11) / 2), 0.0, 0.0, math.cos(math.radians(-11) / 2)]),
                  "camera": 0})

    image_uri = "data:image/png;base64," + base64.b64encode(checker_png()).decode("ascii")
    gltf = {
        "asset": {"version": "2.0", "generator": "nerfpt scripts/make_example_scene.py"},
        "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_emissive_strength", "KHR_materials_transmission",
                           "KHR_materials_ior"],
        "scene": 0,
        "scenes": [{"name": "example", "nodes": list(range(len(nodes))),
                    "extras": {"width": 640, "height": 480, "spp": 32, "max_depth": 12,
                               "background": [0.02, 0.02, 0.03]}}],
        "nodes": nodes,
        "meshes": meshes,
        "materials": materials,
        "textures": [{"source": 0, "sampler": 0}],
        "samplers": [{"magFilter": 9729, "minFilter": 9987, "wrapS": 10497, "wrapT": 10497}],
        "images": [{"name": "checker", "uri": image_uri}],
        "cameras": [{"name": "main", "type": "perspective",
                     "perspective": {"yfov": 0.8, "aspectRatio": 640 / 480, "znear": 0.05}}],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"name": "spot", "type": "spot", "color": [1.0, 0.95, 0.85], "intensity": 12.0,
             "spot": {"innerConeAngle": 0.25, "outerConeAngle": 0.45}}]}},
        "accessors": b.accessors,
        "bufferViews": b.views,
        "buffers": [{"byteLength": len(b.data),
                     "uri": "data:application/octet-stream;base64," + base64.b64encode(bytes(b.data)).decode("ascii")}],
    }
    os.makedirs(os.path.dirname(os.path.abspath(out)), exist_ok=True)
    with open(out, "w", encoding="utf-8") as f:
        json.dump(gltf, f, indent=1)
        f.write("\n")
    print("wrote %s (%d bytes)" % (out, os.path.getsize(out)))
    cloud = os.path.join(os.path.dirname(os.path.abspath(out)), CLOUD_FILE)
    with open(cloud, "wb") as f:
        f.write(cloud_grid())
    print("wrote %s (%d bytes)" % (cloud, os.path.getsize(cloud)))


if __name__ == "__main__":
    main()
