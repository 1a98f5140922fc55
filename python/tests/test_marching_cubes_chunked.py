"""vdiso.marching_cubes on arrays too large to load (Dask, Zarr, any array-like sliced along axis
0): read once, in order, a layer of bricks at a time, and meshed into the same arrays, bit for bit,
as the array held in memory gives."""
import dask
import dask.array as da
import numpy as np
import pytest
import zarr

import vdiso
from conftest import python_child


def wavy(shape=(70, 50, 40), seed=1):
    """A field with much surface, crossing every layer of bricks and the chunks' seams."""
    z, y, x = np.mgrid[: shape[0], : shape[1], : shape[2]]
    noise = np.random.default_rng(seed).normal(0, 0.05, shape)
    return np.sin(z / 7.0) * np.cos(y / 9.0) + np.sin(x / 5.0) + noise


def assert_identical(ours, expected):
    assert len(ours) == len(expected) == 4
    for got, want in zip(ours, expected):
        assert got.dtype == want.dtype and got.shape == want.shape
        assert np.array_equal(got, want)
    assert len(expected[1]) > 1000


class Rows:
    """An array-like that answers slices along axis 0 only, and records them."""

    def __init__(self, a):
        self.a, self.shape, self.dtype, self.asked = a, a.shape, a.dtype, []

    def __getitem__(self, key):
        assert isinstance(key, slice), key
        self.asked.append((key.start, key.stop))
        return self.a[key]


@pytest.mark.parametrize("chunks", [(9, 25, 40), (64, 50, 40), (1, 50, 40), (70, 50, 40)])
@pytest.mark.parametrize("threads", [1, 2])
def test_a_dask_array_gives_the_in_memory_mesh_and_each_chunk_is_computed_once(chunks, threads):
    v = (wavy() * 1000 + 3000).astype(np.uint16)
    computed = []

    def block(x, block_info=None):
        computed.append(tuple(block_info[0]["chunk-location"]))
        return x

    source = da.from_array(v, chunks=chunks).map_blocks(block, dtype=v.dtype)
    with dask.config.set(scheduler="synchronous"):
        assert_identical(vdiso.marching_cubes(source, 3300.0, threads=threads),
                         vdiso.marching_cubes(v, 3300.0, threads=threads))
        assert len(computed) == len(set(computed)) == source.npartitions
        # No level: read once for the range, once to mesh, with the middle of the values.
        computed.clear()
        assert_identical(vdiso.marching_cubes(source, threads=threads), vdiso.marching_cubes(v, threads=threads))
        assert len(computed) == 2 * source.npartitions


def test_a_zarr_array_and_any_array_like_are_read_a_layer_at_a_time():
    v = wavy().astype(np.float32)
    expected = vdiso.marching_cubes(v, 0.3)
    assert_identical(vdiso.marching_cubes(zarr.array(v, chunks=(16, 25, 40)), 0.3), expected)
    rows = Rows(v)
    assert_identical(vdiso.marching_cubes(rows, 0.3), expected)
    # In order, each slice once, at most a layer of bricks and its ghosts (35 slices) at a time.
    assert rows.asked[0][0] == 0 and rows.asked[-1][1] == v.shape[0]
    assert all(a[1] == b[0] for a, b in zip(rows.asked, rows.asked[1:]))
    assert max(stop - start for start, stop in rows.asked) <= 35


def test_noise_gives_the_in_memory_mesh_with_its_vertices_inside_cells():
    """method="lewiner" on noise: cells cut with vertices inside them, on the bricks' seams too,
    the same arrays whether read in memory, a layer at a time, or on any thread count."""
    v = np.random.default_rng(5).random((70, 40, 36)).astype(np.float32)
    expected = vdiso.marching_cubes(v, 0.5, threads=1)
    inside = (np.abs(expected[0] - np.round(expected[0])) > 1e-3).sum(axis=1) > 1
    assert inside.sum() > 10
    assert_identical(vdiso.marching_cubes(da.from_array(v, chunks=(16, 40, 36)), 0.5), expected)
    assert_identical(vdiso.marching_cubes(zarr.array(v, chunks=(20, 40, 36)), 0.5, threads=2), expected)


@pytest.mark.parametrize("dtype", [np.bool_, np.int8, np.int64, np.uint64, np.float16, np.float64])
def test_every_dtype_gives_the_in_memory_mesh(dtype):
    v = wavy()
    if dtype == np.bool_:
        v, level = v > 0.2, None
    elif np.issubdtype(dtype, np.integer):
        v, level = (v * 40 + 100).astype(dtype), 110.0
    else:
        v, level = v.astype(dtype), 0.3
    assert_identical(vdiso.marching_cubes(da.from_array(v, chunks=(16, 50, 40)), level),
                     vdiso.marching_cubes(v, level))


@pytest.mark.parametrize("keywords", [dict(spacing=(1.5, 0.5, 2.0)), dict(step_size=2),
                                      dict(step_size=3, spacing=(1, 2, 1)), dict(mask=True),
                                      dict(mask=True, step_size=2), dict(gradient_direction="ascent"),
                                      dict(allow_degenerate=False)], ids=str)
