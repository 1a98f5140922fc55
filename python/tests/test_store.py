"""vdiso.convert, vdiso.open and Store against the command line, with real NumPy, Zarr and Dask."""
import json
import os
import signal
import time

import dask.array as da
import numpy as np
import pytest
import zarr

import vdiso
from conftest import at_once, interrupt, python_child, run


def head(shape=(40, 50, 60), dtype=np.uint16):
    z, y, x = np.mgrid[: shape[0], : shape[1], : shape[2]].astype(np.float64)
    r = np.sqrt(((x - 31) / 1.2) ** 2 + (y - 24) ** 2 + ((z - 19) * 1.1) ** 2)
    v = 1000 - 40 * r + 30 * np.sin(x / 3) * np.cos(y / 4)
    return np.clip(v, 0, 1000).astype(dtype)


@pytest.fixture
def volume_and_cli_store(tmp_path, vdiso_bin):
    v = head()
    raw = tmp_path / "v.raw"
    v.tofile(raw)
    cli = tmp_path / "cli.vdiso"
    r = run([vdiso_bin, "convert", str(raw), str(cli), "--dims", "60,50,40", "--type", "u16", "--quiet"])
    assert r.returncode == 0, r.stderr
    return v, cli


@pytest.mark.parametrize("kind", ["numpy", "fortran", "zarr", "dask"])
def test_convert_equals_the_command_line_byte_for_byte(tmp_path, volume_and_cli_store, kind):
    v, cli = volume_and_cli_store
    source = {"numpy": lambda: v, "fortran": lambda: np.asfortranarray(v),
              "zarr": lambda: zarr.array(v, chunks=(7, 50, 60)),
              "dask": lambda: da.from_array(v, chunks=(9, 25, 60))}[kind]()
    out = tmp_path / "py.vdiso"
    seen = []
    summary = vdiso.convert(source, out, progress=lambda done, total: seen.append((done, total)))
    assert summary["bricks"] > 0
    assert out.read_bytes() == cli.read_bytes()
    assert seen and seen[-1][0] == seen[-1][1]


def test_convert_a_file_and_open_it(tmp_path, volume_and_cli_store):
    v, cli = volume_and_cli_store
    store = vdiso.open(cli)
    assert store.shape == v.shape and store.dtype == np.uint16 and store.spacing == (1.0, 1.0, 1.0)
    assert store.value_range == (float(v.min()), float(v.max()))
    counts, edges = store.histogram()
    assert counts.sum() == v.size and len(edges) == len(counts) + 1
    assert store.info()["dims"] == [60, 50, 40] and store.levels == store.info()["levels"][-1]["level"] + 1
    nrrd = tmp_path / "v.nhdr"
    nrrd.write_text("NRRD0004\ntype: uint16\ndimension: 3\nsizes: 60 50 40\nspacings: 0.5 0.5 2\n"
                    "encoding: raw\nendian: little\ndata file: v.raw\n")
    vdiso.convert(str(nrrd), tmp_path / "n.vdiso")
    assert vdiso.open(tmp_path / "n.vdiso").spacing == (2.0, 0.5, 0.5)


@pytest.mark.parametrize("method", ["octree", "sage"])
def test_extract_equals_the_command_line(tmp_path, vdiso_bin, volume_and_cli_store, method):
    _, cli = volume_and_cli_store
    r = run([vdiso_bin, "extract", str(cli), "--iso", "500.5", "--method", method, "--stats", "-", "--quiet",
             "--size", "320x240"])
    assert r.returncode == 0, r.stderr
    theirs = json.loads(r.stdout.splitlines()[-1])
    mesh = vdiso.open(cli).extract(500.5, method=method, size=(320, 240))
    assert mesh.stats["triangles"] == theirs["triangles"] == len(mesh.faces)
    assert len(mesh.vertices) == mesh.stats["vertices"]
    # The arrays are the mesh's own buffers.
    for name in ("vertices", "normals", "faces", "points", "point_normals"):
        array = getattr(mesh, name)
        assert array.base is mesh and not array.flags.owndata
    assert mesh.vertices.dtype == np.float32 and mesh.faces.dtype == np.uint32
    if method == "octree":
        same = vdiso.marching_cubes(head(), 500.5)
        assert len(same[1]) == len(mesh.faces)
    out = tmp_path / "m.glb"
    mesh.write(out)
    with pytest.raises(FileExistsError, match="overwrite=True"):
        mesh.write(out)
    mesh.write(out, overwrite=True)


