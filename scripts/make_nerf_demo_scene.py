#!/usr/bin/env python3
"""Writes scenes/nerf_demo/scene.gltf: a Cornell box with a NeRF (a `volume` cube whose extras name
`lego.npt`, a nerfpt model trained on NeRF-synthetic lego) standing on a pedestal next to a mirror sphere.
The model file itself is written by scripts/demo.sh (trained briefly, or reused).

Placement (docs/formats.md, "NeRF models in a scene"): the cube's local box [-1, 1]^3 holds the model's crop box
with local axes = the training world's axes. lego's world is Z-up, so the cube is turned -90 degrees about X
(local +Z -> scene +Y) and yawed to show the model at an angle. With no crop the cube spans lego's whole
aabb (world +-0.5/0.33 = +-1.515); lego's lowest point is at world z ~ -0.35, i.e. local z = -0.35/1.515.

Usage: python3 scripts/make_nerf_demo_scene.py [OUT.gltf [VOLUME_FILE]] [--crop X0,Y0,Z0,X1,Y1,Z1]
           [--bottom LOCAL_Z] [--cube-scale S] [--yaw DEG]
VOLUME_FILE (default lego.npt, relative to OUT's folder) may also be a grid baked with `nerfpt bake`: grid
densities are per world unit, so the scene then sets density_scale = 1 / CUBE_SCALE to keep the baked object
as opaque as the model queried directly (whose sigma is per model unit, independent of the node's scale).
Another model (a capture) is placed with --crop (model space, the part of the model that fills the cube: the
object without its surroundings), --bottom (the object's lowest point in the cube's local z, -1..1, so that it
stands on the pedestal), --cube-scale and --yaw; or, when `nerfpt capture` found the object (the model
carries its object frame), with --object: no crop, the object's own box and base, standing on the pedestal's
top, scaled by --cube-scale (scene units per object unit: a metric capture's metres).
"""
import argparse
import base64
import json
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from make_example_scene import Builder, box, quad, rnd, sphere, sub  # noqa: E402

CUBE_SCALE = 0.55          # scene units per local unit
LEGO_BOTTOM_LOCAL = -0.35 / 1.515
PEDESTAL_HALF = [0.36, 0.14, 0.36]
PEDESTAL_AT = [-0.38, 0.0, -0.25]


def quat_mul(a, b):
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return [aw * bx + ax * bw + ay * bz - az * by, aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw, aw * bw - ax * bx - ay * by - az * bz]


