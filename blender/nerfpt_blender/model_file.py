"""Where a nerfpt model (.npt) sits in its training world, read from the model file's header.

Pure Python (no bpy). The file layout is docs/formats.md, "Model file": magic 'NPTNERF1', u32 version, then
sections (4-byte tag, u64 length, payload). Only 'SCEN' (f32 aabb_scale, 16 f64 world_to_model, row major) and
'OBJF' (the object frame's JSON) are read here; the parameter arrays are skipped, so reading a large model takes
no time. A model with an 'RLIT' section
(`nerfpt train --relightable`) is relightable.

Placement (docs/formats.md, "NeRF models queried directly"): the crop box (model space; default the model's box
0.5 -+ aabb_scale/2) maps axis by axis onto the volume cube's local box [-1, 1]^3, local x, y, z running along
the training world's x, y, z. The training world is the transforms.json cameras' space, Z up for NeRF-synthetic
data and for `nerfpt capture`, as in Blender. So a Blender object with no rotation, its location at the centre of
the crop box in the training world and its scale half the box's size there, shows the capture where its cameras
saw it.
"""

import json
import math
import struct

MAGIC = b"NPTNERF1"


class ModelFileError(Exception):
    pass


def _open_model(path):
    try:
        f = open(path, "rb")
    except OSError as e:
        raise ModelFileError(f"{path}: cannot open: {e.strerror or e}") from None
    head = f.read(12)
    if len(head) < 12 or head[:8] != MAGIC:
        f.close()
        raise ModelFileError(f"{path}: not a nerfpt model file")
    (version,) = struct.unpack("<I", head[8:])
    if version != 1:
        f.close()
        raise ModelFileError(f"{path}: unsupported model file version {version}")
    return f


def section_tags(path):
    """The tags of the model file's sections, in file order (payloads skipped, not checked)."""
    tags = []
    with _open_model(path) as f:
        size = f.seek(0, 2)
        pos = 12
        while pos < size:
            f.seek(pos)
            sec = f.read(12)
            if len(sec) < 12:
                raise ModelFileError(f"{path}: truncated (section header)")
            length = struct.unpack("<Q", sec[4:])[0]
            if pos + 12 + length > size:
                raise ModelFileError(f"{path}: truncated (section '{sec[:4].decode('latin-1')}')")
            tags.append(sec[:4].decode("latin-1"))
            pos += 12 + length
    return tags


def is_relightable(path):
    """Whether the model carries the intrinsic fields (section 'RLIT', docs/formats.md "Model file")."""
    return "RLIT" in section_tags(path)


def _section(path, tag):
    """The payload of the first section `tag` (bytes), or None."""
    with _open_model(path) as f:
        while True:
            sec = f.read(12)
            if len(sec) == 0:
                return None
            if len(sec) < 12:
                raise ModelFileError(f"{path}: truncated (section header)")
            length = struct.unpack("<Q", sec[4:])[0]
            if sec[:4] == tag:
                data = f.read(length)
                if len(data) < length:
                    raise ModelFileError(f"{path}: truncated (section '{tag.decode('latin-1')}')")
                return data
            f.seek(length, 1)


def object_frame(path):
    """The object frame `nerfpt capture` stores (section 'OBJF', docs/formats.md), or None when the model has
    none: {'object_to_world': 4 rows (object space, Z up -> the training world, a similarity), 'box': (min, max)
    in object space, 'metric': whether object units are metres}."""
    data = _section(path, b"OBJF")
    if data is None:
        return None
    where = f"{path}: section 'OBJF'"
    try:
        j = json.loads(data.decode("utf-8"))
        m = [float(v) for v in j["object_to_world"]]
        lo = [float(v) for v in j["box"]["min"]]
        hi = [float(v) for v in j["box"]["max"]]
        metric = bool(j.get("metric", False))
    except (ValueError, KeyError, TypeError, UnicodeDecodeError) as e:
        raise ModelFileError(f"{where}: not an object frame ({e})") from None
    if len(m) != 16 or len(lo) != 3 or len(hi) != 3 or not all(map(math.isfinite, m + lo + hi)):
        raise ModelFileError(f"{where}: object_to_world needs 16 numbers and the box 3 + 3, all finite")
    if not all(lo[a] < hi[a] for a in range(3)):
        raise ModelFileError(f"{where}: box: the minimum must be below the maximum on every axis")
    return {"object_to_world": [m[4 * r : 4 * r + 4] for r in range(4)], "box": (lo, hi), "metric": metric}


