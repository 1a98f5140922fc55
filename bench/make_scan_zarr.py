#!/usr/bin/python3
"""Writes a scan as an OME-Zarr 0.4 image of one level (Zarr v2, blosc lz4 chunks of CHUNK^3),
with Debian's python3-zarr: the real scans' input for indexing in place (bench/zarr_index.sh).

    bench/make_scan_zarr.py INPUT CHUNK OUT.ome.zarr

INPUT: a NIfTI-1 file (.nii or .nii.gz) or an NRRD header with a raw data file (.nhdr).
"""
import gzip
import json
import os
import struct
import sys

import numcodecs
import numpy as np
import zarr


def read_nifti(path):
    data = (gzip.open if path.endswith(".gz") else open)(path, "rb").read()
    dims = struct.unpack_from("<8h", data, 40)
    datatype = struct.unpack_from("<h", data, 70)[0]
    pixdim = struct.unpack_from("<8f", data, 76)
    offset = int(struct.unpack_from("<f", data, 108)[0])
    dtype = {2: np.uint8, 4: np.int16, 512: np.uint16, 16: np.float32}[datatype]
    nx, ny, nz = dims[1:4]
    v = np.frombuffer(data, dtype=dtype, count=nx * ny * nz, offset=offset).reshape(nz, ny, nx)
    return v, (pixdim[3], pixdim[2], pixdim[1])


def read_nrrd(path):
    fields = {}
    for line in open(path, encoding="latin-1"):
        if ":" in line and not line.startswith("#"):
            k, v = line.split(":", 1)
            fields[k.strip()] = v.strip()
    nx, ny, nz = map(int, fields["sizes"].split())
    dtype = {"int16": np.int16, "uint16": np.uint16, "uint8": np.uint8, "float": np.float32}[fields["type"]]
    raw = os.path.join(os.path.dirname(path), fields["data file"])
    v = np.fromfile(raw, dtype=dtype).reshape(nz, ny, nx)
    sx, sy, sz = map(float, fields["spacings"].split())
    return v, (sz, sy, sx)


def main():
    path, chunk, out = sys.argv[1], int(sys.argv[2]), sys.argv[3]
    v, scale = read_nifti(path) if ".nii" in path else read_nrrd(path)
    root = zarr.open_group(out, mode="w")
    root.attrs["multiscales"] = [{"version": "0.4", "axes": [{"name": a, "type": "space"} for a in "zyx"],
                                  "datasets": [{"path": "0", "coordinateTransformations": [
                                      {"type": "scale", "scale": [float(s) for s in scale]}]}]}]
    root.create_dataset("0", data=v, chunks=(chunk,) * 3,
                        compressor=numcodecs.Blosc(cname="lz4", clevel=5, shuffle=numcodecs.Blosc.SHUFFLE))
    print(json.dumps({"out": out, "shape": v.shape, "dtype": str(v.dtype)}))


if __name__ == "__main__":
    main()