def test_defaults_are_the_command_lines(vdiso_bin, volume_and_cli_store):
    """size, lod_error and cache_mb left out: the library's defaults, which the command line takes."""
    _, cli = volume_and_cli_store
    r = run([vdiso_bin, "extract", str(cli), "--iso", "500.5", "--method", "sage", "--stats", "-", "--quiet"])
    assert r.returncode == 0, r.stderr
    theirs = json.loads(r.stdout.splitlines()[-1])
    mine = vdiso.open(cli).extract(500.5, method="sage").stats
    for key in ("triangles", "vertices", "points", "lod_error"):
        assert mine[key] == theirs[key], key


def test_frames_and_render(volume_and_cli_store):
    _, cli = volume_and_cli_store
    store = vdiso.open(cli)
    frames = list(store.frames(500.5, ["normal", "distant", {"eye": [30, -150, 20], "target": [30, 25, 20],
                                                               "up": [0, 0, 1], "fov": 30}], size=(200, 200)))
    assert len(frames) == 3 and all(len(f.faces) > 0 for f in frames)
    image = store.render(500.5, size=(96, 64))
    assert image.shape == (64, 96, 3) and image.dtype == np.uint8 and image.std() > 5


def test_refusals(tmp_path, volume_and_cli_store):
    v, cli = volume_and_cli_store
    store = vdiso.open(cli)
    with pytest.raises(ValueError, match="method expects"):
        store.extract(500, method="marching")
    with pytest.raises(ValueError, match="iso"):
        store.extract(float("nan"))
    with pytest.raises(ValueError, match="lod_error applies"):
        store.extract(500, lod_error=2)
    with pytest.raises(ValueError, match="view"):
        store.extract(500, method="sage", view="sideways")
    with pytest.raises(ValueError, match="camera"):
        store.extract(500, method="sage", camera=[1, 2, 3])
    with pytest.raises(ValueError, match="camera"):
        store.extract(500, method="sage", camera={"eye": [1, 2, 3]})
    with pytest.raises(FileNotFoundError):
        vdiso.open(tmp_path / "missing.vdiso")
    (tmp_path / "junk.vdiso").write_bytes(b"not a store at all" * 10)
    with pytest.raises(OSError, match="junk.vdiso"):
        vdiso.open(tmp_path / "junk.vdiso")
    with pytest.raises(FileExistsError):
        vdiso.convert(v, cli)
    with pytest.raises(ValueError, match="3-D"):
        vdiso.convert(np.zeros((4, 4)), tmp_path / "a.vdiso")
    with pytest.raises(ValueError, match="not supported"):
        vdiso.convert(np.zeros((4, 4, 4), dtype=np.complex64), tmp_path / "a.vdiso")
    with pytest.raises(ValueError, match="at least 2"):
        vdiso.convert(np.zeros((4, 0, 4), dtype=np.uint8), tmp_path / "a.vdiso")
    with pytest.raises(ValueError, match="compress"):
        vdiso.convert(v, tmp_path / "a.vdiso", compress="gzip")
    with pytest.raises(ValueError, match="source"):
        vdiso.convert(42, tmp_path / "a.vdiso")
    # Every bad argument named in the library's words: no pybind11 signature dump.
    for kwargs, message in [({"threads": 2 ** 31}, "threads expects 0 to 256"),
                            ({"cache_mb": -1}, "cache_mb expects 1 to"),
                            ({"min_piece": -5}, "min_piece expects 0 to"),
                            ({"smooth": 2 ** 40}, "smooth expects 0 to 1000")]:
        with pytest.raises(ValueError, match=message):
            store.extract(500, **kwargs)
    with pytest.raises(TypeError, match="threads: expects an integer, not float"):
        store.extract(500, threads=1.5)
    with pytest.raises(ValueError, match="brick expects 2 to 512"):
        vdiso.convert(v, tmp_path / "b.vdiso", brick=2 ** 33)
    # A NaN camera is named as one; an eye beyond the arithmetic's reach as too far.
    camera = {"eye": [float("nan"), 0, 0], "target": [0, 0, 0], "up": [0, 0, 1], "fov": 30}
    with pytest.raises(ValueError, match="camera: .*finite"):
        store.extract(500, method="sage", camera=camera)
    camera["eye"] = [1e300, 0, 0]
    with pytest.raises(ValueError, match="too far from target"):
        store.extract(500, method="sage", camera=camera)
    # The camera crosses as a struct: its fields named, the library's one check applied.
    camera["eye"] = [-60, 20, 20]
    with pytest.raises(ValueError, match="camera: unknown field 'fovy'"):
        store.extract(500, method="sage", camera={**camera, "fovy": 30})
    with pytest.raises(ValueError, match="camera: near and far go together"):
        store.extract(500, method="sage", camera={**camera, "near": 1})
    with pytest.raises(ValueError, match="camera: near and far must satisfy 0 < near < far"):
        store.extract(500, method="sage", camera={**camera, "near": 2, "far": 1})
    with pytest.raises(TypeError, match="camera: eye, target and up expect 3 numbers"):
        store.extract(500, method="sage", camera={**camera, "eye": ["a", 0, 0]})
    same = vdiso.Camera(eye=camera["eye"], target=camera["target"], up=camera["up"], fov=camera["fov"])
    a = store.extract(500, method="sage", camera=camera, size=(64, 48))
    b = store.extract(500, method="sage", camera=same, size=(64, 48))
    assert a.stats["triangles"] > 0 and np.array_equal(a.faces, b.faces)
    assert np.array_equal(a.vertices, b.vertices)
    # A volume with no finite sample has no isosurface: refused at conversion, nothing written.
    with pytest.raises(OSError, match="no finite sample"):
        vdiso.convert(np.full((8, 8, 8), np.nan, np.float32), tmp_path / "nan.vdiso")
    assert not (tmp_path / "nan.vdiso").exists()

    class Liar:
        """Says one shape and slices into another."""
        shape, dtype = (10, 8, 8), np.dtype(np.uint8)

        def __getitem__(self, key):
            return np.zeros((3, 8, 7), dtype=np.uint8)

    with pytest.raises(OSError, match="came back with shape"):
        vdiso.convert(Liar(), tmp_path / "liar.vdiso")
    assert not (tmp_path / "liar.vdiso").exists() and not (tmp_path / "a.vdiso").exists()


