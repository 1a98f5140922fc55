"""vdiso.marching_cubes on the real scans held in memory, and the same samples as a Zarr array
of 64^3 chunks (Zarr's default compressor): loaded first (np.asarray, then meshed), and read a
layer of bricks at a time, as a Zarr array and as a Dask array over it: seconds, median of
REPEAT, all cores. Prints a JSON line per scan. Used by bench/python.sh scans.

    python_scans_mc.py [REPEAT]"""
import json
import statistics
import sys
import tempfile
import time

import dask.array as da
import numpy as np
import zarr

import vdiso
from python_mc import load

repeat = int(sys.argv[1]) if len(sys.argv) > 1 else 5
scans = [("ch2better", "data/ch2better.nii.gz", 40.5), ("ch2", "data/ch2.nii.gz", 40.5),
         ("cranium skin", "256x256x108xi16:data/cranium.raw", -423.5),
         ("cranium bone", "256x256x108xi16:data/cranium.raw", 200.5)]
with tempfile.TemporaryDirectory() as tmp:
    for name, spec, iso in scans:
        volume = load(spec)
        stored = zarr.array(volume, chunks=(64, 64, 64), store=f"{tmp}/{name.split()[0]}.zarr", overwrite=True)
        row = {"scan": name, "iso": iso, "shape": volume.shape}
        kinds = (("memory", lambda: volume), ("zarr_loaded_first", lambda: np.asarray(stored)),
                 ("zarr", lambda: stored), ("dask", lambda: da.from_zarr(stored)))
        for kind, source in kinds:
            times = []
            for _ in range(repeat):
                start = time.perf_counter()
                verts, faces, _, _ = vdiso.marching_cubes(source(), iso)
                times.append(time.perf_counter() - start)
            row[kind + "_s"] = statistics.median(times)
            row[kind + "_triangles"] = len(faces)
        print(json.dumps(row), flush=True)
