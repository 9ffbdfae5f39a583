#!/usr/bin/env python3
"""Camera-path jumps of a COLMAP binary model (images in name order): python3 scripts/colmap_path_jumps.py SPARSE_FOLDER.
The same rule as nerfpt poses (capture/path_continuity.h): a step over 8x the median step is a jump."""
import struct, sys, numpy as np
def read_images(path):
    out = {}
    with open(path, 'rb') as f:
        n, = struct.unpack('<Q', f.read(8))
        for _ in range(n):
            iid, = struct.unpack('<i', f.read(4))
            q = struct.unpack('<4d', f.read(32)); t = struct.unpack('<3d', f.read(24))
            cid, = struct.unpack('<i', f.read(4))
            name = b''
            while True:
                c = f.read(1)
                if c == b'\0': break
                name += c
            np2, = struct.unpack('<Q', f.read(8)); f.read(24 * np2)
            w, x, y, z = q
            R = np.array([[1-2*(y*y+z*z), 2*(x*y-w*z), 2*(x*z+w*y)],
                          [2*(x*y+w*z), 1-2*(x*x+z*z), 2*(y*z-w*x)],
                          [2*(x*z-w*y), 2*(y*z+w*x), 1-2*(x*x+y*y)]])
            out[name.decode()] = -R.T @ np.array(t)
    return out
imgs = read_images(sys.argv[1] + '/images.bin')
names = sorted(imgs)
C = np.array([imgs[n] for n in names])
steps = np.linalg.norm(np.diff(C, axis=0), axis=1)
med = np.median(steps)
spread = np.sqrt(((C - C.mean(0))**2).sum(1).mean())
print(f"{len(names)} images, median step {med:.4f}, trajectory rms {spread:.3f}, max step {steps.max():.4f} ({steps.max()/med:.1f}x median)")
for i in np.where(steps > 8 * med)[0]:
    print(f"  jump {names[i]} -> {names[i+1]}: {steps[i]:.3f} ({steps[i]/med:.1f}x)")
