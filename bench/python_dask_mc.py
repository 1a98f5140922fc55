"""vdiso.marching_cubes on a Dask array never whole in memory: an N^3 u16 array generated lazily,
chunk by chunk (C^3 chunks: a ball with a wavy skin and noise), meshed a layer of bricks at a time
(`slabs`), or, as before the slab path, after computing it whole (`memory`: np.asarray first),
or on a dask.distributed LocalCluster of W worker processes of one thread each (`clusterW`:
marching_cubes(client=...)); prints seconds, triangles and the peak RSS of the process (and of
each worker). Used by bench/python.sh dask.

    python_dask_mc.py N C slabs|memory|clusterW [THREADS]"""
import json
import resource
import sys
import time

import dask
import dask.array as da
import numpy as np

import vdiso

n, chunk, mode = int(sys.argv[1]), int(sys.argv[2]), sys.argv[3]
threads = int(sys.argv[4]) if len(sys.argv) > 4 else None


def block(block_info=None):
    (z0, z1), (y0, y1), (x0, x1) = block_info[None]["array-location"]
    c = np.float32(n / 2)
    z, y, x = np.ogrid[z0:z1, y0:y1, x0:x1]
    z, y, x = (np.float32(1) * z - c, np.float32(1) * y - c, np.float32(1) * x - c)
    r = np.sqrt(x * x + y * y + z * z) + np.float32(n / 40) * np.sin(x / np.float32(n / 25)) * np.cos(y / np.float32(n / 31))
    noise = np.random.default_rng(z0 * n * n + y0 * n + x0).normal(0, 20, r.shape).astype(np.float32)
    return np.clip(np.float32(40000) - r * np.float32(40000 / (0.45 * n)) + noise, 0, 65535).astype(np.uint16)


volume = da.map_blocks(block, dtype=np.uint16, chunks=((chunk,) * (n // chunk),) * 3)
level = 20000.5


def on_cluster():
    from distributed import Client, LocalCluster
    with LocalCluster(n_workers=int(mode[7:]), threads_per_worker=1, processes=True,
                      dashboard_address=None) as cluster, Client(cluster) as client:
        client.run(lambda: None)  # the workers up before the clock starts
        start = time.perf_counter()
        verts, faces, normals, values = vdiso.marching_cubes(volume, level, client=client)
        seconds = time.perf_counter() - start
        workers = client.run(lambda: resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024)
    print(json.dumps({"n": n, "chunk": chunk, "mode": mode, "seconds": seconds, "triangles": len(faces),
                      "vertices": len(verts), "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
                      "worker_peak_rss_mb": sorted(workers.values())}))


def on_this_machine():
    with dask.config.set(num_workers=threads or None):
        start = time.perf_counter()
        source = np.asarray(volume) if mode == "memory" else volume
        verts, faces, normals, values = vdiso.marching_cubes(source, level, threads=threads)
        seconds = time.perf_counter() - start
    print(json.dumps({"n": n, "chunk": chunk, "mode": mode, "threads": threads, "input_gb": 2 * n ** 3 / 1e9,
                      "seconds": seconds, "triangles": len(faces), "vertices": len(verts),
                      "output_mb": (verts.nbytes + faces.nbytes + normals.nbytes + values.nbytes) / 1e6,
                      "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}))


if __name__ == "__main__":  # the cluster's worker processes import this file too
    on_cluster() if mode.startswith("cluster") else on_this_machine()
