#!/usr/bin/python3
"""A stand-in for a 512x512x234 CT head: the Debian CT (data/cranium.raw, 256x256x108 int16,
scripts/fetch_data.sh) resampled trilinearly to 512x512x234 with Gaussian noise of 15 HU (a
real scan at that size has its own noise; the resampling alone would smooth it away), written
as data/bench/ct512.raw with its NRRD header. Skin -423.5, bone 200.5 as on the CT.

    /usr/bin/python3 bench/make_ct512.py && build/bin/vdiso convert data/bench/ct512.nhdr data/bench/ct512.vdiso
"""
import os

import numpy as np

here = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
src = os.path.join(here, "data", "cranium.raw")
out = os.path.join(here, "data", "bench")
volume = np.fromfile(src, dtype="<i2").reshape(108, 256, 256).astype(np.float32)


def resample(a, axis, n):
    """a resampled to n samples along axis, end samples kept (linear interpolation)."""
    m = a.shape[axis]
    x = np.linspace(0, m - 1, n)
    i0 = np.floor(x).astype(int)
    i1 = np.minimum(i0 + 1, m - 1)
    shape = [1, 1, 1]
    shape[axis] = n
    f = (x - i0).astype(np.float32).reshape(shape)
    return np.take(a, i0, axis) * (1 - f) + np.take(a, i1, axis) * f


for axis, n in ((0, 234), (1, 512), (2, 512)):
    volume = resample(volume, axis, n)
volume += np.random.default_rng(1).normal(0, 15, volume.shape).astype(np.float32)
os.makedirs(out, exist_ok=True)
np.clip(np.rint(volume), -32768, 32767).astype("<i2").tofile(os.path.join(out, "ct512.raw"))
with open(os.path.join(out, "ct512.nhdr"), "w") as f:
    f.write("NRRD0004\n# data/cranium.raw resampled to 512x512x234, noise sigma 15 HU (bench/make_ct512.py)\n"
            "type: int16\ndimension: 3\nsizes: 512 512 234\nspacings: 0.4785156 0.4785156 0.6923\n"
            "encoding: raw\nendian: little\ndata file: ct512.raw\n")
