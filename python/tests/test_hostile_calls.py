"""Calls a demanding user makes by mistake or on a bad day: each is refused by name, or done, and
never crashes the interpreter (the review of 2026-11-30 found each of these crashing, hanging or
reporting a finished job as failed)."""
import time
import warnings

import dask.array as da
import numpy as np
import pytest
import zarr

import vdiso
from conftest import at_once
from vdiso import _vdiso


def ball(shape=(20, 21, 22)):
    z, y, x = np.ogrid[: shape[0], : shape[1], : shape[2]]
    return ((z - 10) ** 2 + (y - 10) ** 2 + (x - 11) ** 2).astype(np.float32)


@pytest.fixture
def store_path(tmp_path):
    path = tmp_path / "ball.vdiso"
    vdiso.convert(ball((40, 41, 42)) * -1.0, str(path))
    return str(path)


@pytest.fixture
def store(store_path):
    return vdiso.open(store_path)


def test_a_camera_of_another_size_than_the_picture_is_refused(store):
    camera = {"eye": [-300, 20, 20], "target": [20, 20, 20], "up": [0, 0, 1], "fov": 30, "width": 64, "height": 64}
    with pytest.raises(ValueError, match="differ from size"):
        store.render(-100.0, camera=camera, size=(128, 128))
    image = store.render(-100.0, camera=camera, size=(64, 64))
    assert image.shape == (64, 64, 3)


def test_a_spacing_beyond_float32_is_refused_not_a_crash():
    with pytest.raises(ValueError, match="beyond float32"):
        vdiso.marching_cubes(ball(), 40.0, spacing=(1e38, 1.0, 1.0))
    verts = vdiso.marching_cubes(ball(), 40.0, spacing=(1e30, 1.0, 1.0))[0]
    assert np.isfinite(verts).all()


@pytest.mark.parametrize("kind", ["dask", "zarr"])
def test_a_step_over_chunks_that_end_between_steps_meshes_as_numpy(kind):
    v = np.random.default_rng(0).random((10, 8, 8)).astype(np.float32)
    source = da.from_array(v, chunks=(9, 8, 8)) if kind == "dask" else zarr.array(v, chunks=(9, 8, 8))
    want = vdiso.marching_cubes(v, 0.5, step_size=2)
    got = vdiso.marching_cubes(source, 0.5, step_size=2)
    assert len(got[1]) == len(want[1]) > 0
    assert np.array_equal(got[0], want[0])


def test_faces_changed_in_place_are_refused_by_write(store, tmp_path):
    mesh = store.extract(-100.0)
    mesh.faces[0, 0] = 4_000_000_000
    for ext in ("stl", "ply"):
        out = tmp_path / f"bad.{ext}"
        with pytest.raises(ValueError, match="names vertex 4000000000"):
            mesh.write(str(out))
        assert not out.exists()


def test_mesh_parts_of_broken_triangles_are_refused():
    v = ball((40, 21, 22))
    shape = list(v.shape)
    part = _vdiso._mesh_slab_part(np.ascontiguousarray(v[0:34]), shape, np.dtype(np.float32), 0, 1, 40.0,
                                  (1.0, 1.0, 1.0), 1)
    part = dict(part)
    part["indices"] = np.asarray(part["indices"])[:-1]
    with pytest.raises(ValueError, match="not three a triangle"):
        _vdiso._join_slab_parts([part], 40.0, (1.0, 1.0, 1.0))


def test_a_progress_that_raises_when_the_work_is_done_warns_and_keeps_the_result(tmp_path):
    calls = []

    def progress(done, total):
        calls.append(done / total)
        if done >= total:
            raise RuntimeError("the last call fails")

    out = tmp_path / "p.vdiso"
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        vdiso.convert(ball(), str(out), progress=progress)
    assert any("after the work was done" in str(w.message) for w in caught)
    assert vdiso.open(str(out)).shape == ball().shape
    assert calls[-1] == 1.0


def test_a_progress_that_raises_stops_its_own_call_and_no_other(tmp_path):
    # Call A's callable raises while A's work waits on a slow source; calls in another thread,
    # converting arrays one after another all the while, must each finish as if alone (the stop
    # was process-wide: they failed "interrupted" while A's work took a slab's read to notice).
    import threading

    class SlowSource:
        def __init__(self, array):
            self.array, self.shape, self.dtype = array, array.shape, array.dtype

        def __getitem__(self, key):
            time.sleep(0.3)
            return self.array[key]

    a_done = threading.Event()
    outcome = {"b": [], "b_errors": []}

    def call_a():
        calls = []

        def progress(done, total):
            calls.append(done)
            if len(calls) == 2:
                raise RuntimeError("A's callable fails")

        try:
            vdiso.convert(SlowSource(ball((256, 21, 22))), str(tmp_path / "a.vdiso"), progress=progress)
        except RuntimeError as e:
            outcome["a"] = str(e)
        a_done.set()

    def calls_b():
        big = ball((256, 256, 256))
        while not a_done.is_set():
            try:
                vdiso.convert(big, str(tmp_path / "b.vdiso"), overwrite=True)
                outcome["b"].append(vdiso.open(str(tmp_path / "b.vdiso")).shape)
            except Exception as e:  # noqa: BLE001 (counted below)
                outcome["b_errors"].append(str(e))

    a = threading.Thread(target=call_a)
    b = threading.Thread(target=calls_b)
    a.start()
    b.start()
    a.join()
    b.join()
    assert outcome.get("a") == "A's callable fails"
    assert not (tmp_path / "a.vdiso").exists()
    assert outcome["b_errors"] == []
    assert outcome["b"] and all(shape == (256, 256, 256) for shape in outcome["b"])


def test_index_progress_counts_to_one(tmp_path):
    array = zarr.open(str(tmp_path / "a.zarr"), mode="w", shape=(30, 31, 32), chunks=(8, 31, 32), dtype="f4")
    array[:] = ball((30, 31, 32))
    seen = []
    vdiso.index(str(tmp_path / "a.zarr"), progress=lambda done, total: seen.append((done, total)))
    assert seen and all(total == 1.0 for _, total in seen) and seen[-1] == (1.0, 1.0)


def test_a_server_stopped_from_two_threads_at_once_stops_once(store_path):
    server = vdiso.serve(store_path, port=0)
    _, errors = at_once(server.stop)
    assert errors == []
    assert not server.running


def test_a_failed_dask_chunk_leaves_no_write_into_freed_memory(tmp_path):
    # The failing chunk raises while the others still compute; they finish after the call has
    # returned and must write into memory that is still theirs.
    def block(block_info=None):
        (_, _), (y0, _), (_, _) = block_info[None]["array-location"]
        if y0 == 0:
            time.sleep(0.05)
            raise RuntimeError("chunk y=0 failed")
        time.sleep(0.4)
        loc = block_info[None]["array-location"]
        return np.full([b - a for a, b in loc], 7, np.float32)

    vol = da.map_blocks(block, dtype=np.float32, chunks=((50,), (25,) * 4, (100,)))
    with pytest.raises(Exception, match="chunk y=0 failed"):
        vdiso.convert(vol, str(tmp_path / "x.vdiso"))
    junk = [np.ones(100_000) for _ in range(50)]  # the freed memory in use again
    time.sleep(0.8)  # the other chunks have written by now
    assert all(j[0] == 1.0 for j in junk)
    assert not (tmp_path / "x.vdiso").exists()