LAZY = """
import resource, sys
import dask.array as da, numpy as np
import vdiso
limit = {limit}
resource.setrlimit(resource.RLIMIT_DATA, (limit, limit))
n = {n}
def block(block_info=None):
    (z0, z1), (y0, y1), (x0, x1) = block_info[None]["array-location"]
    out = np.empty((z1 - z0, y1 - y0, x1 - x0), np.uint8)
    out[:] = (np.arange(y0, y1)[:, None] + np.arange(x0, x1)[None, :]) % 251
    out += (np.arange(z0, z1) % 5).astype(np.uint8)[:, None, None]
    return out
volume = da.map_blocks(block, dtype=np.uint8, chunks=((16,) * (n // 16), (n,), (n,)))
print("ready", flush=True)
vdiso.convert(volume, {out!r}, brick=32)
print("done", resource.getrusage(resource.RUSAGE_SELF).ru_maxrss >> 10, flush=True)
"""


def test_a_dask_array_larger_than_the_memory_limit_converts(tmp_path):
    n = 1024  # 1 GiB of samples, generated chunk by chunk, under a 600 MB data limit
    out = tmp_path / "lazy.vdiso"
    child = python_child(LAZY.format(limit=600 << 20, n=n, out=str(out)))
    stdout, stderr = child.communicate(timeout=600)
    assert child.returncode == 0, stderr
    assert "done" in stdout
    store = vdiso.open(out)
    assert store.shape == (n, n, n) and store.value_range == (0.0, 254.0)


