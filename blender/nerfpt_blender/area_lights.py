"""Blender area lights as nerfpt emitters (glTF has no area lights): a one-sided emissive polygon in the light's
place, facing the light's -Z, with the radiance Cycles gives the light. Plain data, no bpy (testable alone).

Cycles 3.4's convention, measured (docs/blender.md, "Area lights"): an area light of power P watts and colour c
emits radiance L = c P / (4 A) towards its -Z side, A being its area in the world (the light's size times the
object's scale along its local x and y; pi/4 of the bounding rectangle for a disc or an ellipse). That is pi/4
of P / (pi A), the radiance whose emitted flux would be P.
"""

import math

from . import gltf_post

ROUND_SEGMENTS = 64  # a disc or an ellipse: area-preserving polygon of this many sides (fan around the centre)
FULL_SPREAD = math.pi  # Lambertian emission; narrower spreads cannot be carried by a glTF emitter


def outline(shape, size_x, size_y, segments=ROUND_SEGMENTS):
    """The light's outline in its local xy plane, counter-clockwise seen from +Z, centred on the origin.
    SQUARE and DISK use size_x for both sides. A round outline's polygon has the ellipse's area (its vertices
    lie slightly outside the ellipse), so that the emitted power is the light's."""
    if shape in ("SQUARE", "DISK"):
        size_y = size_x
    hx, hy = 0.5 * size_x, 0.5 * size_y
    if shape in ("SQUARE", "RECTANGLE"):
        return [(-hx, -hy), (hx, -hy), (hx, hy), (-hx, hy)]
    grow = math.sqrt(2.0 * math.pi / (segments * math.sin(2.0 * math.pi / segments)))
    return [
        (grow * hx * math.cos(2.0 * math.pi * i / segments), grow * hy * math.sin(2.0 * math.pi * i / segments))
        for i in range(segments)
    ]


def cycles_area(shape, size_x, size_y, world):
    """The area Cycles divides the power by: the sizes times the lengths of the world matrix's x and y columns
    (world: 4 rows), times pi/4 for round shapes."""
    if shape in ("SQUARE", "DISK"):
        size_y = size_x
    sx = math.sqrt(sum(world[r][0] ** 2 for r in range(3)))
    sy = math.sqrt(sum(world[r][1] ** 2 for r in range(3)))
    area = size_x * sx * size_y * sy
    return area * math.pi / 4.0 if shape in ("DISK", "ELLIPSE") else area


def radiance(color, power, area):
    """Cycles' emitted radiance per channel (see the module's docstring)."""
    return [float(c) * power / (4.0 * area) for c in color[:3]]


def _transform(world, p):
    return [sum(world[r][k] * p[k] for k in range(3)) + world[r][3] for r in range(3)]


def emitter_mesh(shape, size_x, size_y, world, segments=ROUND_SEGMENTS):
    """(positions in Blender world space, triangles) of the light's polygon, wound so that its normal points
    along the light's world -Z (Cycles' emission direction: minus the world matrix's z column)."""
    ring = [_transform(world, (x, y, 0.0)) for x, y in outline(shape, size_x, size_y, segments)]
    if len(ring) == 4:
        positions, triangles = ring, [(0, 2, 1), (0, 3, 2)]
    else:
        positions = [_transform(world, (0.0, 0.0, 0.0))] + ring
        n = len(ring)
        triangles = [(0, 1 + (i + 1) % n, 1 + i) for i in range(n)]
    down = [-world[r][2] for r in range(3)]
    p0, p1, p2 = (positions[i] for i in triangles[0])
    e1 = [p1[k] - p0[k] for k in range(3)]
    e2 = [p2[k] - p0[k] for k in range(3)]
    normal = [e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]]
    if sum(normal[k] * down[k] for k in range(3)) < 0.0:  # a mirroring world matrix
        triangles = [(a, c, b) for a, b, c in triangles]
    return positions, triangles


def add_emitters(gltf, lights, bin_uri):
    """Adds one node, mesh and one-sided emissive material per light: {'name', 'shape', 'size_x', 'size_y',
    'world' (4 rows, Blender), 'color', 'power'}. Returns the bytes bin_uri must hold (b'' when none)."""
    if not lights:
        return b""
    buffers = gltf.setdefault("buffers", [])
    materials = gltf.setdefault("materials", [])
    nodes = gltf.setdefault("nodes", [])
    buffer_index = len(buffers)
    data = bytearray()
    for light in lights:
        area = cycles_area(light["shape"], light["size_x"], light["size_y"], light["world"])
        positions, triangles = emitter_mesh(light["shape"], light["size_x"], light["size_y"], light["world"])
        material = gltf_post.emitter(radiance(light["color"], light["power"], area), 1.0)
        material["name"] = light["name"] + " (nerfpt area light)"
        material["doubleSided"] = False  # Cycles' area lights emit on their -Z side only
        materials.append(material)
        for ext in material["extensions"]:
            gltf_post.use_extension(gltf, ext)
        mesh = gltf_post.append_mesh(
            gltf,
            data,
            buffer_index,
            light["name"] + " (nerfpt area light)",
            [gltf_post.to_gltf_point(p) for p in positions],
            triangles,
            len(materials) - 1,
        )
        nodes.append({"name": light["name"], "mesh": mesh})
        gltf_post.scene_of(gltf).setdefault("nodes", []).append(len(nodes) - 1)
    buffers.append({"byteLength": len(data), "uri": bin_uri})
    return bytes(data)
