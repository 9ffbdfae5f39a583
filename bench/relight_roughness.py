#!/usr/bin/env python3
"""The fitted roughness of a relightable model on the test views: percentiles over the object's pixels of the
roughness_N.exr that bench/relight_fields writes (PRED/aov): the pixels it fitted (roughness >= 0.05; 0 where
no event was found).
Usage: relight_roughness.py PRED_DIR [LABEL]   (OpenImageIO, or scripts/exr_shim on PYTHONPATH)"""
import glob, os, sys
import numpy as np
import OpenImageIO as oiio


def read(path):
    inp = oiio.ImageInput.open(path)
    if inp is None:
        sys.exit(f"relight_roughness: {path}: cannot read")
    spec = inp.spec()
    px = inp.read_image(0, 0, 0, spec.nchannels, 'float')
    inp.close()
    return np.asarray(px, np.float32).reshape(spec.height, spec.width, spec.nchannels)


pred = sys.argv[1]
label = sys.argv[2] if len(sys.argv) > 2 else pred
values = []
for path in sorted(glob.glob(os.path.join(pred, 'aov', 'roughness_*.exr'))):
    r = read(path)[..., 0]
    values.append(r[r > 0])
if not values:
    sys.exit(f"relight_roughness: no roughness_N.exr under {pred}/aov")
v = np.concatenate(values)
p = np.percentile(v, [5, 25, 50, 75, 95])
print(f"{label} roughness over {v.size} object pixels: 5/25/50/75/95th percentiles "
      + " / ".join(f"{x:.3f}" for x in p) + f", mean {v.mean():.3f}")