def _apply(rows, p):
    return [sum(rows[r][c] * p[c] for c in range(3)) + rows[r][3] for r in range(3)]


def object_crop(path, frame):
    """The crop (model space, ((x0, y0, z0), (x1, y1, z1))) that holds the object's box: the bounding box of its
    corners in model space, within the model's box."""
    aabb_scale, w2m = read_scene_section(path)
    lo, hi = frame["box"]
    corners = [
        _apply(w2m, _apply(frame["object_to_world"], (hi[0] if i & 1 else lo[0], hi[1] if i & 2 else lo[1],
                                                      hi[2] if i & 4 else lo[2])))
        for i in range(8)
    ]
    bmin, bmax = model_box(aabb_scale)
    cmin = tuple(max(bmin[a], min(c[a] for c in corners)) for a in range(3))
    cmax = tuple(min(bmax[a], max(c[a] for c in corners)) for a in range(3))
    if not all(cmin[a] < cmax[a] for a in range(3)):
        raise ModelFileError(f"{path}: the object's box lies outside the model's box")
    return cmin, cmax


def read_scene_section(path):
    """(aabb_scale, world_to_model as 4 rows of 4 floats). Raises ModelFileError with a one-line message."""
    with _open_model(path) as f:
        while True:
            sec = f.read(12)
            if len(sec) == 0:
                raise ModelFileError(f"{path}: missing section 'SCEN'")
            if len(sec) < 12:
                raise ModelFileError(f"{path}: truncated (section header)")
            tag, length = sec[:4], struct.unpack("<Q", sec[4:])[0]
            if tag == b"SCEN":
                if length != 4 + 16 * 8:
                    raise ModelFileError(f"{path}: corrupt section 'SCEN'")
                data = f.read(length)
                if len(data) < length:
                    raise ModelFileError(f"{path}: truncated (section 'SCEN')")
                aabb_scale = struct.unpack("<f", data[:4])[0]
                m = struct.unpack("<16d", data[4:])
                rows = [list(m[4 * r : 4 * r + 4]) for r in range(4)]
                if not aabb_scale > 0:
                    raise ModelFileError(f"{path}: aabb_scale {aabb_scale} must be positive")
                return aabb_scale, rows
            f.seek(length, 1)


def _solve_affine(rows, p):
    """x with rows[:3] @ (x, 1) = p (the inverse of an affine map, by Cramer's rule)."""
    a = [r[:3] for r in rows[:3]]
    b = [p[i] - rows[i][3] for i in range(3)]

    def det(m):
        return (
            m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
        )

    d = det(a)
    if abs(d) < 1e-30:
        raise ModelFileError("world_to_model is singular")
    x = []
    for c in range(3):
        m = [row[:] for row in a]
        for r in range(3):
            m[r][c] = b[r]
        x.append(det(m) / d)
    return x


def model_box(aabb_scale):
    h = 0.5 * aabb_scale
    return (0.5 - h,) * 3, (0.5 + h,) * 3


def placement(path, crop=None):
    """Centre and half size (per world axis) of the crop box in the training world: the Blender object's
    location and scale. crop: ((x0, y0, z0), (x1, y1, z1)) in model space, or None for the model's box."""
    aabb_scale, rows = read_scene_section(path)
    lo, hi = crop if crop else model_box(aabb_scale)
    bmin, bmax = model_box(aabb_scale)
    for a in range(3):
        if not lo[a] < hi[a]:
            raise ModelFileError(f"crop: the minimum must be below the maximum on every axis ({'xyz'[a]})")
        if lo[a] < bmin[a] - 1e-6 or hi[a] > bmax[a] + 1e-6:
            raise ModelFileError(
                f"crop must lie inside the model's box {bmin[0]:g},{bmin[1]:g},{bmin[2]:g} .. "
                f"{bmax[0]:g},{bmax[1]:g},{bmax[2]:g}"
            )
    corners = [
        _solve_affine(rows, (hi[0] if i & 1 else lo[0], hi[1] if i & 2 else lo[1], hi[2] if i & 4 else lo[2]))
        for i in range(8)
    ]
    wmin = [min(c[a] for c in corners) for a in range(3)]
    wmax = [max(c[a] for c in corners) for a in range(3)]
    centre = tuple(0.5 * (wmin[a] + wmax[a]) for a in range(3))
    half = tuple(0.5 * (wmax[a] - wmin[a]) for a in range(3))
    return {"aabb_scale": aabb_scale, "centre": centre, "half_size": half}
