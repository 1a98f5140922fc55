"""vdiso.marching_cubes against skimage.measure.marching_cubes on the real scans, for
docs/python.md: method="lorensen" against scikit-image's (triangles; whether the vertices are
the same points and their values equal; how many normals point the same way; the share of the
same triangles, and of triangles wound with their normals) and method="lewiner", the default,
against scikit-image's (triangles, vertices inside cells, and each surface's Euler
characteristic and pieces); seconds at 1 thread, median of REPEAT. One JSON line per scan. Used
by bench/python.sh skimage.

    python_vs_skimage.py [REPEAT]"""
import json
import statistics
import sys
import time

import numpy as np
import skimage.measure

import vdiso
from python_mc import load, topology

repeat = int(sys.argv[1]) if len(sys.argv) > 1 else 3
scans = [("ch2better", "data/ch2better.nii.gz", 40.5), ("ch2", "data/ch2.nii.gz", 40.5),
         ("cranium skin", "256x256x108xi16:data/cranium.raw", -423.5),
         ("cranium bone", "256x256x108xi16:data/cranium.raw", 200.5)]


def timed(run):
    times, out = [], None
    for _ in range(repeat):
        start = time.perf_counter()
        out = run()
        times.append(time.perf_counter() - start)
    return out, statistics.median(times)


def by_point(verts):
    """Each vertex's row, keyed by its position to 1e-4 of a sample (scikit-image and vdiso
    compute the crossing in different precisions)."""
    return {tuple(np.round(v, 4)): i for i, v in enumerate(verts)}


for name, spec, iso in scans:
    volume = load(spec)
    (v, f, n, values), vdiso_s = timed(lambda: vdiso.marching_cubes(volume, iso, threads=1, method="lorensen"))
    (gv, gf, _, _), vdiso_lewiner_s = timed(lambda: vdiso.marching_cubes(volume, iso, threads=1))
    (lv, lf, ln, lvalues), lorensen_s = timed(lambda: skimage.measure.marching_cubes(volume, iso, method="lorensen"))
    (wv, wf, _, _), lewiner_s = timed(lambda: skimage.measure.marching_cubes(volume, iso))
    theirs = by_point(lv)
    match = np.array([theirs.get(tuple(np.round(p, 4)), -1) for p in v])
    same_points = bool((match >= 0).all()) and len(theirs) == len(v)
    found = match >= 0
    agree = np.sum(n[found] * ln[match[found]], axis=1)
    # The same triangles (corners as scikit-image's vertices, up to rotation), and the share of
    # each one's triangles wound with their vertices' normals.
    def cycles(faces, rows):
        return {tuple(np.roll(c, -int(np.argmin(c)))) for c in rows[faces]}
    def along_normals(verts, faces, normals):
        t = verts[faces]
        cross = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
        return float(np.mean(np.sum(cross * normals[faces].sum(axis=1), axis=1) > 0))
    print(json.dumps({
        "scan": name, "iso": iso, "shape": volume.shape,
        "triangles": len(f), "lorensen_triangles": len(lf), "lewiner_triangles": len(wf),
        "vertices": len(v), "lorensen_vertices": len(lv), "lewiner_vertices": len(wv),
        "same_points_as_lorensen": same_points,
        "values_equal": float(np.mean(values[found] == lvalues[match[found]])),
        "normals_same_way": float(np.mean(agree > 0)), "normals_opposite": float(np.mean(agree < 0)),
        "normals_cos_median": float(np.median(agree / np.maximum(
            np.linalg.norm(n[found], axis=1) * np.linalg.norm(ln[match[found]], axis=1), 1e-30))),
        "same_triangles": (len(cycles(f, match) & cycles(lf, np.arange(len(lv)))) / len(f)) if same_points else None,
        "wound_with_normals": along_normals(v, f, n), "lorensen_wound_with_normals": along_normals(lv, lf, ln),
        "vdiso_1_thread_s": vdiso_s, "lorensen_s": lorensen_s, "lewiner_s": lewiner_s,
        "vdiso_lewiner_triangles": len(gf),
        "vdiso_lewiner_inside_cells": int(((np.abs(gv - np.round(gv)) > 1e-3).sum(axis=1) > 1).sum()),
        "vdiso_lewiner_euler_pieces": topology(gv, gf), "lewiner_euler_pieces": topology(wv, wf),
        "lorensen_euler_pieces": topology(lv, lf), "vdiso_lewiner_1_thread_s": vdiso_lewiner_s}), flush=True)
