"""vdiso from Python: isosurfaces of volumes larger than memory, and of what a camera sees.

    import vdiso
    verts, faces, normals, values = vdiso.marching_cubes(volume, level)   # as scikit-image
    vdiso.convert(array_or_path, "head.vdiso")                            # NumPy, Zarr, Dask, files
    store = vdiso.open("head.vdiso")                                      # or an http(s):// or s3:// URL
    mesh = store.extract(600, method="sage", view="normal")               # the visible surface
    image = store.render(600)                                             # (H, W, 3) uint8

Conventions: marching_cubes answers as scikit-image (vertices z, y, x in index units times
spacing, faces int32); a Mesh from a Store is in world space (vertices x, y, z in physical
units, faces uint32; napari_surface() gives z, y, x). An isovalue outside the data is a
ValueError everywhere. Long calls release the GIL, stop on Ctrl-C (KeyboardInterrupt, nothing
written) and take progress=callable(done, total). Errors: ValueError for a bad argument (naming it), TypeError for
an argument of the wrong type (naming it), OSError for I/O (naming the file or URL),
FileExistsError for an output that exists, vdiso.Error for the rest.
"""

import json as _json
import operator as _operator
import os as _os
import errno as _errno
import threading as _threading

from . import _vdiso
from ._vdiso import Error, Mesh, __version__

