"""A stand-in for OpenImageIO's ImageInput, for the GPU machine where neither OpenImageIO nor an OpenEXR-enabled
OpenCV can be installed: reads scanline OpenEXR files with NONE, ZIPS or ZIP compression and HALF/FLOAT/UINT
channels (what Blender and nerfpt write) with numpy and zlib, so that ../shared/data/relight/score.py runs there
unchanged (PYTHONPATH=scripts/exr_shim). Checked against the real OpenImageIO by scripts/exr_shim/check.py.
Channels come back in the file's order (alphabetical, as OpenEXR stores them) except that R, G, B, A (and X, Y, Z)
are put first in that order, as OpenImageIO does."""
import struct
import zlib

import numpy as np

_error = ''


def geterror():
    return _error


class ImageSpec:
    def __init__(self, width, height, names):
        self.width, self.height, self.nchannels, self.channelnames = width, height, len(names), tuple(names)


def _attributes(data):
    attrs, pos = {}, 8
    while data[pos] != 0:
        end = data.index(b'\0', pos)
        name = data[pos:end].decode()
        tend = data.index(b'\0', end + 1)
        kind = data[end + 1:tend].decode()
        size = struct.unpack_from('<i', data, tend + 1)[0]
        attrs[name] = (kind, data[tend + 5:tend + 5 + size])
        pos = tend + 5 + size
    return attrs, pos + 1


def _channels(value):
    out, pos = [], 0
    while value[pos] != 0:
        end = value.index(b'\0', pos)
        pixel_type = struct.unpack_from('<i', value, end + 1)[0]
        out.append((value[pos:end].decode(), pixel_type))
        pos = end + 1 + 16
    return out


def _unpredict(raw):
    t = np.frombuffer(raw, np.uint8).astype(np.int32)
    t = (np.cumsum(t - 128) + 128) & 255  # t[i] = t[i-1] + t[i] - 128, with t[0] unchanged
    t[0] = raw[0]
    t = t.astype(np.uint8)
    half = (len(t) + 1) // 2
    out = np.empty(len(t), np.uint8)
    out[0::2] = t[:half]
    out[1::2] = t[half:]
    return out.tobytes()


def _order(names):
    first = [n for n in ('R', 'G', 'B', 'A', 'X', 'Y', 'Z') if n in names]
    return first + [n for n in names if n not in first]


class ImageInput:
    @staticmethod
    def open(path):
        global _error
        try:
            return ImageInput(path)
        except Exception as e:  # a reader's failure is reported like OpenImageIO's: None and geterror()
            _error = '%s: %s' % (path, e)
            return None

    def __init__(self, path):
        data = open(path, 'rb').read()
        if data[:4] != b'\x76\x2f\x31\x01':
            raise ValueError('not an OpenEXR file')
        if data[5] & 0x02:
            raise ValueError('tiled files are not supported')
        attrs, pos = _attributes(data)
        x0, y0, x1, y1 = struct.unpack('<4i', attrs['dataWindow'][1])
        self._w, self._h = x1 - x0 + 1, y1 - y0 + 1
        self._y0 = y0
        self._channels = _channels(attrs['channels'][1])
        compression = attrs['compression'][1][0]
        lines = {0: 1, 2: 1, 3: 16}.get(compression)
        if lines is None:
            raise ValueError('compression %d is not supported' % compression)
        chunks = (self._h + lines - 1) // lines
        offsets = struct.unpack_from('<%dQ' % chunks, data, pos)
        types = {0: np.uint32, 1: np.float16, 2: np.float32}
        planes = {name: np.zeros((self._h, self._w), np.float32) for name, _ in self._channels}
        for off in offsets:
            y, size = struct.unpack_from('<ii', data, off)
            block = data[off + 8:off + 8 + size]
            n = min(lines, y0 + self._h - y)
            expected = n * self._w * sum({0: 4, 1: 2, 2: 4}[t] for _, t in self._channels)
            if compression != 0 and size < expected:
                block = _unpredict(zlib.decompress(block))
            p = 0
            for row in range(n):
                for name, t in self._channels:
                    nb = self._w * (4 if t != 1 else 2)
                    planes[name][y - y0 + row] = np.frombuffer(block, types[t], self._w, p).astype(np.float32)
                    p += nb
        names = _order([n for n, _ in self._channels])
        self._pixels = np.stack([planes[n] for n in names], -1)
        self._spec = ImageSpec(self._w, self._h, names)

    def spec(self):
        return self._spec

    def read_image(self, subimage=0, miplevel=0, chbegin=0, chend=None, fmt='float'):
        chend = self._spec.nchannels if chend is None else chend
        return self._pixels[..., chbegin:chend].copy()

    def close(self):
        pass
