#!/usr/bin/python3
"""Checks the EXR stand-in (OpenImageIO.py beside this file) against the real OpenImageIO on every EXR given:
the same size, channel names and pixels, bit for bit. Usage: check.py FILE.exr ..."""
import importlib.util
import os
import sys

import numpy as np
import OpenImageIO as real

spec = importlib.util.spec_from_file_location('shim', os.path.join(os.path.dirname(__file__), 'OpenImageIO.py'))
shim = importlib.util.module_from_spec(spec)
spec.loader.exec_module(shim)
bad = 0
for path in sys.argv[1:]:
    a, b = real.ImageInput.open(path), shim.ImageInput.open(path)
    sa, sb = a.spec(), b.spec()
    pa = np.asarray(a.read_image(0, 0, 0, sa.nchannels, 'float')).reshape(sa.height, sa.width, sa.nchannels)
    pb = b.read_image(0, 0, 0, sb.nchannels, 'float')
    same = (sa.width, sa.height, tuple(sa.channelnames)) == (sb.width, sb.height, sb.channelnames) and \
        np.array_equal(pa, pb, equal_nan=True)
    bad += not same
    print('%s %s' % ('ok  ' if same else 'DIFF', path))
print('%d of %d files differ' % (bad, len(sys.argv) - 1))
sys.exit(1 if bad else 0)
