"""From Python, a volume never whole in memory: an N^3 Dask array generated lazily (a ball with a
wavy skin, u8, chunk by chunk) converted to a store, then its SAGE normal view extracted; prints
seconds and the process's peak RSS. Used by bench/python.sh lazy.

    python_lazy.py N OUT.vdiso"""
import json
import resource
import sys
import time

import dask.array as da
import numpy as np

import vdiso

n, out = int(sys.argv[1]), sys.argv[2]
chunk = 8


def block(block_info=None):
    (z0, z1), _, _ = block_info[None]["array-location"]
    c = np.float32(n / 2)
    y = np.arange(n, dtype=np.float32)[:, None] - c
    x = np.arange(n, dtype=np.float32)[None, :] - c
    plane = x * x + y * y
    wave = np.float32(n / 40) * np.sin(x / np.float32(n / 25)) * np.cos(y / np.float32(n / 31))
    out = np.empty((z1 - z0, n, n), np.uint8)
    for i, z in enumerate(range(z0, z1)):
        r = np.sqrt(plane + np.float32((z - c) ** 2)) + wave
        out[i] = np.clip(np.float32(200) - r * np.float32(200 / (0.45 * n)) * np.float32(1.0), 0, 255)
    return out


volume = da.map_blocks(block, dtype=np.uint8, chunks=((chunk,) * (n // chunk), (n,), (n,)))
start = time.perf_counter()
summary = vdiso.convert(volume, out, overwrite=True)
convert_s = time.perf_counter() - start
convert_peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
store = vdiso.open(out)
start = time.perf_counter()
mesh = store.extract(100.5, method="sage", view="normal", size=(1024, 1024), cache_mb=256)
extract_s = time.perf_counter() - start
print(json.dumps({"n": n, "input_gb": n ** 3 / 1e9, "store_gb": summary["file_bytes"] / 1e9, "convert_s": convert_s,
                  "extract_s": extract_s, "triangles": len(mesh.faces), "points": len(mesh.points),
                  "peak_rss_after_convert_mb": convert_peak, "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}))
