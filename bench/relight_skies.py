#!/usr/bin/env python3
"""The linear skies of a relight data set (../shared/data/relight, make_relight.py layout) for nerfpt's renders.

    relight_skies.py DATA OUT_DIR   -> OUT_DIR/LIGHT.exr for every lighting of DATA/lights.json, one line each

Why: the data set's `env.exr` files are meant to be the lighting's sky in linear radiance (its README), the sky
Cycles rendered the ground truth with (a ramp over z = sin(elevation) through `lights.json`'s `stops`). The dev set
made by make_relight.py holds them sRGB-encoded instead (Blender's image save applied the display transform: the
file equals sRGB(stops) to 1e-6), about 3-5x too bright in the dim skies: the room's walls rendered 1.6-1.8x too
bright and the sunset's shadows filled with blue. So the sky is rebuilt here from the stops with make_relight.py's
own formula (equirect 256x128, nerfpt's convention: row 0 is +Y, v = acos(d.y)/pi, azimuth-independent), and the
file is checked against it: linear (used as it is), sRGB-encoded (replaced, with a warning) or neither (the file
is used, with a warning). Numpy only (OpenImageIO or scripts/exr_shim to read; the EXR is written here).
"""
import json
import os
import struct
import sys

import numpy as np
import OpenImageIO as oiio  # scripts/exr_shim on the GPU machine


def sky(stops, width=256, height=128):
    v = (np.arange(height) + 0.5) / height
    z = np.cos(np.pi * v)
    zs = np.array([s[0] for s in stops], float)
    cs = np.array([s[1] for s in stops], float)
    rows = np.stack([np.interp(z, zs, cs[:, k]) for k in range(3)], axis=-1)
    return np.repeat(rows[:, None, :], width, axis=1).astype(np.float32)


def read_rgb(path):
    inp = oiio.ImageInput.open(path)
    if inp is None:
        raise SystemExit('%s: cannot read: %s' % (path, oiio.geterror()))
    spec = inp.spec()
    px = np.asarray(inp.read_image(0, 0, 0, spec.nchannels, 'float'), np.float32)
    inp.close()
    return px.reshape(spec.height, spec.width, spec.nchannels)[..., :3]


def srgb(x):
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(np.maximum(x, 0), 1 / 2.4) - 0.055)


def write_exr(path, rgb):
    """A scanline OpenEXR, uncompressed FLOAT channels B, G, R (alphabetical, as the format wants)."""
    h, w, _ = rgb.shape

    def attr(name, kind, data):
        return name.encode() + b'\0' + kind.encode() + b'\0' + struct.pack('<i', len(data)) + data

    chlist = b''.join(c.encode() + b'\0' + struct.pack('<iBBBBii', 2, 0, 0, 0, 0, 1, 1) for c in 'BGR') + b'\0'
    box = struct.pack('<iiii', 0, 0, w - 1, h - 1)
    header = (struct.pack('<ii', 20000630, 2) + attr('channels', 'chlist', chlist) +
              attr('compression', 'compression', b'\0') + attr('dataWindow', 'box2i', box) +
              attr('displayWindow', 'box2i', box) + attr('lineOrder', 'lineOrder', b'\0') +
              attr('pixelAspectRatio', 'float', struct.pack('<f', 1.0)) +
              attr('screenWindowCenter', 'v2f', struct.pack('<ff', 0, 0)) +
              attr('screenWindowWidth', 'float', struct.pack('<f', 1.0)) + b'\0')
    line_bytes = 8 + 3 * 4 * w
    first = len(header) + 8 * h
    offsets = struct.pack('<%dQ' % h, *[first + y * line_bytes for y in range(h)])
    lines = b''.join(struct.pack('<ii', y, 3 * 4 * w) + rgb[y, :, ::-1].T.astype('<f4').tobytes() for y in range(h))
    tmp = path + '.tmp'
    with open(tmp, 'wb') as f:
        f.write(header + offsets + lines)
    os.replace(tmp, path)


def main():
    if len(sys.argv) != 3:
        raise SystemExit('usage: relight_skies.py DATA OUT_DIR')
    data, out = sys.argv[1:3]
    lights = json.load(open(os.path.join(data, 'lights.json')))
    os.makedirs(out, exist_ok=True)
    for name, light in lights.items():
        path = os.path.join(data, light['env']) if light.get('env') else None
        target = os.path.join(out, name + '.exr')
        if 'stops' not in light:
            print('%s: no stops in lights.json: the sky is %s as it is' % (name, path))
            write_exr(target, read_rgb(path))
            continue
        linear = sky(light['stops'])
        if path is None or not os.path.exists(path):
            print('%s: no env file: the sky from its stops' % name)
        else:
            given = read_rgb(path)
            if given.shape != linear.shape:
                print('%s: warning: %s is %dx%d, not 256x128: using it as it is' % (
                    name, path, given.shape[1], given.shape[0]))
                write_exr(target, given)
                continue
            if np.abs(given - linear).max() < 1e-4:
                print('%s: %s is the linear sky of its stops' % (name, path))
            elif np.abs(given - srgb(linear)).max() < 1e-3:
                print('%s: warning: %s holds the sky sRGB-encoded (up to %.1fx too bright): the linear sky from '
                      'its stops instead' % (name, path, float((given / np.maximum(linear, 1e-6)).max())))
            else:
                print('%s: warning: %s matches neither its stops nor their sRGB encoding: using it as it is' % (
                    name, path))
                linear = given
        write_exr(target, linear)


if __name__ == '__main__':
    main()
