"""VTK's Flying Edges (vtkFlyingEdges3D, normals on) over a volume in memory, from Python:
median seconds of REPEAT runs on THREADS threads and the triangle count, as one JSON line.
The reference the real-scan table (bench/real_scans.sh) divides by.

    fe_python.py VOLUME ISO THREADS REPEAT
VOLUME: a .nii.gz, a .nhdr with a raw data file, or DIMSxTYPE:FILE.raw (see python_mc.py)."""
import json
import os
import statistics
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from python_mc import load  # noqa: E402

import vtk  # noqa: E402
from vtk.util import numpy_support  # noqa: E402


def load_any(spec):
    if spec.endswith(".nhdr"):
        fields = dict(line.split(": ", 1) for line in open(spec).read().splitlines()[1:] if ": " in line)
        x, y, z = (int(v) for v in fields["sizes"].split())
        kind = {"int16": "i16", "uint16": "u16", "uint8": "u8", "float": "f32"}[fields["type"]]
        return load(f"{x}x{y}x{z}x{kind}:{os.path.join(os.path.dirname(spec), fields['data file'])}")
    return load(spec)


spec, iso, threads, repeat = sys.argv[1], float(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4])
volume = load_any(spec)
vtk.vtkSMPTools.Initialize(threads)
image = vtk.vtkImageData()
image.SetDimensions(volume.shape[2], volume.shape[1], volume.shape[0])
image.GetPointData().SetScalars(numpy_support.numpy_to_vtk(volume.ravel(), deep=False))
seconds, triangles = [], 0
for _ in range(repeat):
    fe = vtk.vtkFlyingEdges3D()
    fe.SetInputData(image)
    fe.SetValue(0, iso)
    fe.ComputeNormalsOn()
    start = time.perf_counter()
    fe.Update()
    seconds.append(time.perf_counter() - start)
    triangles = fe.GetOutput().GetNumberOfCells()
print(json.dumps({"volume": spec, "iso": iso, "threads": threads, "seconds": statistics.median(seconds),
                  "triangles": triangles}))