def test_ctrl_c_stops_within_a_second_and_writes_nothing(tmp_path):
    out = tmp_path / "never.vdiso"
    child = python_child(LAZY.format(limit=-1, n=2048, out=str(out)))
    assert child.stdout.readline().strip() == "ready"
    time.sleep(1.5)
    waited = interrupt(child)
    assert not out.exists() and not any(p.name.startswith("never") for p in tmp_path.iterdir())
    assert waited < 5, f"stopped {waited:.1f} s after Ctrl-C"


MC_CHILD = """
import sys
import numpy as np
import vdiso
a = (np.sin(np.arange(640) / 40.0) * 60 + 70).astype(np.uint16)
v = a[:, None, None] + a[None, :, None] + a[None, None, :]
said = []
def progress(done, total):
    if not said:
        said.append(1)
        print("working", done <= total, flush=True)
vdiso.marching_cubes(v, 210.5, threads=1, progress=progress)
print("done", flush=True)
"""


def test_marching_cubes_reports_progress_and_stops_within_a_second():
    child = python_child(MC_CHILD)
    assert child.stdout.readline().strip() == "working True"
    waited = interrupt(child)
    assert waited < 1, f"stopped {waited:.2f} s after Ctrl-C"


def test_serve_shows_the_viewer_and_stops(volume_and_cli_store):
    import urllib.error
    import urllib.request
    _, cli = volume_and_cli_store
    with vdiso.serve(str(cli), iso=500.5) as server:
        assert server.running and server.url.startswith("http://127.0.0.1:")
        page = urllib.request.urlopen(server.url, timeout=30).read().decode()
        assert "<html" in page.lower()
        assert server.url in server._repr_html_()
        with pytest.raises(urllib.error.HTTPError):
            urllib.request.urlopen(server.url.split("?")[0] + "?token=wrong", timeout=30)
    assert not server.running
    with pytest.raises(OSError):
        urllib.request.urlopen(server.url, timeout=5)
    with pytest.raises(FileNotFoundError):
        vdiso.serve("missing.vdiso")
    with pytest.raises(ValueError, match="lod_error expects"):
        vdiso.serve(str(cli), lod_error=-1)
    with pytest.raises(ValueError, match="port expects"):
        vdiso.serve(str(cli), port=70000)
    with pytest.raises(ValueError, match="cache_mb expects"):
        vdiso.serve(str(cli), cache_mb=-1)
    with pytest.raises(ValueError, match="threads expects"):
        vdiso.serve(str(cli), threads=2 ** 31)
    with pytest.raises(ValueError, match="threads expects 1 to 64 image strips"):  # the server's one check
        vdiso.serve(str(cli), threads=100)


@pytest.fixture
def s3_bucket(tmp_path):
    """tests/remote/s3_server.py on loopback: a real SigV4 check (botocore's), a bucket in tmp_path."""
    import subprocess
    import sys as _sys
    from conftest import ROOT
    root = tmp_path / "s3"
    (root / "bucket").mkdir(parents=True)
    server = subprocess.Popen(["/usr/bin/python3", os.path.join(ROOT, "tests", "remote", "s3_server.py"),
                               "--root", str(root), "--cred", "AKIDPYTHONTEST:pythontestsecret", "--lifetime", "600",
                               "--parent-pid", str(os.getpid())], stdout=subprocess.PIPE, text=True)
    line = server.stdout.readline().split()
    assert line and line[0] == "PORT", line
    env = {"AWS_ACCESS_KEY_ID": "AKIDPYTHONTEST", "AWS_SECRET_ACCESS_KEY": "pythontestsecret",
           "AWS_ENDPOINT_URL": f"http://127.0.0.1:{line[1]}", "AWS_REGION": "us-east-1",
           "AWS_SHARED_CREDENTIALS_FILE": "/nonexistent", "AWS_CONFIG_FILE": "/nonexistent"}
    saved = {k: os.environ.get(k) for k in env}
    os.environ.update(env)
    yield root / "bucket"
    for k, v in saved.items():
        if v is None:
            os.environ.pop(k, None)
        else:
            os.environ[k] = v
    server.terminate()
    server.wait(timeout=30)