__all__ = ["marching_cubes", "convert", "index", "open", "serve", "Store", "Server", "Mesh", "Camera", "Error",
           "__version__"]


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
    scikit-image's (the whole volume is meshed first: a mask saves no time here). method: "lorensen" only; "lewiner" is refused
    (its ambiguity resolution is not implemented), never answered with another surface.
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
        spacing = tuple(_float(s, "spacing") * step for s in spacing)
    verts, faces, normals, values = _vdiso.marching_cubes(
        volume, None if level is None else _float(level, "level"), tuple(_float(s, "spacing") for s in spacing),
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
    if step > 1 and all(_float(s, "spacing") == step for s in spacing):
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


def _int(value, name):
    """`value` as a Python int for the library, which checks its range and names `name`."""
    if isinstance(value, bool):
        raise TypeError(f"{name}: expects an integer, not bool")
    try:
        v = _operator.index(value)
    except TypeError:
        raise TypeError(f"{name}: expects an integer, not {type(value).__name__}") from None
    if not -2 ** 63 <= v < 2 ** 63:
        raise ValueError(f"{name}: expects a value the library can hold, not {v}")
    return v


def _float(value, name):
    """`value` as a float, or a TypeError naming `name`."""
    try:
        return float(value)
    except (TypeError, ValueError):
        raise TypeError(f"{name}: expects a number, not {type(value).__name__}") from None


class Camera:
    """A camera in world space: eye, target, up (x, y, z) and a vertical field of view in degrees,
    as `vdiso extract --camera` reads it."""

    def __init__(self, eye, target, up=(0.0, 0.0, 1.0), fov=30.0):
        self.eye, self.target, self.up, self.fov = tuple(eye), tuple(target), tuple(up), float(fov)

    def to_dict(self):
        return {"eye": list(self.eye), "target": list(self.target), "up": list(self.up), "fov": self.fov}

    def __repr__(self):
        return f"vdiso.Camera(eye={self.eye}, target={self.target}, up={self.up}, fov={self.fov})"


_CAMERA_FIELDS = ("eye", "target", "up", "fov", "width", "height", "near", "far")


def _camera(camera, width, height):
    """The library's camera struct for a vdiso.Camera or a dict of its fields (width and height
    default to the picture's); the library checks it (core/camera.h)."""
    if camera is None:
        return None
    if isinstance(camera, Camera):
        camera = camera.to_dict()
    if not isinstance(camera, dict):
        raise ValueError(f"camera: expects a dict with eye, target, up, fov or a vdiso.Camera, not {type(camera).__name__}")
    for name in camera:
        if name not in _CAMERA_FIELDS:
            raise ValueError(f"camera: unknown field {name!r} (expected {', '.join(_CAMERA_FIELDS)})")
    for name in _CAMERA_FIELDS[:4]:
        if name not in camera:
            raise ValueError(f"camera: {name!r} missing")
    try:
        return _vdiso._Camera(**{"width": width, "height": height, **camera})
    except TypeError:
        raise TypeError("camera: eye, target and up expect 3 numbers each, fov, near and far a number, "
                        "width and height a whole number") from None


def _size(size):
    """(width, height) checked; None: the library's default, as `vdiso extract --size`'s (800 x 800)."""
    if size is None:
        return _vdiso._default_size
    try:
        width, height = (int(v) for v in size)
    except (TypeError, ValueError):
        raise ValueError(f"size: expects (width, height), not {size!r}") from None
    low, high = _vdiso._min_image_side, _vdiso._max_image_side  # core/camera.h's
    if not (low <= width <= high and low <= height <= high):
        raise ValueError(f"size: expects {low} to {high} pixels each way, not {width} x {height}")
    return width, height


def _local_input(path, what):
    """Raises FileNotFoundError / PermissionError for a local path that is not there or not
    readable, before the library is asked."""
    path = _os.fspath(path)
    if "://" in path:
        return path
    probe = path.split(":/", 1)[0] if ".h5:/" in path or ".hdf5:/" in path else path
    if not any(c in probe for c in "*?[") and not _os.path.exists(probe):
        raise FileNotFoundError(_errno.ENOENT, f"{what}: no such file or folder", probe)
    if _os.path.exists(probe) and not _os.access(probe, _os.R_OK):
        raise PermissionError(_errno.EACCES, f"{what}: not readable", probe)
    return path


def _reopen(path, s3_endpoint, anonymous, disk_cache):
    """What unpickling a Store calls: the store opened again where it lies."""
    return Store(path, s3_endpoint=s3_endpoint, anonymous=anonymous, disk_cache=disk_cache)


class Store:
    """A brick store opened for extraction (vdiso.open). shape, spacing: NumPy's axis order (z, y, x),
    as convert() and marching_cubes take them; origin and mesh vertices: world (x, y, z).
    A context manager (close() on leaving); pickled as where it lies, and opened again there."""

    def __init__(self, path, *, s3_endpoint="", anonymous=False, disk_cache=""):
        self._opened = (_local_input(path, "store"), str(s3_endpoint), bool(anonymous), _os.fspath(disk_cache))
        self._store = _vdiso._Store(*self._opened)
        self._live = None  # the session extract() and render() share (_shared)
        self._lock = _threading.Lock()

    def _open(self):
        if self._store is None:
            raise ValueError(f"vdiso.Store {self._opened[0]}: closed")
        return self._store

    def close(self):
        """Lets go of the store: its file or connections, its brick cache. Calls after it raise
        ValueError; closing twice is allowed."""
        with self._lock:
            self._live = None
            self._store = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def __reduce__(self):
        return _reopen, self._opened

    path = property(lambda self: self._open().path, doc="the store's path or URL")
    shape = property(lambda self: tuple(reversed(self._open().dims)), doc="(z, y, x) samples")
    dtype = property(lambda self: self._open().dtype, doc="the samples' NumPy dtype")
    spacing = property(lambda self: tuple(reversed(self._open().spacing_xyz)), doc="(z, y, x) sample spacing")
    origin = property(lambda self: self._open().origin_xyz, doc="world (x, y, z) of sample 0")
    orientation = property(lambda self: self._open().direction,
                           doc="3x3 LPS directions of the x, y, z axes (columns), or None")
    levels = property(lambda self: self._open().levels, doc="levels of detail, the full resolution included")
    value_range = property(lambda self: self._open().value_range, doc="(min, max) of the samples")

    def _check_iso(self, iso):
        """An isovalue outside the samples is a ValueError, as marching_cubes and scikit-image say."""
        iso = _float(iso, "iso")
        low, high = self.value_range
        if not low <= iso <= high:
            raise ValueError(f"iso: {iso} lies outside the store's values, {low} to {high}")
        return iso

    def histogram(self):
        """(counts, edges): the store's 256-bin histogram of sample values."""
        return self._open().histogram()

    def info(self, iso=None):
        """What `vdiso info --json` prints, as a dict."""
        return _json.loads(self._open().info_json(iso))

    @staticmethod
    def _settings(iso, method="octree", lod_error=None, threads=None, cache_mb=None, largest=False,
                  min_piece=0, smooth=0, decimate=None, mesh_space="physical"):
        # None: the library's default (lod_error 1, cache_mb 1024: app/extract_settings.h).
        return (method, _float(iso, "iso"), None if lod_error is None else _float(lod_error, "lod_error"),
                _int(0 if threads is None else threads, "threads"),
                None if cache_mb is None else _int(cache_mb, "cache_mb"), bool(largest), _int(min_piece, "min_piece"),
                _int(smooth, "smooth"), 1.0 if decimate is None else _float(decimate, "decimate"),
                _mesh_space_is_volume(mesh_space))

    def _session(self, iso, method="octree", **settings):
        """A session of its own (a path of frames keeps its settings)."""
        return _vdiso._Session(self._open(), *self._settings(iso, method, **settings))

    def _shared(self, iso, method="octree", **settings):
        """The store's one session, set to these settings: its brick cache and tree are kept from
        call to call, so a second extract() reads no brick the first left in the cache. Call with
        self._lock held: one extraction at a time per Store (open the store twice to run two)."""
        values = self._settings(iso, method, **settings)
        if self._live is None:
            self._live = _vdiso._Session(self._open(), *values)
        else:
            self._live.configure(*values)
        return self._live

    def extract(self, iso, *, method="octree", camera=None, view=None, size=None, lod_error=None,
                threads=None, cache_mb=None, largest=False, min_piece=0, smooth=0, decimate=None,
                mesh_space="physical", progress=None):
        """extract(iso, *, method="octree", camera=None, view=None, size=None, lod_error=None,
        threads=None, cache_mb=None, largest=False, min_piece=0, smooth=0, decimate=None,
        mesh_space="physical", progress=None) -> Mesh

        The isosurface `iso` as `vdiso extract` makes it. method: "octree" or "noise" (the whole
        surface), "sage" or "wise" (what `camera` sees, at the levels of detail `lod_error`
        pixels allow). camera: a dict with eye, target, up, fov or a vdiso.Camera; view: the
        --view words ("normal", "distant", "closeup", with a side: "normal,left"); neither: the
        normal view. An iso outside the store's values is a ValueError. size: (width, height) of the picture the view is for, by default the
        command line's (800, 800); lod_error and cache_mb default to the command line's too.
        largest, min_piece, smooth, decimate: post-processing of the full surface. mesh_space:
        "physical" (world x, y, z: the store's origin, spacing and orientation applied) or
        "volume" (origin + (x, y, z) sample indices times spacing, the store's own axes, as
        `vdiso extract --mesh-space volume`): marching_cubes's vertices of the same array are
        then (mesh.vertices - store.origin)[:, ::-1]. Calls on one Store share its brick cache and tree (a second call reads no brick the first
        left in the cache) and run one at a time; open the store twice to extract in parallel.
        """
        width, height = _size(size)
        iso = self._check_iso(iso)
        with self._lock:
            session = self._shared(iso, method, lod_error=lod_error, threads=threads, cache_mb=cache_mb, largest=largest,
                                   min_piece=min_piece, smooth=smooth, decimate=decimate, mesh_space=mesh_space)
            return session.extract(_camera(camera, width, height), view or "normal", width, height, progress)

    def frames(self, iso, cameras, *, size=None, **settings):
        """A generator of Meshes, one per camera (dicts, vdiso.Camera or view words), over one
        brick cache, as `vdiso extract --path`. Takes extract()'s settings."""
        width, height = _size(size)
        _check_settings(settings, "frames")
        settings.setdefault("method", "sage")
        session = self._session(self._check_iso(iso), **settings)
        for camera in cameras:
            if isinstance(camera, str):
                yield session.extract(None, camera, width, height)
            else:
                yield session.extract(_camera(camera, width, height), "normal", width, height)

    def render(self, iso, camera=None, view="normal", size=None, method="sage", **settings):
        """render(iso, camera=None, view="normal", size=None, method="sage", **settings) -> (H, W, 3) uint8

        The surface drawn as `vdiso extract --png` draws it (OSMesa), for a notebook. settings:
        extract()'s (lod_error, threads, cache_mb, ...)."""
        width, height = _size(size)
        _check_settings(settings, "render")
        iso = self._check_iso(iso)
        with self._lock:
            return self._shared(iso, method, **settings).render(_camera(camera, width, height), view or "normal", width, height)

    def __repr__(self):
        if self._store is None:
            return f"<vdiso.Store {self._opened[0]}: closed>"
        return f"<vdiso.Store {self.path}: {self.shape} {self.dtype}, {self.levels} levels>"


_SETTINGS = ("method", "lod_error", "threads", "cache_mb", "largest", "min_piece", "smooth", "decimate", "mesh_space")


def _mesh_space_is_volume(mesh_space):
    if mesh_space not in ("physical", "volume"):
        raise ValueError(f"mesh_space: expects \"physical\" or \"volume\", not {mesh_space!r}")
    return mesh_space == "volume"


def _check_settings(settings, function):
    """Keywords a Store method passes on, checked against extract()'s so that a typo is named
    with the public method it was given to."""
    for name in settings:
        if name not in _SETTINGS:
            raise TypeError(f"Store.{function}() got an unexpected keyword argument {name!r} "
                            f"(it takes {', '.join(_SETTINGS)})")


def _mesh_to_meshio(self):
    """The triangles as a meshio.Mesh (points world (x, y, z), "triangle" cells, point data
    "Normals"), for meshio's writers and readers of other formats. Needs meshio."""
    import meshio
    return meshio.Mesh(self.vertices, [("triangle", self.faces)], point_data={"Normals": self.normals})


def _mesh_napari(self):
    """(vertices, faces, values) as napari's add_surface takes them: vertices in napari's axis order
    (z, y, x), world units; values zeros (one per vertex)."""
    import numpy as np
    return (np.ascontiguousarray(self.vertices[:, ::-1]), self.faces, np.zeros(len(self.vertices), np.float32))


Mesh.to_meshio = _mesh_to_meshio
Mesh.napari_surface = _mesh_napari


def open(path, *, s3_endpoint="", anonymous=False, disk_cache=""):  # noqa: A001 (as vdiso.open)
    """open(path) -> Store: a .vdiso store on disk, or at an http(s):// or s3:// URL."""
    return Store(path, s3_endpoint=s3_endpoint, anonymous=anonymous, disk_cache=disk_cache)


def index(data, index=None, *, scale_level=0, brick=32, levels="auto", overwrite=False, restart=False,
          checkpoint_seconds=30, progress=None):
    """index(data, index=None, *, scale_level=0, brick=32, levels="auto", overwrite=False, restart=False,
    checkpoint_seconds=30, progress=None) -> dict

    Indexes a Zarr array or OME-Zarr image (a folder, or an http(s):// or s3:// URL) where it
    lies, as `vdiso index` does: then vdiso.open(data) (a folder finds its index beside it,
    data + ".vdiso") or vdiso.open(index) reads it like a store, without a converted copy.
    A call that stops (Ctrl-C, a failed read) leaves INDEX.partial and INDEX.resume, where the
    pass stood at most about checkpoint_seconds before; the same call again goes on from there
    (restart=True starts over). Returns what was written: the
    index's path and bytes ("index", "file_bytes"), the chunks indexed, the data's bytes as
    stored ("data_bytes"), and the layers of bricks an interrupted call had done
    ("resumed_layers" of "layers")."""
    return _vdiso._index(str(data), "" if index is None else str(index), _int(scale_level, "scale_level"),
                         _int(brick, "brick"), str(levels), bool(overwrite), bool(restart),
                         float(checkpoint_seconds), progress)


def convert(source, path, *, spacing=None, origin=None, brick=32, levels="auto", compress="lz4",
            overwrite=False, progress=None):
    """convert(source, path, *, spacing=None, origin=None, brick=32, levels="auto", compress="lz4",
    overwrite=False, progress=None) -> dict

    Writes a brick store at `path` from `source`: a file or folder in any format `vdiso convert`
    reads (a list of slice files too), or a NumPy, Zarr or Dask array, or any object with shape,
    dtype and slicing along axis 0. An array is read slab by slab along axis 0, so one larger
    than memory converts in the converter's bounded memory; a Dask or Zarr array a whole chunk's
    slab at a time, so that no chunk is computed or decoded twice. spacing: (z, y, x) as
    marching_cubes takes it; origin: world (x, y, z) (arrays only). The store appears only when
    complete. Returns what was written (bricks, levels, bytes, seconds)."""
    path = _os.fspath(path)
    levels = str(levels)
    if isinstance(source, (str, bytes, _os.PathLike)) or (
            isinstance(source, (list, tuple)) and source and isinstance(source[0], (str, _os.PathLike))):
        if origin is not None:
            raise ValueError("origin: applies to array sources (a file states its own)")
        inputs = [source] if not isinstance(source, (list, tuple)) else list(source)
        inputs = [_local_input(p, "source") for p in inputs]
        spacing = None if spacing is None else tuple(float(s) for s in spacing)
        return _vdiso._convert_files(inputs, path, spacing, _int(brick, "brick"), levels, compress, bool(overwrite),
                                     progress)
    import numpy as np
    for attr in ("shape", "dtype", "__getitem__"):
        if not hasattr(source, attr):
            raise ValueError(f"source: expects a path or an array-like with shape, dtype and slicing, "
                             f"not {type(source).__name__}")
    name = f"{type(source).__module__}.{type(source).__name__}"
    shape = [int(n) for n in source.shape]
    spacing = (1.0, 1.0, 1.0) if spacing is None else tuple(float(s) for s in spacing)
    origin = (0.0, 0.0, 0.0) if origin is None else tuple(float(s) for s in origin)
    return _vdiso._convert_array(source, name, shape, np.dtype(source.dtype), path, spacing, origin,
                                 _int(brick, "brick"), levels, compress, bool(overwrite), _z_chunk_bounds(source, shape),
                                 progress)


def _z_chunk_bounds(source, shape):
    """Where a chunked array's chunks begin along axis 0, and its end (Dask: a size per chunk;
    Zarr: one size): convert reads whole chunks, so none is computed or decoded twice. [] for an
    array without chunks."""
    chunks = getattr(source, "chunks", None)
    if not isinstance(chunks, tuple) or not chunks:
        return []
    first = chunks[0]
    try:
        sizes = [int(c) for c in first] if isinstance(first, tuple) else None
        depth = None if sizes is not None else int(first)
    except (TypeError, ValueError):
        return []
    if sizes is None:
        if depth <= 0:
            return []
        sizes = [min(depth, shape[0] - z) for z in range(0, shape[0], depth)]
    bounds = [0]
    for size in sizes:
        bounds.append(bounds[-1] + size)
    return bounds


class Server:
    """A running `vdiso serve` (vdiso.serve): url, stop(), a context manager; in Jupyter it shows the
    viewer in an iframe."""

    def __init__(self, stores, iso=None, port=0, host="127.0.0.1", *, cache_mb=None, threads=None,
                 lod_error=None, web_root=None, max_viewers=None):
        if isinstance(stores, (str, bytes, _os.PathLike)):
            stores = [stores]
        stores = [_local_input(s, "store") for s in stores]
        optional = lambda value, check, name: None if value is None else check(value, name)  # noqa: E731
        self._server = _vdiso._Server(stores, optional(iso, _float, "iso"), _int(port, "port"), str(host),
                                      optional(cache_mb, _int, "cache_mb"), optional(threads, _int, "threads"),
                                      optional(lod_error, _float, "lod_error"), web_root or _vdiso._web_root,
                                      _int(0 if max_viewers is None else max_viewers, "max_viewers"))

    url = property(lambda self: self._server.url, doc="http://HOST:PORT/?token=... (the token is the key)")
    port = property(lambda self: self._server.port)
    running = property(lambda self: self._server.running)

    def stop(self):
        """Closes every connection and stops the server; returns when it has stopped."""
        self._server.stop()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.stop()

    def _repr_html_(self):
        return f'<iframe src="{self.url}" width="100%" height="600" style="border:0"></iframe>'

    def __repr__(self):
        return f"<vdiso.Server {self.url} ({'running' if self.running else 'stopped'})>"


def serve(stores, iso=None, port=0, host="127.0.0.1", **options):
    """serve(stores, iso=None, port=0, host="127.0.0.1", *, cache_mb=None, threads=None, lod_error=None,
    max_viewers=None)
    -> Server

    `vdiso serve` in this process, on its own thread: the browser viewer of one or more stores
    (paths or URLs) at server.url. port 0: any free port. cache_mb, threads, lod_error and
    max_viewers left out: `vdiso serve`'s defaults (`vdiso serve --help`). Use as a context
    manager, or stop()."""
    return Server(stores, iso, port, host, **options)
