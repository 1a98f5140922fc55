"""vdiso.marching_cubes: scikit-image's marching_cubes over the library's octree extraction of an
array in place (python/src/marching_cubes.cpp), with scikit-image's keywords."""

from . import _vdiso
from ._args import _float, _int, _z_chunk_bounds


def marching_cubes(volume, level=None, spacing=(1.0, 1.0, 1.0), *, gradient_direction="descent", step_size=1,
                   allow_degenerate=True, method="lewiner", mask=None, threads=None, progress=None, client=None):
    """marching_cubes(volume, level=None, spacing=(1.0, 1.0, 1.0), *, gradient_direction="descent",
    step_size=1, allow_degenerate=True, method="lewiner", mask=None, threads=None, progress=None,
    client=None) -> (verts, faces, normals, values)

    The isosurface `level` of a 3-D array, as skimage.measure.marching_cubes returns it: verts
    (V, 3) in the array's axis order scaled by `spacing` (float32; float64 when a spacing is not
    1, as scikit-image's), faces (F, 3) int32, normals
    (V, 3) float32 pointing away from the values above `level` (outward for a bright object),
    values (V,) float32 as scikit-image's (the largest spread of the samples about `level`, as
    float32, in the cells around each vertex's edge that are meshed; a vertex inside a cell, that
    cell's). `volume`: any 3-D
    array of uint8, int8, uint16, int16, uint32, int32, float32 or float64, C- or F-ordered or
    strided, read in place (never copied to float); bool is read as uint8 in place; float16 is
    copied to float32, and int64 and uint64 (what skimage.measure.label returns) to the 32-bit
    integers when their values fit, else to float64. `level` None: the middle of the array's
    range (NaN left out), found by the library after its checks of the array; a level outside
    the values is a ValueError (as scikit-image), a level with no
    surface gives empty arrays (scikit-image raises RuntimeError). The library's octree
    extraction, on `threads` threads (None: all cores). method="lewiner" (the default, as
    scikit-image's): the surface has the topology of the trilinear interpolant of the samples,
    as Lewiner et al. guarantee (ambiguous faces cut by the asymptotic decider, tunnels inside
    a cell found), with a vertex inside a few cells where no triangulation of the crossings
    alone is clean; scikit-image's own "lewiner" departs from that topology on some cells
    (docs/python.md). method="lorensen": Lorensen and Cline's cases, ambiguous cells not
    resolved: scikit-image's "lorensen" (the same vertices, as many triangles) and every other
    vdiso front end's cut. progress: callable(done, total) in samples; Ctrl-C stops the call
    within a fraction of a second.

    A Dask or Zarr array, or any array-like with shape, dtype and slicing along axis 0 that is
    not a NumPy array, is never loaded whole: it is read once, in order, a layer of 35 slices at
    a time (a Dask or Zarr array a whole chunk's slab at a time, so no chunk is computed or
    decoded twice), and meshed layer by layer into the same arrays as the array held in memory
    gives, bit for bit. Memory: the output, a chunk's slab and a layer. With level=None it is
    read twice (once for its range): pass a level to read it once.

    client: a dask.distributed Client, to mesh a Dask array on the cluster's workers: the layers
    of bricks are cut into runs, each run's slices (with one more on each side) computed and
    meshed on a worker (`threads` each, or the worker's threads), and the runs welded by the
    edges they share into the same arrays again. The client holds the parts and the output.

    scikit-image's keywords: gradient_direction "descent" (its default and this winding) or
    "ascent" (the faces' winding reversed); step_size, the cells' side in samples (the array read
    as a strided view, no copy); allow_degenerate=False merges vertices that coincide and drops
    the triangles that then have no area; mask, a boolean array of the volume's shape: only the
    triangles of the cells whose far corner (of highest indices) it marks are kept, and the
    values count those cells only, as scikit-image's; only the bricks of 32^3 cells holding such a cell are meshed (the mask of an
    array read a layer at a time read a layer at a time too), so a small mask saves work;
    method, above.
    """
    import numpy as np
    chunked = not isinstance(volume, np.ndarray) and _sliceable(volume)
    if not chunked:
        volume = _readable_samples(np.asarray(volume))
    shape = tuple(int(n) for n in volume.shape)
    if level is None and 0 in shape:
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
    if method not in ("lewiner", "lorensen"):
        raise ValueError(f"method: expects \"lewiner\" or \"lorensen\", not {method!r}")
    trilinear = method == "lewiner"
    if gradient_direction not in ("descent", "ascent"):
        raise ValueError(f"gradient_direction: expects \"descent\" or \"ascent\", not {gradient_direction!r}")
    step = _int(step_size, "step_size")
    if step < 1:
        raise ValueError(f"step_size: expects 1 or more, not {step}")
    if mask is not None:
        if not hasattr(mask, "shape"):
            mask = np.asarray(mask)
        if tuple(mask.shape) != shape:
            raise ValueError(f"mask: expects the volume's shape {shape}, not {tuple(mask.shape)}")
    level = None if level is None else _float(level, "level")
    threads = None if threads is None else _int(threads, "threads")
    if client is not None:
        if not hasattr(volume, "__dask_graph__"):
            raise ValueError(f"client: meshes a Dask array on the cluster, not a {type(volume).__name__}")
        verts, faces, normals, values = _on_cluster(volume, level, tuple(s * step for s in spacing), step, threads,
                                                    client, progress, trilinear)
    elif chunked:
        rows = _SlabView(volume, step)
        name = f"{type(volume).__module__}.{type(volume).__name__}"
        verts, faces, normals, values = _vdiso._marching_cubes_in_slabs(
            rows if rows.wrapped else volume, name, list(rows.shape), rows.dtype, level,
            tuple(s * step for s in spacing), threads, _z_chunk_bounds(rows, list(rows.shape)), progress,
            bricks=None if mask is None or 0 in shape else _bricks_marked(mask, step), trilinear=trilinear)
    else:
        verts, faces, normals, values = _vdiso.marching_cubes(
            volume[::step, ::step, ::step] if step > 1 else volume, level, tuple(s * step for s in spacing),
            threads=threads, progress=progress,
            bricks=None if mask is None or 0 in shape else _bricks_marked(mask, step), trilinear=trilinear)
    if mask is not None:
        # A triangle lies in one cell, its centroid inside it (or on its faces): the cell's
        # first corner is the centroid's floor, in samples. scikit-image tests a cell's far
        # corner (the one of highest indices).
        cells = np.floor(verts[faces].mean(axis=1) / (np.asarray(spacing) * step)).astype(np.int64)
        np.clip(cells, 0, np.array([(n - 1) // step for n in shape]) - 1, out=cells)
        far = (cells + 1) * step
        kept = _samples_at(mask, far[:, 0], far[:, 1], far[:, 2]).astype(bool, copy=False)
        values = _values_of_kept_cells(volume, level, step, faces, cells, kept, values)
        faces = faces[kept]
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


def _on_cluster(volume, level, spacing, step, threads, client, progress, trilinear):
    """marching_cubes' arrays of the Dask array `volume` meshed on `client`'s workers, a run of
    layers of bricks a task (_vdiso._mesh_slab_part), welded here (_vdiso._join_slab_parts)."""
    import dask
    import dask.array as da
    import numpy as np
    from distributed import as_completed
    if step > 1:
        volume = volume[::step, ::step, ::step]
    readable = _read_as(volume.dtype)
    volume = volume.astype(readable)
    shape = [int(n) for n in volume.shape]
    if len(shape) != 3:
        raise ValueError(f"volume: expects a 3-D array, not one of {len(shape)} dimensions")
    if level is None:  # the middle of the values, as the library holds them (32-bit floats at most)
        lo, hi = client.gather(client.compute([da.nanmin(volume), da.nanmax(volume)]))
        level = _vdiso._level_in(None, float(np.float32(lo)), float(np.float32(hi)))
    brick = _vdiso._marching_cubes_brick  # app/slab_extraction.h's layers, as the bricks in memory
    layers = max(1, -(-(shape[0] - 1) // brick))
    workers = client.nthreads()
    if not workers:
        raise ValueError("client: the cluster has no workers")
    each = threads if threads is not None else min(workers.values())
    # At least two runs a worker, and runs of at most about 256 MB of samples.
    layer_bytes = brick * shape[1] * shape[2] * readable.itemsize
    count = min(layers, max(2 * len(workers), -(-layers * layer_bytes // (256 << 20))))
    cuts = [round(k * layers / count) for k in range(count + 1)]
    tasks, samples = [], []
    for first, end in zip(cuts, cuts[1:]):
        r0, r1 = max(first * brick - 1, 0), min(end * brick + 2, shape[0])
        tasks.append(dask.delayed(_mesh_run, pure=True)(volume[r0:r1], shape, readable, first, end, level,
                                                         spacing, each, trilinear))
        samples.append((r1 - r0) * shape[1] * shape[2])
    futures = client.compute(tasks)
    done, total = 0, sum(samples)
    try:
        for future in as_completed(futures):
            done += samples[futures.index(future)]
            if progress is not None:
                progress(done, total)
        parts = client.gather(futures)
    except BaseException:
        client.cancel(futures)
        raise
    return _vdiso._join_slab_parts(parts, level, spacing)


def _mesh_run(rows, shape, dtype, first, end, level, spacing, threads, trilinear):
    """A worker's task: layers [first, end) meshed from their slices `rows`."""
    import numpy as np
    return _vdiso._mesh_slab_part(np.ascontiguousarray(rows), shape, dtype, first, end, level, spacing, threads,
                                  trilinear)


def _sliceable(volume):
    """Whether `volume` is an array-like to read a layer at a time: shape, a NumPy dtype and
    slicing (a Dask, Zarr, h5py or xarray array); others (lists, tensors) are loaded whole."""
    import numpy as np
    if not all(hasattr(volume, a) for a in ("shape", "dtype", "__getitem__")):
        return False
    try:
        np.dtype(volume.dtype)
    except TypeError:
        return False
    return True


class _SlabView:
    """An array-like read along axis 0 as marching_cubes reads one too large to load, every
    `step`-th sample on each axis and in a dtype the library reads (_read_as): slices of it are
    slices of the source, converted. `wrapped` is False when it is the source itself."""

    def __init__(self, source, step):
        import numpy as np
        self._source, self._step = source, step
        self.dtype = _read_as(source.dtype)
        self.shape = tuple((int(n) + step - 1) // step for n in source.shape)
        self.wrapped = step > 1 or self.dtype != np.dtype(source.dtype)
        bounds = _z_chunk_bounds(source, [int(n) for n in source.shape])
        # The chunks' first slices in this view's numbering (a chunk holds the samples from its
        # first multiple of `step`); a chunk holding none of them is no chunk of the view.
        firsts = sorted({(b + step - 1) // step for b in bounds[:-1]} | {0}) if bounds else []
        firsts = [f for f in firsts if f < self.shape[0]]
        self.chunks = (tuple(b - a for a, b in zip(firsts, firsts[1:] + [self.shape[0]])),) if firsts else None

    def __getitem__(self, key):
        import numpy as np
        z = key if isinstance(key, slice) else key[0]
        first, end, _ = z.indices(self.shape[0])
        s = self._step
        got = np.asarray(self._source[first * s:max(end - 1, first) * s + 1:s, ::s, ::s])
        return got.view(np.uint8) if got.dtype.kind == "b" else got.astype(self.dtype, copy=False)


def _bricks_marked(mask, step):
    """The bricks (the library's numbers, x fastest) of the array read every `step`-th sample that
    hold a cell whose far corner the mask marks: only they are meshed, so a mask saves the work
    of the bricks it leaves out (their triangles would all be dropped). The mask is read a layer
    of bricks' far corners at a time (a Dask or Zarr mask is never loaded whole)."""
    import numpy as np
    b = _vdiso._marching_cubes_brick
    cells = [(n - 1) // step for n in mask.shape]  # of the array read every step-th sample
    grid = [-(-n // b) for n in cells]
    marked = []
    for z in range(grid[0]):
        first, end = z * b, min((z + 1) * b, cells[0])  # the layer's cells along axis 0
        far = np.asarray(mask[(first + 1) * step:end * step + 1:step, step::step, step::step])
        far = far[:, :cells[1], :cells[2]].astype(bool, copy=False)
        padded = np.zeros((b, grid[1] * b, grid[2] * b), bool)
        padded[:far.shape[0], :far.shape[1], :far.shape[2]] = far
        hit = padded.reshape(b, grid[1], b, grid[2], b).any(axis=(0, 2, 4))
        marked.extend((z * grid[1] * grid[2] + np.flatnonzero(hit)).tolist())
    return marked


def _read_as(dtype):
    """The dtype an array of `dtype` read a part at a time is given to the library in: its own,
    or bool as uint8, float16 as float32 and the 64-bit integers as float64 (which the library
    holds as float32, as it holds them narrowed to 32 bits in memory: the same surface)."""
    import numpy as np
    dtype = np.dtype(dtype)
    kind, size = dtype.kind, dtype.itemsize
    return np.dtype(np.uint8 if kind == "b" else np.float32 if kind == "f" and size == 2
                    else np.float64 if kind in "iu" and size == 8 else dtype)


def _samples_at(array, z, y, x):
    """array[z, y, x] at the points given: a NumPy array indexed, a Dask or Zarr one read at
    those points only (vindex)."""
    import numpy as np
    if isinstance(array, np.ndarray):
        return array[z, y, x]
    got = array.vindex[z, y, x] if hasattr(array, "vindex") else np.asarray(array)[z, y, x]
    if hasattr(got, "compute"):
        got = got.compute()
    return np.asarray(got)


def _values_of_kept_cells(volume, level, step, faces, cells, kept, values):
    """`values` as scikit-image's with a mask: a vertex's largest spread over the cells it meshes
    only. The library counted every cell around the vertex's edge; a vertex that a dropped
    triangle uses, or that lies on a face of a brick not meshed, also lies in a cell the mask
    leaves out, so its value is made again from the kept triangles' cells (each triangle lies in
    one), their corners read where they lie.
    `cells`: each triangle's cell (its first corner, in samples / step); `kept`: the mask's word."""
    import numpy as np
    touched = np.zeros(len(values), bool)
    touched[faces[~kept].ravel()] = True
    # A brick the mask leaves out is not meshed (_bricks_marked): a vertex on its face has no
    # dropped triangle there, and all its triangles lie in its bricks' outer cells.
    brick = _vdiso._marching_cubes_brick
    outer = ((cells % brick == 0) | (cells % brick == brick - 1)).any(axis=1)
    again = kept & (touched[faces].any(axis=1) | outer)
    if not again.any():
        return values
    # Made again: the vertices all of whose kept triangles are among those (the others' values
    # already count only kept cells).
    uses = np.bincount(faces[kept].ravel(), minlength=len(values))
    redo = (uses == np.bincount(faces[again].ravel(), minlength=len(values))) & (uses > 0)
    if level is None:  # the middle of the values, as the library took it (32-bit floats at most)
        lo, hi = _range_of(volume)
        level = _vdiso._level_in(None, float(np.float32(lo)), float(np.float32(hi)))
    first = cells[again] * step
    corners = [first + np.array([dz, dy, dx]) * step for dz in (0, 1) for dy in (0, 1) for dx in (0, 1)]
    samples = np.stack([_samples_at(volume, c[:, 0], c[:, 1], c[:, 2]) for c in corners], axis=1)
    spread = _vdiso._cell_spreads(samples.astype(np.float64), level)
    best = np.zeros(len(values), np.float32)
    np.maximum.at(best, faces[again].ravel(), np.repeat(spread, 3))
    values = values.copy()
    values[redo] = best[redo]
    return values


def _range_of(volume):
    """The smallest and largest sample, NaN left out."""
    import numpy as np
    if isinstance(volume, np.ndarray):
        return np.nanmin(volume), np.nanmax(volume)
    if hasattr(volume, "__dask_graph__"):
        import dask
        import dask.array as da
        return dask.compute(da.nanmin(volume), da.nanmax(volume))
    lo, hi = np.inf, -np.inf
    for z in range(volume.shape[0]):
        layer = np.asarray(volume[z])
        lo, hi = min(lo, np.nanmin(layer)), max(hi, np.nanmax(layer))
    return lo, hi


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