def test_a_store_in_a_bucket_extracts_as_on_disk(s3_bucket, volume_and_cli_store, tmp_path):
    _, cli = volume_and_cli_store
    (s3_bucket / "head.vdiso").write_bytes(cli.read_bytes())
    remote = vdiso.open("s3://bucket/head.vdiso", disk_cache=tmp_path / "cache")
    local = vdiso.open(cli)
    assert remote.shape == local.shape and remote.info()["histogram"] == local.info()["histogram"]
    for method in ("octree", "sage"):
        a = remote.extract(500.5, method=method, size=(320, 240))
        b = local.extract(500.5, method=method, size=(320, 240))
        assert len(a.faces) == len(b.faces) and a.stats["remote_requests"] > 0
        np.testing.assert_array_equal(a.vertices, b.vertices)
    with pytest.raises(OSError, match="missing.vdiso"):
        vdiso.open("s3://bucket/missing.vdiso")


def test_a_store_from_a_bucket_used_after_fork_is_an_error_not_a_hang(s3_bucket, volume_and_cli_store):
    """Its transfers are run by a thread of the process that opened it, which a forked child
    lacks: reading there is an OSError saying to open it again (a pickled Store does), and
    closing it there leaves the parent's threads alone (joining them crashed the child)."""
    import pickle
    _, cli = volume_and_cli_store
    (s3_bucket / "head.vdiso").write_bytes(cli.read_bytes())
    remote = vdiso.open("s3://bucket/head.vdiso")
    remote.extract(500.5, size=(160, 120))
    read_end, write_end = os.pipe()
    child = os.fork()
    if child == 0:  # the child: report and leave without running the parent's cleanup
        try:
            remote.extract(700.5, method="octree", cache_mb=64)  # another cache: its bricks read anew
            said = "read"
        except OSError as e:
            said = str(e)
        except BaseException as e:  # noqa: BLE001 - anything else is the test's finding
            said = f"{type(e).__name__}: {e}"
        try:
            again = pickle.loads(pickle.dumps(remote)).extract(700.5, method="octree")
            said += f"|again {len(again.faces)}"
        except BaseException as e:  # noqa: BLE001
            said += f"|again {type(e).__name__}: {e}"
        remote.close()
        os.write(write_end, said.encode())
        os._exit(0)
    os.close(write_end)
    deadline = time.monotonic() + 60
    while (status := os.waitpid(child, os.WNOHANG)) == (0, 0):
        if time.monotonic() > deadline:
            os.kill(child, 9)
            pytest.fail("the forked child hung reading the parent's remote store")
        time.sleep(0.05)
    assert os.waitstatus_to_exitcode(status[1]) == 0, "the forked child died"
    said = os.read(read_end, 4096).decode()
    os.close(read_end)
    first, again = said.split("|again ")
    assert "opened before fork() cannot be read in the child process" in first, said
    assert int(again) == len(remote.extract(700.5, method="octree").faces) > 0, said