def main():
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out", nargs="?", default=os.path.join(root, "out", "nerf_demo", "scene.gltf"))
    ap.add_argument("volume_file", nargs="?", default="lego.npt")
    ap.add_argument("--crop", help="X0,Y0,Z0,X1,Y1,Z1 in model space (default: the whole model)")
    ap.add_argument("--bottom", type=float, default=LEGO_BOTTOM_LOCAL, help="the object's lowest local z")
    ap.add_argument("--cube-scale", type=float, default=CUBE_SCALE, help="scene units per local unit")
    ap.add_argument("--yaw", type=float, default=-30.0, help="turn about the vertical, degrees")
    ap.add_argument("--object", action="store_true",
                    help="place a captured model by its object frame (\"placement\": \"object\") on the pedestal")
    args = ap.parse_args()
    if args.object and (args.crop or not args.volume_file.endswith(".npt")):
        ap.error("--object: a model file (.npt) with an object frame, and no --crop")
    out, volume_file, cube_scale = args.out, args.volume_file, args.cube_scale
    volume = {"file": volume_file}
    if args.crop:
        c = [float(v) for v in args.crop.split(",")]
        if len(c) != 6 or any(c[i] >= c[i + 3] for i in range(3)):
            ap.error("--crop: expected X0,Y0,Z0,X1,Y1,Z1 with X0 < X1, Y0 < Y1, Z0 < Z1")
        volume["crop"] = {"min": c[:3], "max": c[3:]}
    if not volume_file.endswith(".npt"):
        volume["density_scale"] = round(1.0 / cube_scale, 6)
    b = Builder()

    def pbr(name, color, metallic=0.0, roughness=1.0, **extra):
        m = {"name": name, "pbrMetallicRoughness": {"baseColorFactor": color + [1.0], "metallicFactor": metallic,
                                                    "roughnessFactor": roughness},
             "extensions": {"KHR_materials_specular": {"specularFactor": 0}}}
        m.update(extra)
        return m

    materials = [  # the shared Cornell scene's colours
        pbr("white", [0.73, 0.73, 0.73]),
        pbr("red", [0.63, 0.065, 0.05]),
        pbr("green", [0.14, 0.45, 0.091]),
        pbr("lamp", [0.0, 0.0, 0.0], emissiveFactor=[1.0, 0.85, 0.6]),
        {"name": "mirror", "pbrMetallicRoughness": {"baseColorFactor": [0.95, 0.95, 0.95, 1.0],
                                                    "metallicFactor": 1.0, "roughnessFactor": 0.0}},
        pbr("pedestal", [0.55, 0.55, 0.6], roughness=0.7),
        pbr("volume", [1.0, 1.0, 1.0]),
    ]
    materials[3]["extensions"]["KHR_materials_emissive_strength"] = {"emissiveStrength": 8.0}
    mat = {m["name"]: i for i, m in enumerate(materials)}
    meshes, nodes = [], []

    def add_mesh(name, geometry, material, node_extra=None):
        pos, nor, uvs, idx = geometry
        attrs = {"POSITION": b.floats(pos, "VEC3"), "NORMAL": b.floats(nor, "VEC3"),
                 "TEXCOORD_0": b.floats(uvs, "VEC2")}
        meshes.append({"name": name, "primitives": [{"attributes": attrs, "indices": b.indices(idx),
                                                      "material": mat[material], "mode": 4}]})
        node = {"name": name, "mesh": len(meshes) - 1}
        node.update(node_extra or {})
        nodes.append(node)

    # The room: x, z in [-1, 1], y in [0, 2], open at z = 1 towards the camera; quads face inwards.
    room = [
        ("floor", quad([-1, 0, -1], [0, 0, 2], [2, 0, 0]), "white"),
        ("back", quad([-1, 0, -1], [2, 0, 0], [0, 2, 0]), "white"),
        ("left", quad([-1, 0, -1], [0, 2, 0], [0, 0, 2]), "red"),
        ("right", quad([1, 0, -1], [0, 0, 2], [0, 2, 0]), "green"),
        ("ceiling", quad([-1, 2, -1], [2, 0, 0], [0, 0, 2]), "white"),
        ("lamp", quad([-0.4, 1.99, -0.4], [0.8, 0, 0], [0, 0, 0.8]), "lamp"),
    ]
    for name, geometry, material in room:
        to_centre = sub([0.0, 1.0, 0.0], geometry[0][0])
        assert sum(geometry[1][0][k] * to_centre[k] for k in range(3)) > 0, name + " faces out of the room"
        add_mesh(name, geometry, material)

    ped_top = PEDESTAL_AT[1] + 2 * PEDESTAL_HALF[1]
    add_mesh("pedestal", box(1.0), "pedestal",
             {"translation": [PEDESTAL_AT[0], PEDESTAL_HALF[1], PEDESTAL_AT[2]], "scale": PEDESTAL_HALF})
    add_mesh("mirror_sphere", sphere(1.0), "mirror", {"translation": [0.42, 0.3, 0.05], "scale": [0.3, 0.3, 0.3]})
    stand_up = [-math.sin(math.pi / 4), 0.0, 0.0, math.cos(math.pi / 4)]  # -90 degrees about X
    yaw = math.radians(args.yaw)
    rotation = quat_mul([0.0, math.sin(yaw / 2), 0.0, math.cos(yaw / 2)], stand_up)
    if args.object:
        # The cube's local space is the object frame, Y up, base centre at the origin: the node stands it on
        # the pedestal's top and turns it about the vertical.
        volume["placement"] = "object"
        add_mesh("captured_object", box(1.0), "volume",
                 {"translation": [PEDESTAL_AT[0], ped_top, PEDESTAL_AT[2]],
                  "rotation": rnd([0.0, math.sin(yaw / 2), 0.0, math.cos(yaw / 2)]), "scale": [cube_scale] * 3,
                  "extras": {"volume": volume}})
    else:
        add_mesh("lego", box(1.0), "volume",
                 {"translation": [PEDESTAL_AT[0], ped_top - args.bottom * cube_scale, PEDESTAL_AT[2]],
                  "rotation": rnd(rotation), "scale": [cube_scale] * 3,
                  "extras": {"volume": volume}})
    nodes.append({"name": "camera", "translation": [0.0, 1.0, 3.9], "camera": 0})

    gltf = {
        "asset": {"version": "2.0", "generator": "nerfpt scripts/make_nerf_demo_scene.py"},
        "extensionsUsed": ["KHR_materials_emissive_strength", "KHR_materials_specular"],
        "scene": 0,
        "scenes": [{"name": "nerf_demo", "nodes": list(range(len(nodes))),
                    "extras": {"width": 512, "height": 512, "spp": 64, "max_depth": 8}}],
        "nodes": nodes,
        "meshes": meshes,
        "materials": materials,
        "cameras": [{"name": "main", "type": "perspective",
                     "perspective": {"yfov": 0.6911, "aspectRatio": 1.0, "znear": 0.05}}],
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


if __name__ == "__main__":
    main()
