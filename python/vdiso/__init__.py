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
import os as _os
import errno as _errno
import threading as _threading

from . import _vdiso
from ._args import _float, _int, _z_chunk_bounds
from ._marching_cubes import marching_cubes
from ._vdiso import Error, Mesh, __version__

__all__ = ["marching_cubes", "convert", "index", "open", "serve", "Store", "Server", "Mesh", "Camera", "Error",
           "__version__"]


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
    # The picture's size is the camera's: a dict giving another is refused, not obeyed halfway.
    given = (camera.get("width", width), camera.get("height", height))
    if given != (width, height):
        raise ValueError(f"camera: width and height {given[0]} x {given[1]} differ from size {width} x {height} "
                         "(give one of them)")
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


def _import(package, method):
    """`package` imported, or an ImportError that says which method needs it."""
    import importlib
    try:
        return importlib.import_module(package)
    except ImportError:
        raise ImportError(f"Mesh.{method}() needs the {package} package, which is not installed "
                          f"(Debian 12 has none: pip install {package})") from None


def _mesh_to_trimesh(self):
    """The triangles as a trimesh.Trimesh (vertices world (x, y, z), faces, the vertex normals),
    as made: not merged or processed by trimesh. Needs trimesh."""
    trimesh = _import("trimesh", "to_trimesh")
    return trimesh.Trimesh(vertices=self.vertices, faces=self.faces, vertex_normals=self.normals, process=False)


def _mesh_to_pyvista(self):
    """The triangles as a pyvista.PolyData (points world (x, y, z), triangle faces, point data
    "Normals"). Needs pyvista."""
    import numpy as np
    pyvista = _import("pyvista", "to_pyvista")
    faces = np.hstack([np.full((len(self.faces), 1), 3, dtype=np.int64), self.faces.astype(np.int64)])
    data = pyvista.PolyData(np.asarray(self.vertices, dtype=np.float32), faces.ravel())
    data.point_data["Normals"] = self.normals
    return data


Mesh.to_meshio = _mesh_to_meshio
Mesh.to_trimesh = _mesh_to_trimesh
Mesh.to_pyvista = _mesh_to_pyvista
Mesh.napari_surface = _mesh_napari


def open(path, *, s3_endpoint="", anonymous=False, disk_cache=""):  # noqa: A001 (as vdiso.open)
    """open(path) -> Store: a .vdiso store on disk, or at an http(s):// or s3:// URL."""
    return Store(path, s3_endpoint=s3_endpoint, anonymous=anonymous, disk_cache=disk_cache)


def index(data, index=None, *, scale_level=0, brick=32, levels="auto", scale_levels=1, overwrite=False,
          restart=False, checkpoint_seconds=30, progress=None):
    """index(data, index=None, *, scale_level=0, brick=32, levels="auto", scale_levels=1, overwrite=False,
    restart=False, checkpoint_seconds=30, progress=None) -> dict

    Indexes a Zarr array or OME-Zarr image (a folder, or an http(s):// or s3:// URL) where it
    lies, as `vdiso index` does: then vdiso.open(data) (a folder finds its index beside it,
    data + ".vdiso") or vdiso.open(index) reads it like a store, without a converted copy.
    A call that stops (Ctrl-C, a failed read) leaves INDEX.partial and INDEX.resume, where the
    pass stood at most about checkpoint_seconds before; the same call again goes on from there
    (restart=True starts over). An OME-Zarr's own 2x scales are the first `scale_levels` coarse
    levels where they fit, read where they lie (`vdiso index --scale-levels`; 0: vdiso's filtered
    levels, kept in the index).
    Returns what was written: the index's path and bytes ("index", "file_bytes"), the chunks
    indexed, the data's bytes as stored ("data_bytes"), the layers of bricks an interrupted
    call had done ("resumed_layers" of "layers"), the levels taken from the image's scales
    ("own_scale_levels") and why the next scale was not ("scales_not_used")."""
    return _vdiso._index(str(data), "" if index is None else str(index), _int(scale_level, "scale_level"),
                         _int(brick, "brick"), str(levels), _int(scale_levels, "scale_levels"), bool(overwrite), bool(restart),
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