def test_post_processing_and_progress_match_the_command_line(vdiso_bin, volume_and_cli_store):
    _, cli = volume_and_cli_store
    flags = ["--largest", "--smooth", "3", "--decimate", "0.5"]
    r = run([vdiso_bin, "extract", str(cli), "--iso", "500.5", "--method", "octree", "--stats", "-", "--quiet",
             "-o", str(cli.parent / "post.ply")] + flags)
    assert r.returncode == 0, r.stderr
    theirs = json.loads(r.stdout.splitlines()[-1])
    seen = []
    mesh = vdiso.open(cli).extract(500.5, largest=True, smooth=3, decimate=0.5,
                                   progress=lambda done, total: seen.append(done / total))
    assert mesh.stats["triangles"] == theirs["triangles"] == len(mesh.faces)
    assert mesh.stats["pieces_kept"] == 1 and seen and seen[-1] == 1.0
    with pytest.raises(ValueError, match="decimate expects"):
        vdiso.open(cli).extract(500.5, decimate=1.5)
    with pytest.raises(ValueError, match="smooth, decimate, largest and min_piece apply"):
        vdiso.open(cli).extract(500.5, method="sage", largest=True)


def test_a_second_extract_reads_no_brick_the_first_read(volume_and_cli_store):
    """One Store keeps one session: its brick cache and tree stay from call to call, whatever
    the isovalue or method; a refused setting leaves it as it was; another budget is another cache."""
    _, cli = volume_and_cli_store
    store = vdiso.open(cli)
    first = store.extract(500.5)
    assert first.stats["bricks_loaded"] > 0
    again = store.extract(500.5)
    assert again.stats["bricks_loaded"] == 0 and len(again.faces) == len(first.faces)
    store.extract(700.5, method="noise")  # NOISE ranges every brick: the cache now holds them all
    assert store.extract(600.5, method="noise").stats["bricks_loaded"] == 0
    assert store.extract(700.5).stats["bricks_loaded"] == 0
    with pytest.raises(ValueError, match="method"):
        store.extract(500, method="marching")
    assert store.extract(500.5).stats["bricks_loaded"] == 0
    assert store.extract(500.5, cache_mb=64).stats["bricks_loaded"] > 0


def test_threads_extract_and_post_process_at_once(volume_and_cli_store):
    """The GIL is released: Python threads extract at once (one Store runs its extractions one
    at a time over its one cache), post-processing included, and each gets what one alone gets."""
    _, cli = volume_and_cli_store
    store = vdiso.open(cli)
    alone = store.extract(500.5, largest=True, smooth=2)
    results, errors = at_once(lambda: len(store.extract(500.5, largest=True, smooth=2).faces))
    assert not errors and results == [len(alone.faces)] * 4


def test_an_interrupted_index_goes_on_where_it_stopped(tmp_path):
    v = head()
    data = tmp_path / "head.zarr"
    zarr.array(v, chunks=(8, 20, 24), store=str(data))
    whole = vdiso.index(data, tmp_path / "whole.vdiso", brick=8)
    chunk = data / "3.0.0"
    good = chunk.read_bytes()
    chunk.write_bytes(b"not a chunk")
    with pytest.raises(OSError, match="3.0.0"):
        vdiso.index(data, brick=8, checkpoint_seconds=0)
    assert os.path.exists(str(data) + ".vdiso.resume") and not os.path.exists(str(data) + ".vdiso")
    chunk.write_bytes(good)
    summary = vdiso.index(data, brick=8)
    assert 0 < summary["resumed_layers"] < summary["layers"]
    assert open(summary["index"], "rb").read() == open(whole["index"], "rb").read()
    assert not os.path.exists(str(data) + ".vdiso.resume")
    with pytest.raises(ValueError, match="checkpoint_seconds"):
        vdiso.index(data, tmp_path / "x.vdiso", checkpoint_seconds=-1)


