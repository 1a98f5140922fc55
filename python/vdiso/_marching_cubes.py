"""vdiso.marching_cubes: scikit-image's marching_cubes over the library's octree extraction of an
array in place (python/src/marching_cubes.cpp), with scikit-image's keywords."""

from . import _vdiso
from ._args import _float, _int


def marching_cubes(volume, level=None, spacing=(1.0, 1.0, 1.0), *, gradient_direction="descent", step_size=1,
                   allow_degenerate=True, method="lorensen", mask=None, threads=None, progress=None):
    """marching_cubes(volume, level=None, spacing=(1.0, 1.0, 1.0), *, gradient_direction="descent",
    step_size=1, allow_degenerate=True, method="lorensen", mask=None, threads=None, progress=None)
    -> (verts, faces, normals, values)

    The isosurface `level` of a 3-D array, as skimage.measure.marching_cubes returns it: verts
    (V, 3) in the array's axis order scaled by `spacing` (float32; float64 when a spacing is not
    1, as scikit-image's), faces (F, 3) int32, normals
    (V, 3) float32 pointing away from the values above `level` (outward for a bright object),
    values (V,) float32 (the largest sample of the cell each vertex lies in). `volume`: any 3-D
    array of uint8, int8, uint16, int16, uint32, int32, float32 or float64, C- or F-ordered or
    strided, read in place (never copied to float); bool is read as uint8 in place; float16 is
    copied to float32, and int64 and uint64 (what skimage.measure.label returns) to the 32-bit
    integers when their values fit, else to float64. `level` None: the middle of the array's
    range (NaN left out), found by the library after its checks of the array; a level outside
    the values is a ValueError (as scikit-image), a level with no
    surface gives empty arrays (scikit-image raises RuntimeError). The triangles of
    `vdiso extract --method octree`, on `threads` threads (None: all cores): Lorensen and Cline's
    cases, ambiguous cells not resolved, as scikit-image's method="lorensen" (the same vertices
    and as many triangles, an ambiguous cell sometimes cut along its other diagonal), not its
    default "lewiner" (which resolves them and makes a few more triangles). progress:
    callable(done, total) in samples; Ctrl-C stops the call within a fraction of a second.

    scikit-image's keywords: gradient_direction "descent" (its default and this winding) or
    "ascent" (the faces' winding reversed); step_size, the cells' side in samples (the array read
    as a strided view, no copy); allow_degenerate=False merges vertices that coincide and drops
    the triangles that then have no area; mask, a boolean array of the volume's shape: only the
    triangles of the cells whose far corner (of highest indices) it marks are kept, as
    scikit-image's (the whole volume is meshed first: a mask saves no time here). method:
    "lorensen" only; "lewiner" is refused (its ambiguity resolution is not implemented), never
    answered with another surface.
    """
    import numpy as np
    if not isinstance(volume, np.ndarray):
        volume = np.asarray(volume)
    volume = _readable_samples(volume)
    if level is None and volume.size == 0:
        raise ValueError("volume: an empty array has no isosurface")
    # level None: the library takes the middle of the values, after its checks of the array.
    try:
        spacing = tuple(spacing)
    except TypeError:
        raise TypeError(f"spacing: expects 3 numbers (z, y, x), not {type(spacing).__name__}") from None
    if len(spacing) != 3:
        raise ValueError(f"spacing: expects 3 numbers (z, y, x), not {len(spacing)}")
    spacing = tuple(_float(s, "spacing") for s in spacing)
    unit = spacing == (1.0, 1.0, 1.0)
    if method != "lorensen":
        raise ValueError(f"method: {method!r} is not implemented: vdiso's surface is scikit-image's "
                         "method=\"lorensen\" (ambiguous cells not resolved); pass method=\"lorensen\"")
    if gradient_direction not in ("descent", "ascent"):
        raise ValueError(f"gradient_direction: expects \"descent\" or \"ascent\", not {gradient_direction!r}")
    step = _int(step_size, "step_size")
    if step < 1:
        raise ValueError(f"step_size: expects 1 or more, not {step}")
    if mask is not None:
        mask = np.asarray(mask)
        if mask.shape != volume.shape:
            raise ValueError(f"mask: expects the volume's shape {volume.shape}, not {mask.shape}")
        mask = mask.astype(bool, copy=False)
    if step > 1:
        volume = volume[::step, ::step, ::step]
        mask = None if mask is None else mask[::step, ::step, ::step]
        spacing = tuple(s * step for s in spacing)
    verts, faces, normals, values = _vdiso.marching_cubes(
        volume, None if level is None else _float(level, "level"), spacing,
        threads=None if threads is None else _int(threads, "threads"), progress=progress)
    if mask is not None:
        # A triangle lies in one cell, its centroid inside it (or on its faces): the cell's
        # first corner is the centroid's floor, in samples. scikit-image tests a cell's far
        # corner (the one of highest indices).
        cells = np.floor(verts[faces].mean(axis=1) / np.asarray(spacing)).astype(np.int64)
        np.clip(cells, 0, np.array(volume.shape) - 2, out=cells)
        faces = faces[mask[cells[:, 0] + 1, cells[:, 1] + 1, cells[:, 2] + 1]]
        verts, faces, normals, values = _used_vertices(verts, faces, normals, values)
    if not allow_degenerate:
        _, first, inverse = np.unique(verts, axis=0, return_index=True, return_inverse=True)
        faces = first[inverse.reshape(-1)][faces].astype(np.int32)
        faces = faces[(faces[:, 0] != faces[:, 1]) & (faces[:, 1] != faces[:, 2]) & (faces[:, 0] != faces[:, 2])]
        verts, faces, normals, values = _used_vertices(verts, faces, normals, values)
    if step > 1 and unit:
        verts = verts.astype(np.float32)  # scikit-image's type for a unit spacing, whatever the step
    if gradient_direction == "ascent":
        faces = np.ascontiguousarray(faces[:, ::-1])
    return verts, faces, normals, values


def _used_vertices(verts, faces, normals, values):
    """The vertices the faces use, in their order, and the faces renumbered."""
    import numpy as np
    used = np.unique(faces)
    if len(used) == len(verts):
        return verts, faces, normals, values
    number = np.full(len(verts), -1, np.int32)
    number[used] = np.arange(len(used), dtype=np.int32)
    return verts[used], number[faces], normals[used], values[used]


def _readable_samples(volume):
    """`volume` itself when the library reads its dtype in place; bool as uint8 (a view), float16
    as float32, and 64-bit integers as the 32-bit ones when every value fits (else float64):
    copies, as scikit-image makes (it takes float64 throughout)."""
    import numpy as np
    kind, size = volume.dtype.kind, volume.dtype.itemsize
    if kind == "b":
        return volume.view(np.uint8)
    if kind == "f" and size == 2:
        return volume.astype(np.float32)
    if kind in "iu" and size == 8:
        narrow = np.int32 if kind == "i" else np.uint32
        if volume.size:
            info = np.iinfo(narrow)
            if volume.min() >= info.min and volume.max() <= info.max:
                return volume.astype(narrow)
        else:
            return volume.astype(narrow)
        return volume.astype(np.float64)
    return volume
