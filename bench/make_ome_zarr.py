#!/usr/bin/python3
"""Writes a raw u16 volume (x fastest, little-endian) as an OME-Zarr 0.4 image of one level
(Zarr v2, zlib chunks), with the standard library only: the bench's input for converting from
object storage (bench/remote_zarr.sh). Not a general Zarr writer.

    bench/make_ome_zarr.py RAW NX NY NZ CHUNK OUT.ome.zarr
"""
import json
import os
import sys
import zlib


def main():
    raw, nx, ny, nz, chunk, out = sys.argv[1], *map(int, sys.argv[2:6]), sys.argv[6]
    os.makedirs(os.path.join(out, "0"), exist_ok=True)
    with open(os.path.join(out, ".zgroup"), "w") as f:
        json.dump({"zarr_format": 2}, f)
    with open(os.path.join(out, ".zattrs"), "w") as f:
        json.dump({"multiscales": [{"version": "0.4", "axes": [{"name": a, "type": "space"} for a in "zyx"],
                                    "datasets": [{"path": "0", "coordinateTransformations": [
                                        {"type": "scale", "scale": [1.0, 1.0, 1.0]}]}]}]}, f)
    with open(os.path.join(out, "0", ".zarray"), "w") as f:
        json.dump({"zarr_format": 2, "shape": [nz, ny, nx], "chunks": [chunk] * 3, "dtype": "<u2",
                   "compressor": {"id": "zlib", "level": 1}, "fill_value": 0, "order": "C",
                   "filters": None, "dimension_separator": "/"}, f)
    row = nx * 2
    with open(raw, "rb") as f:
        for kz in range(0, nz, chunk):
            # One layer of slices at a time.
            f.seek(kz * ny * row)
            layer = f.read(min(chunk, nz - kz) * ny * row)
            depth = len(layer) // (ny * row)
            for ky in range(0, ny, chunk):
                for kx in range(0, nx, chunk):
                    parts = []
                    for z in range(chunk):
                        for y in range(ky, ky + chunk):
                            if z < depth and y < ny:
                                start = (z * ny + y) * row + kx * 2
                                piece = layer[start:start + min(chunk, nx - kx) * 2]
                            else:
                                piece = b""
                            parts.append(piece + b"\0" * (chunk * 2 - len(piece)))
                    folder = os.path.join(out, "0", str(kz // chunk), str(ky // chunk))
                    os.makedirs(folder, exist_ok=True)
                    with open(os.path.join(folder, str(kx // chunk)), "wb") as c:
                        c.write(zlib.compress(b"".join(parts), 1))


if __name__ == "__main__":
    main()
