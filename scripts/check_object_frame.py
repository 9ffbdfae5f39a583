#!/usr/bin/env python3
"""The object frame `nerfpt capture` found against a simulated capture's ground truth (issue 25).

    nerfpt pose-error WORKDIR/transforms.json TRUTH_DIR/truth.json --json WORKDIR/pose_error.json
    scripts/check_object_frame.py WORKDIR TRUTH_DIR/truth.json WORKDIR/pose_error.json

TRUTH_DIR comes from scripts/make_handheld_capture.py (truth.json's 'object': up, base centre, height in
Blender's world, metres). pose-error's similarity (reference = s R estimate + t) carries capture.json's object
into that world. Prints: up error (degrees), the base plane's offset at the true base centre and the height
error (both in % of the true height), the base centre's horizontal offset (mm), and the issue's pass/fail
(up within 2 degrees, the base plane within 1% of the height). No numpy: 3-vectors by hand.
"""
import json, math, sys


def mat_vec(m, v):
    return [sum(m[r][c] * v[c] for c in range(3)) for r in range(3)]


def sub(a, b):
    return [a[i] - b[i] for i in range(3)]


def dot(a, b):
    return sum(a[i] * b[i] for i in range(3))


def main():
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    work, truth_path, pe_path = sys.argv[1:]
    obj = json.load(open(f'{work}/capture.json'))['stages']['object']
    truth = json.load(open(truth_path))['object']
    sim = json.load(open(pe_path))['similarity']
    s, R, t = sim['scale'], sim['rotation'], sim['translation']
    if not obj.get('found'):
        print(f'object not found: {obj.get("reason")}')
        return 1
    up = mat_vec(R, obj['up'])
    base = [s * x + t[i] for i, x in enumerate(mat_vec(R, obj['base_center']))]
    height = s * obj['height']
    tu = truth['up']
    up_err = math.degrees(math.acos(max(-1.0, min(1.0, dot(up, tu) / math.sqrt(dot(up, up) * dot(tu, tu))))))
    th = truth['height']
    plane_off = dot(sub(truth['base_center'], base), up)  # the true base centre above (+) the found plane
    d = sub(base, truth['base_center'])
    horiz = math.sqrt(max(0.0, dot(d, d) - dot(d, tu) ** 2))
    box = obj['box']
    size = [s * (box['max'][i] - box['min'][i]) for i in range(3)]
    tsize = [truth['box_max'][i] - truth['box_min'][i] for i in range(3)]
    ok = up_err <= 2.0 and abs(plane_off) <= 0.01 * th
    sparse = obj.get('sparse')
    first = f'first box height {1000 * s * sparse["height"]:.1f} mm, ' if sparse else ''
    print(f'{truth.get("kind", "?")}: up {up_err:.2f} deg, base plane {100 * plane_off / th:+.2f}% of the height '
          f'({1000 * plane_off:+.1f} mm), height {1000 * height:.1f} mm vs {1000 * th:.1f} '
          f'({100 * (height - th) / th:+.1f}%; {first}{"dense" if obj.get("dense", {}).get("found") else "sparse"}), base centre {1000 * horiz:.1f} mm off, box '
          f'{" x ".join(f"{1000 * x:.0f}" for x in size)} mm (object {" x ".join(f"{1000 * x:.0f}" for x in tsize)}), '
          f'{obj["plane_inliers"]} plane points, {obj["seed_points"]} object points: '
          f'{"PASS" if ok else "FAIL"} (up <= 2 deg, plane <= 1%)')
    return 0 if ok else 1


if __name__ == '__main__':
    sys.exit(main())