def test_an_indexed_zarr_opens_in_place_like_its_converted_store(tmp_path):
    v = head()
    data = tmp_path / "head.zarr"
    zarr.array(v, chunks=(16, 20, 24), store=str(data))
    summary = vdiso.index(data, brick=8)
    assert summary["index"] == str(data) + ".vdiso" and os.path.exists(summary["index"])
    assert summary["chunks"] == 3 * 3 * 3 and summary["data_bytes"] > 0
    vdiso.convert(data, tmp_path / "head.vdiso", brick=8)
    converted = vdiso.open(tmp_path / "head.vdiso")
    for method in ("octree", "sage"):
        mine, theirs = vdiso.open(data).extract(500.5, method=method), converted.extract(500.5, method=method)
        assert len(mine.faces) > 1000
        assert np.array_equal(mine.vertices, theirs.vertices) and np.array_equal(mine.faces, theirs.faces)
    with pytest.raises(FileExistsError):
        vdiso.index(data, brick=8)
    with pytest.raises(ValueError, match="index expects the index's path"):
        vdiso.index("s3://bucket/head.zarr")


def test_an_ome_zarr_s_own_scales_are_its_coarse_levels(tmp_path):
    """An OME-Zarr written with zarr-python, scales of every other sample: the index takes them
    as levels and stays small; scale_levels=0 filters and stores every level instead."""
    v = head()
    data = tmp_path / "head.ome.zarr"
    group = zarr.open_group(str(data), mode="w")
    datasets = []
    for level in range(3):
        step = 2 ** level
        group.array(str(level), v[::step, ::step, ::step], chunks=(16, 16, 16))
        datasets.append({"path": str(level), "coordinateTransformations": [{"type": "scale", "scale": [step] * 3}]})
    axes = [{"name": a, "type": "space"} for a in "zyx"]
    group.attrs["multiscales"] = [{"version": "0.4", "axes": axes, "datasets": datasets}]
    own = vdiso.index(data, brick=8, scale_levels=2)
    made = vdiso.index(data, tmp_path / "made.vdiso", brick=8, scale_levels=0)
    assert own["own_scale_levels"] == 2 and own["scales_not_used"] == ""
    assert made["own_scale_levels"] == 0
    assert own["file_bytes"] * 3 < made["file_bytes"]
    store = vdiso.open(data)
    assert len(store.extract(500.5, method="sage", view="distant").faces) > 100
    assert len(store.extract(500.5).faces) == len(vdiso.open(tmp_path / "made.vdiso").extract(500.5).faces)


def test_everyday_conveniences(tmp_path, volume_and_cli_store):
    import pickle

    import meshio
    _, cli = volume_and_cli_store
    assert vdiso.__version__ == "0.1" and vdiso.Error.__doc__ and vdiso.Store.shape.__doc__
    with vdiso.open(cli) as store:
        mesh = store.extract(500.5)
        assert len(mesh) == len(mesh.faces) > 1000
        # Pickled (for Dask and multiprocessing): the mesh's arrays, the store where it lies.
        again = pickle.loads(pickle.dumps(mesh))
        assert len(again) == len(mesh) and again.stats == mesh.stats
        for name in ("vertices", "normals", "faces"):
            assert np.array_equal(getattr(again, name), getattr(mesh, name))
        reopened = pickle.loads(pickle.dumps(store))
        assert reopened.shape == store.shape and len(reopened.extract(500.5)) == len(mesh)
        # An isovalue outside the values is refused alike everywhere, as marching_cubes does.
        for call in (lambda: store.extract(5000), lambda: store.render(-1), lambda: list(store.frames(5000, ["normal"]))):
            with pytest.raises(ValueError, match="iso: .* outside the store's values, 0.0 to 977.0"):
                call()
        with pytest.raises(ValueError, match="level"):
            vdiso.marching_cubes(head(), 5000)
        # Typos are named with the public method; a wrong-length spacing says so in a line.
        with pytest.raises(TypeError, match=r"Store.render\(\) got an unexpected keyword argument 'lodd_error'"):
            store.render(500.5, lodd_error=2)
        with pytest.raises(ValueError, match=r"^spacing: expects 3 numbers \(z, y, x\), not 2$"):
            vdiso.marching_cubes(head(), 500.5, spacing=(1, 2))
        # Hand-offs: meshio (Debian's), napari's surface tuple.
        m = mesh.to_meshio()
        assert isinstance(m, meshio.Mesh) and np.array_equal(m.cells_dict["triangle"], mesh.faces)
        m.write(tmp_path / "skin.vtu")
        assert len(meshio.read(tmp_path / "skin.vtu").cells_dict["triangle"]) == len(mesh)
        verts, faces, values = mesh.napari_surface()
        assert np.array_equal(verts[:, ::-1], mesh.vertices) and faces is not None and len(values) == len(verts)
        # trimesh and PyVista when importable (Debian 12 has neither): else an ImportError naming them.
        for method, package in (("to_trimesh", "trimesh"), ("to_pyvista", "pyvista")):
            try:
                __import__(package)
            except ImportError:
                with pytest.raises(ImportError, match=rf"Mesh.{method}\(\) needs the {package} package"):
                    getattr(mesh, method)()
                continue
            handed = getattr(mesh, method)()
            assert len(handed.faces if package == "trimesh" else handed.points) == (
                len(mesh.faces) if package == "trimesh" else len(mesh.vertices))
    with pytest.raises(ValueError, match="closed"):
        store.extract(500.5)
    assert "closed" in repr(store)
    store.close()  # twice is allowed
    # A state whose faces name a vertex the mesh does not have is refused.
    state = mesh.__getstate__()
    bad = vdiso.Mesh.__new__(vdiso.Mesh)
    with pytest.raises(ValueError, match="Mesh state: arrays that do not make a mesh"):
        bad.__setstate__((state[0], state[1], np.array([0, 1, 1 << 30], np.uint32).tobytes(), b"", b"", {}))


