"""One marching-cubes run from Python, measured in its own process: time (median of REPEAT) and
peak memory above the loaded input. Used by bench/python.sh.

    python_mc.py VOLUME ISO METHOD THREADS REPEAT
VOLUME: a .nii.gz (NIfTI-1) or DIMSxTYPE:FILE.raw (512x512x512xu16:data/bench/head512.raw).
METHOD: vdiso, skimage, vtk (vtkFlyingEdges3D)."""
import gzip
import json
import resource
import statistics
import struct
import sys
import time

import numpy as np


def load(spec):
    if spec.endswith(".nii.gz") or spec.endswith(".nii"):
        data = (gzip.open if spec.endswith(".gz") else open)(spec, "rb").read()
        dims = struct.unpack("<8h", data[40:56])[1:4]
        dtype = {2: np.uint8, 4: np.int16, 8: np.int32, 16: np.float32, 64: np.float64, 256: np.int8,
                 512: np.uint16}[struct.unpack("<h", data[70:72])[0]]
        offset = int(struct.unpack("<f", data[108:112])[0])
        x, y, z = dims
        return np.frombuffer(data, dtype, x * y * z, offset).reshape(z, y, x).copy()
    shape_type, path = spec.split(":", 1)
    *dims, kind = shape_type.split("x")
    x, y, z = (int(d) for d in dims)
    return np.fromfile(path, {"u8": np.uint8, "u16": np.uint16, "i16": np.int16, "f32": np.float32}[kind]).reshape(z, y, x)


def topology(verts, faces):
    """A triangle mesh's Euler characteristic V - E + F and its connected pieces (scipy)."""
    import scipy.sparse
    import scipy.sparse.csgraph
    edges = np.unique(np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1), axis=0)
    used = np.unique(faces)
    graph = scipy.sparse.coo_matrix((np.ones(len(edges)), (edges[:, 0], edges[:, 1])), shape=(len(verts),) * 2)
    labels = scipy.sparse.csgraph.connected_components(graph, directed=False)[1]
    return int(len(used) - len(edges) + len(faces)), int(len(np.unique(labels[used])))


def rss_mb():
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def main():
    spec, iso, method, threads, repeat = sys.argv[1], float(sys.argv[2]), sys.argv[3], int(sys.argv[4]), int(sys.argv[5])
    volume = load(spec)
    if method == "vdiso":
        import vdiso
        run = lambda: vdiso.marching_cubes(volume, iso, threads=threads)
    elif method == "skimage":
        import skimage.measure
        run = lambda: skimage.measure.marching_cubes(volume, iso)
    else:
        import vtk
        from vtk.util import numpy_support
        vtk.vtkSMPTools.Initialize(threads)
        image = vtk.vtkImageData()
        image.SetDimensions(volume.shape[2], volume.shape[1], volume.shape[0])
        image.GetPointData().SetScalars(numpy_support.numpy_to_vtk(volume.ravel(), deep=False))

        def run():
            fe = vtk.vtkFlyingEdges3D()
            fe.SetInputData(image)
            fe.SetValue(0, iso)
            fe.ComputeNormalsOn()
            fe.Update()
            out = fe.GetOutput()
            return out.GetNumberOfPoints(), out.GetNumberOfCells()
    base = rss_mb()
    seconds, result = [], None
    for _ in range(repeat):
        result = None  # the previous run's output is not held while the next one runs
        start = time.perf_counter()
        result = run()
        seconds.append(time.perf_counter() - start)
    triangles = result[1] if method == "vtk" else len(result[1])
    print(json.dumps({"volume": spec, "method": method, "threads": threads, "seconds": statistics.median(seconds),
                      "mvoxels_per_s": volume.size / statistics.median(seconds) / 1e6, "triangles": int(triangles),
                      "input_mb": volume.nbytes / 1e6, "peak_over_input_mb": rss_mb() - base}))


if __name__ == "__main__":
    main()