def test_scikit_images_keywords_give_the_in_memory_mesh(keywords):
    v = wavy()
    mask = np.random.default_rng(2).random(v.shape) > 0.3
    here = dict(keywords, mask=mask) if "mask" in keywords else keywords
    expected = vdiso.marching_cubes(v, 0.3, **here)
    # The mask a Dask array too: read at the cells' corners only.
    lazy = dict(keywords, mask=da.from_array(mask, chunks=(10, 50, 40))) if "mask" in keywords else keywords
    assert_identical(vdiso.marching_cubes(da.from_array(v, chunks=(16, 50, 40)), 0.3, **lazy), expected)
    assert_identical(vdiso.marching_cubes(zarr.array(v, chunks=(16, 25, 40)), 0.3, **here), expected)


@pytest.mark.parametrize("step", [1, 2])
@pytest.mark.parametrize("first, end", [(33, 80), (25, 50)])
def test_a_small_mask_meshes_few_bricks_of_an_array_read_a_layer_at_a_time(monkeypatch, step, first, end):
    """Only the marked bricks are meshed, and the arrays are the in-memory ones: a mask from a
    layer's first cells on (far corners from 33: their face with the layer before is that layer's,
    which is not meshed), and one across two layers."""
    import vdiso._marching_cubes as mc
    v = wavy((150, 100, 90))
    mask = np.zeros(v.shape, bool)
    mask[first * step:end * step, 20 * step:60 * step, 20 * step:60 * step] = True
    expected = vdiso.marching_cubes(v, 0.3, mask=mask, step_size=step)
    meshed = []
    marked = mc._bricks_marked
    monkeypatch.setattr(mc, "_bricks_marked", lambda mask, step: meshed.append(marked(mask, step)) or meshed[-1])
    for lazy in (da.from_array(v, chunks=(16, 50, 40)), zarr.array(v, chunks=(16, 25, 40))):
        assert_identical(vdiso.marching_cubes(lazy, 0.3, mask=da.from_array(mask, chunks=(20, 50, 45)), step_size=step),
                         expected)
    cells = [(n - 1) // step for n in v.shape]
    total = np.prod([-(-n // 32) for n in cells])
    assert 0 < len(meshed[-1]) < total, (len(meshed[-1]), total)


def test_bad_chunked_input_is_refused_by_name():
    v = da.from_array(wavy(), chunks=(16, 50, 40))
    with pytest.raises(ValueError, match=r"level: 50.0+ is outside the volume's values"):
        vdiso.marching_cubes(v, 50.0)
    with pytest.raises(ValueError, match="dask.array.core.Array: expects a 3-D array, not one of 2 dimensions"):
        vdiso.marching_cubes(da.zeros((4, 5)), 0.5)
    with pytest.raises(ValueError, match="level: expects a finite isovalue"):
        vdiso.marching_cubes(v, float("nan"))
    with pytest.raises(ValueError, match="mask: expects the volume's shape"):
        vdiso.marching_cubes(v, 0.3, mask=da.zeros((3, 3, 3), dtype=bool))

    class Liar(Rows):
        def __getitem__(self, key):
            return super().__getitem__(key)[:, :-1]

    with pytest.raises(OSError, match=r"Liar: slices 0 to 34 came back with shape \(34, 49, 40\), not \(34, 50, 40\)"):
        vdiso.marching_cubes(Liar(wavy()), 0.3)


LARGE = """
import resource, sys
import dask.array as da, numpy as np
import vdiso
limit = {limit}
if limit > 0:
    resource.setrlimit(resource.RLIMIT_DATA, (limit, limit))
n = {n}
def block(block_info=None):  # a ball, u8, chunk by chunk
    (z0, z1), (y0, y1), (x0, x1) = block_info[None]["array-location"]
    c = np.float32(n // 2)
    z, y, x = (np.arange(a, b, dtype=np.float32) - c for a, b in ((z0, z1), (y0, y1), (x0, x1)))
    plane = y[:, None] ** 2 + x[None, :] ** 2
    out = np.empty((z1 - z0, y1 - y0, x1 - x0), np.uint8)
    for i in range(z1 - z0):
        out[i] = np.clip(np.float32(200) - (plane + z[i] ** 2) * np.float32(200 / (0.4 * n) ** 2), 0, 255)
    return out
volume = da.map_blocks(block, dtype=np.uint8, chunks=((16,) * (n // 16), (n,), (n,)))
said = []
def progress(done, total):
    if done > 0 and not said:
        said.append(1)
        print("working", done <= total, flush=True)
import time
try:
    verts, faces, normals, values = vdiso.marching_cubes(volume, 100.5, progress=progress)
except KeyboardInterrupt:
    print("stopped at", time.monotonic(), flush=True)  # the call's end, before the interpreter's
    raise
radius = np.linalg.norm(verts - np.float32(n // 2), axis=1)
print("done", len(faces), radius.min(), radius.max(), flush=True)
"""


def test_a_dask_array_larger_than_the_memory_limit_is_meshed():
    n = 1024  # 1 GiB of samples, generated chunk by chunk, under a 600 MB data limit
    child = python_child(LARGE.format(limit=600 << 20, n=n))
    stdout, stderr = child.communicate(timeout=900)
    assert child.returncode == 0, stderr
    triangles, low, high = (float(w) for w in stdout.split("done")[-1].split())
    # The ball where the samples, 200 - r^2 200 / (0.4 n)^2 truncated, pass 100.5 (where the
    # field is 101): its vertices within a sample of that sphere, about three triangles a unit
    # of its area.
    r = 0.4 * n * np.sqrt(99 / 200)
    assert r - 1 < low and high < r + 1, (low, high, r)
    assert 2 < triangles / (4 * np.pi * r * r) < 4, triangles


def test_ctrl_c_stops_a_chunked_marching_cubes_within_a_second():
    import signal
    import time
    child = python_child(LARGE.format(limit=-1, n=1536))
    assert child.stdout.readline().strip() == "working True"
    sent = time.monotonic()
    child.send_signal(signal.SIGINT)
    stdout, stderr = child.communicate(timeout=60)
    assert child.returncode != 0 and "KeyboardInterrupt" in stderr and "stopped at" in stdout, stderr
    assert "done" not in stdout
    waited = float(stdout.split("stopped at")[1].split()[0]) - sent  # one monotonic clock for both
    assert waited < 1, f"stopped {waited:.2f} s after Ctrl-C"


@pytest.fixture(scope="module")
def cluster_client():
    """A dask.distributed cluster of two worker processes on this machine."""
    from distributed import Client, LocalCluster
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        with Client(cluster) as client:
            yield client


@pytest.mark.parametrize("level, keywords", [(0.3, {}), (None, {}), (0.3, dict(step_size=2, spacing=(1, 2, 3))),
                                             (0.3, dict(mask=True)), (0.3, dict(allow_degenerate=False))], ids=str)
def test_a_dask_array_meshed_on_a_cluster_gives_the_in_memory_mesh(cluster_client, level, keywords):
    from distributed import get_task_stream
    v = wavy((150, 50, 40))
    mask = np.random.default_rng(2).random(v.shape) > 0.3
    here = dict(keywords, mask=mask) if "mask" in keywords else keywords
    lazy = dict(keywords, mask=da.from_array(mask, chunks=(40, 50, 40))) if "mask" in keywords else keywords
    with get_task_stream(cluster_client) as stream:
        # Each chunk a task of its own (inline_array): no one task holds the array, so no worker
        # holds every run's input.
        ours = vdiso.marching_cubes(da.from_array(v, chunks=(16, 50, 40), inline_array=True), level,
                                    client=cluster_client, **lazy)
    assert_identical(ours, vdiso.marching_cubes(v, level, **here))
    # The runs were meshed on the cluster's workers (which ones is the scheduler's choice: a
    # fast worker may take all three runs of a small array).
    runs = [t for t in stream.data if t["key"].startswith("_mesh_run")]
    workers = set(cluster_client.scheduler_info()["workers"])
    assert len(runs) >= 2 and {t["worker"] for t in runs} <= workers


def test_a_closed_surface_meshed_on_a_cluster_has_no_crack(cluster_client):
    z, y, x = np.ogrid[:200, :60, :70]
    ball = (np.sqrt((z - 100.3) ** 2 + (y - 30.1) ** 2 + (x - 34.7) ** 2) * 3).astype(np.int64)  # int64, as label() gives
    verts, faces, _, _ = vdiso.marching_cubes(da.from_array(ball, chunks=(25, 60, 70)), 80.5, client=cluster_client)
    edges = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
    _, uses = np.unique(edges, axis=0, return_counts=True)
    assert len(faces) > 10000 and (uses == 2).all()  # no boundary edge: no crack, no duplicate vertex at a seam
    assert len(np.unique(verts, axis=0)) == len(verts)


def test_noise_meshed_on_a_cluster_gives_the_in_memory_mesh(cluster_client):
    v = np.random.default_rng(6).random((100, 30, 34)).astype(np.float32)  # cells with vertices inside
    assert_identical(vdiso.marching_cubes(da.from_array(v, chunks=(25, 30, 34)), 0.5, client=cluster_client),
                     vdiso.marching_cubes(v, 0.5))


def test_a_cluster_is_given_a_dask_array(cluster_client):
    with pytest.raises(ValueError, match="client: meshes a Dask array on the cluster, not a ndarray"):
        vdiso.marching_cubes(wavy(), 0.3, client=cluster_client)
    with pytest.raises(ValueError, match=r"level: 50.0+ is outside the volume's values"):
        vdiso.marching_cubes(da.from_array(wavy(), chunks=(16, 50, 40)), 50.0, client=cluster_client)