def test_a_store_mesh_in_volume_space_is_marching_cubes_reversed(tmp_path):
    v = head()
    vdiso.convert(v, tmp_path / "o.vdiso", spacing=(1.5, 0.75, 1.0), origin=(10.0, -4.0, 2.0))
    store = vdiso.open(tmp_path / "o.vdiso")
    verts, faces, _, _ = vdiso.marching_cubes(v, 500.5, spacing=(1.5, 0.75, 1.0))
    mesh = store.extract(500.5, mesh_space="volume")
    assert len(mesh) == len(faces) and len(mesh.vertices) == len(verts)
    ours = (mesh.vertices - np.array(store.origin, np.float32))[:, ::-1]

    def triangles(vv, ff):
        """Each face as its three corners (rounded), corners sorted within it, faces sorted."""
        t = np.round(vv[ff].astype(np.float64), 3)
        t = np.array([sorted(map(tuple, tri)) for tri in t]).reshape(len(ff), 9)
        return t[np.lexsort(t.T[::-1])]
    assert np.array_equal(triangles(ours, mesh.faces), triangles(verts, faces))
    physical = store.extract(500.5)
    assert np.allclose(physical.vertices, mesh.vertices, atol=1e-4)  # no orientation: the same
    frames = list(store.frames(500.5, ["normal"], mesh_space="volume"))
    assert len(frames) == 1
    with pytest.raises(ValueError, match="mesh_space"):
        store.extract(500.5, mesh_space="world")


def test_convert_computes_each_dask_chunk_once(tmp_path, volume_and_cli_store):
    # Chunks 9 deep against the writer's slabs of 32 and more: each chunk is computed once.
    import dask
    v, cli = volume_and_cli_store
    computed = []

    def block(x, block_info=None):
        computed.append(tuple(block_info[0]["chunk-location"]))
        return x

    source = da.from_array(v, chunks=(9, 25, 60)).map_blocks(block, dtype=v.dtype)
    with dask.config.set(scheduler="synchronous"):
        vdiso.convert(source, tmp_path / "once.vdiso")
    assert (tmp_path / "once.vdiso").read_bytes() == cli.read_bytes()
    assert len(computed) == len(set(computed)) == 5 * 2 * 1, computed
    # A Zarr array's chunks are read whole too (the same bytes).
    vdiso.convert(zarr.array(v, chunks=(7, 50, 60)), tmp_path / "z.vdiso")
    assert (tmp_path / "z.vdiso").read_bytes() == cli.read_bytes()
