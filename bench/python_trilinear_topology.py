"""method="lewiner" against the trilinear interpolant it stands for, for docs/python.md: a scan
cut into blocks of 17^3 samples; where vdiso's and scikit-image's "lewiner" surfaces of a block
differ in topology (Euler characteristic V - E + F, or connected pieces), the block's
interpolant sampled SCALE times finer and meshed (cells then far smaller than its features)
says which is right. One JSON line: blocks, blocks that differ, and how many of those each
matches.

    python_trilinear_topology.py SPEC ISO [SCALE] [MAX_DIFFERING]"""
import json
import sys

import numpy as np
import skimage.measure
from scipy.ndimage import map_coordinates

import vdiso
from python_mc import load, topology


spec, iso = sys.argv[1], float(sys.argv[2])
scale = int(sys.argv[3]) if len(sys.argv) > 3 else 24
most = int(sys.argv[4]) if len(sys.argv) > 4 else 40
volume = load(spec).astype(np.float32)
blocks = differing = ours_right = theirs_right = 0
for z in range(0, volume.shape[0] - 17, 16):
    for y in range(0, volume.shape[1] - 17, 16):
        for x in range(0, volume.shape[2] - 17, 16):
            block = np.ascontiguousarray(volume[z:z + 17, y:y + 17, x:x + 17])
            if differing >= most or not (block.min() < iso < block.max()):
                continue
            blocks += 1
            ours = topology(*vdiso.marching_cubes(block, iso)[:2])
            theirs = topology(*skimage.measure.marching_cubes(block, iso)[:2])
            if ours == theirs:
                continue
            differing += 1
            grid = np.mgrid[tuple(slice(0, n - 1, complex(0, (n - 1) * scale + 1)) for n in block.shape)]
            fine = map_coordinates(block.astype(np.float64), grid, order=1).astype(np.float32)
            truth = topology(*vdiso.marching_cubes(fine, iso, method="lorensen")[:2])
            ours_right += ours == truth
            theirs_right += theirs == truth
print(json.dumps({"scan": spec, "iso": iso, "scale": scale, "blocks": blocks, "differing": differing,
                  "vdiso_matches_interpolant": ours_right, "skimage_matches_interpolant": theirs_right}))
