#!/usr/bin/env python3
"""Turns the NeRF demo scene (scripts/make_nerf_demo_scene.py) into a 48-frame shot for the shot benchmark
(bench/shot_gpu.sh, docs/benchmarks.md): the camera slides from left to right while it dollies in, turning to keep
the pedestal in view; everything else stays. One glTF animation, 24 fps, frames 1-48 (keys at F / 24 s, the
translation LINEAR, the rotation LINEAR = slerp between per-frame keys). The NeRF is still queried directly.

Usage: python3 scripts/make_nerf_demo_shot.py IN.gltf OUT.gltf   (OUT beside IN: the volume's path is relative)
"""
import base64
import json
import math
import struct
import sys

src, out = sys.argv[1], sys.argv[2]
with open(src, encoding="utf-8") as f:
    gltf = json.load(f)
cam = next(i for i, n in enumerate(gltf["nodes"]) if "camera" in n)
target = (0.0, 0.6, 0.0)  # the pedestal's top, about
times, trans, rots = [], [], []
for frame in range(1, 49):
    u = (frame - 1) / 47
    p = (-0.6 + 1.2 * u, 1.0 + 0.1 * u, 3.9 - 1.2 * u)
    dx, dy, dz = (target[0] - p[0], target[1] - p[1], target[2] - p[2])
    yaw = math.atan2(-dx, -dz)  # glTF cameras look along -Z
    pitch = math.atan2(dy, math.hypot(dx, dz))
    qy = (0.0, math.sin(yaw / 2), 0.0, math.cos(yaw / 2))
    qx = (math.sin(pitch / 2), 0.0, 0.0, math.cos(pitch / 2))
    # q = qy * qx (yaw, then pitch about the turned x axis)
    x1, y1, z1, w1 = qy
    x2, y2, z2, w2 = qx
    q = (w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2, w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
         w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2, w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2)
    times.append(frame / 24.0)
    trans += p
    rots += q
blob = struct.pack(f"<{len(times)}f", *times) + struct.pack(f"<{len(trans)}f", *trans) + struct.pack(f"<{len(rots)}f", *rots)
buffer = len(gltf["buffers"])
gltf["buffers"].append({"byteLength": len(blob),
                        "uri": "data:application/octet-stream;base64," + base64.b64encode(blob).decode("ascii")})
n = len(times)
views = gltf["bufferViews"]
accessors = gltf["accessors"]
first_view = len(views)
for offset, size in ((0, 4 * n), (4 * n, 12 * n), (16 * n, 16 * n)):
    views.append({"buffer": buffer, "byteOffset": offset, "byteLength": size})
accessors.append({"bufferView": first_view, "componentType": 5126, "count": n, "type": "SCALAR",
                  "min": [times[0]], "max": [times[-1]]})
accessors.append({"bufferView": first_view + 1, "componentType": 5126, "count": n, "type": "VEC3"})
accessors.append({"bufferView": first_view + 2, "componentType": 5126, "count": n, "type": "VEC4"})
a = len(accessors) - 3
gltf["animations"] = [{
    "name": "shot",
    "samplers": [{"input": a, "output": a + 1, "interpolation": "LINEAR"},
                 {"input": a, "output": a + 2, "interpolation": "LINEAR"}],
    "channels": [{"sampler": 0, "target": {"node": cam, "path": "translation"}},
                 {"sampler": 1, "target": {"node": cam, "path": "rotation"}}],
}]
gltf["scenes"][0].setdefault("extras", {})["fps"] = 24
with open(out, "w", encoding="utf-8") as f:
    json.dump(gltf, f, indent=1)
