"""vdiso.marching_cubes against scikit-image: the same surface and the same conventions."""
import numpy as np
import pytest
import skimage.measure

import vdiso

DTYPES = [np.uint8, np.int8, np.uint16, np.int16, np.uint32, np.int32, np.float32, np.float64]


def blob(shape=(23, 27, 31), dtype=np.float32, scale=1.0):
    """Two overlapping balls over a gentle ramp: a surface with curvature, off-centre in every axis."""
    z, y, x = np.mgrid[: shape[0], : shape[1], : shape[2]].astype(np.float64)
    d1 = np.sqrt((x - 12.3) ** 2 + (y - 11.1) ** 2 + (z - 9.7) ** 2)
    d2 = np.sqrt((x - 19.0) ** 2 + (y - 15.5) ** 2 + (z - 12.2) ** 2)
    v = 100.0 - 6.0 * np.minimum(d1, d2 * 1.3) + 0.5 * x
    if np.issubdtype(dtype, np.integer):
        info = np.iinfo(dtype)
        v = np.clip(np.round(v * scale), info.min, info.max)
    return v.astype(dtype)


def area(verts, faces):
    t = verts[faces]
    return 0.5 * np.linalg.norm(np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]), axis=1).sum()


def nearest(a, b):
    """Index into b of each row of a's nearest point, and the distance (brute force, small meshes)."""
    index = np.empty(len(a), dtype=np.int64)
    dist = np.empty(len(a))
    for s in range(0, len(a), 512):
        d = np.linalg.norm(a[s:s + 512, None, :] - b[None, :, :], axis=2)
        index[s:s + 512] = d.argmin(1)
        dist[s:s + 512] = d.min(1)
    return index, dist


def assert_same_surface(ours, theirs):
    v, f, n, values = ours
    sv, sf, sn, svalues = theirs
    assert v.dtype == sv.dtype and f.dtype == sf.dtype and n.dtype == sn.dtype and values.dtype == svalues.dtype
    assert v.shape[1] == 3 and f.shape[1] == 3 and n.shape == v.shape and values.shape == (len(v),)
    assert len(f) > 100
    assert abs(area(v, f) / area(sv, sf) - 1) < 0.005
    index, dist = nearest(v, sv)
    assert dist.max() < 1e-4
    # Values as scikit-image's: the largest spread about the level of the cells using the vertex.
    np.testing.assert_array_equal(values, svalues[index])
    # Normals point the same way (outward from the values above the level).
    assert (np.sum(n * sn[index], axis=1) > 0).mean() > 0.99
    # Winding as scikit-image's, relative to the normals.
    t = v[f]
    face_normals = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
    st = sv[sf]
    their_faces = np.cross(st[:, 1] - st[:, 0], st[:, 2] - st[:, 0])
    ours_agree = (np.sum(face_normals * n[f[:, 0]], axis=1) > 0).mean()
    theirs_agree = (np.sum(their_faces * sn[sf[:, 0]], axis=1) > 0).mean()
    assert abs(ours_agree - theirs_agree) < 0.02


@pytest.mark.parametrize("dtype", DTYPES, ids=lambda d: np.dtype(d).name)
def test_every_dtype_matches_scikit_image(dtype):
    volume = blob(dtype=dtype)
    level = 40.5
    assert_same_surface(vdiso.marching_cubes(volume, level), skimage.measure.marching_cubes(volume, level))


def test_spacing_and_axis_order_match_scikit_image():
    volume = blob(shape=(19, 33, 26))
    spacing = (0.5, 1.25, 2.0)
    ours = vdiso.marching_cubes(volume, 30.0, spacing=spacing)
    assert_same_surface(ours, skimage.measure.marching_cubes(volume, 30.0, spacing=spacing))
    # Axis 0 spans its samples times its spacing.
    assert ours[0][:, 0].max() <= (19 - 1) * 0.5 + 1e-6


def test_c_f_and_strided_arrays_give_the_same_mesh():
    volume = blob()
    c = vdiso.marching_cubes(volume, 35.0)
    f = vdiso.marching_cubes(np.asfortranarray(volume), 35.0)
    for a, b in zip(c, f):
        np.testing.assert_array_equal(a, b)
    view = np.ascontiguousarray(blob(shape=(46, 27, 62)))[::2, :, ::-2]
    assert not view.flags.c_contiguous
    ours = vdiso.marching_cubes(view, 35.0)
    copied = vdiso.marching_cubes(np.ascontiguousarray(view), 35.0)
    for a, b in zip(ours, copied):
        np.testing.assert_array_equal(a, b)
    assert_same_surface(ours, skimage.measure.marching_cubes(view, 35.0))


def test_threads_give_the_same_mesh():
    volume = blob(shape=(70, 80, 90))
    one = vdiso.marching_cubes(volume, 35.0, threads=1)
    two = vdiso.marching_cubes(volume, 35.0, threads=2)
    for a, b in zip(one, two):
        np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("volume, level, message", [
    (np.zeros((4, 4)), 1.0, "3-D"),
    (np.zeros((4, 4, 4, 4)), 1.0, "3-D"),
    (np.zeros((4, 0, 4), dtype=np.float32), 1.0, "at least 2"),
    (np.zeros((4, 1, 4), dtype=np.float32), 1.0, "at least 2"),
    (np.zeros((4, 4, 4), dtype=np.complex64), 1.0, "not supported"),
    (np.zeros((4, 4, 4), dtype=">f4"), 1.0, "byte order"),
    (np.zeros((4, 4, 4), dtype=np.float32), float("nan"), "level"),
    (np.zeros((4, 4, 4), dtype=np.float32), float("inf"), "level"),
])
def test_bad_input_is_a_value_error(volume, level, message):
    with pytest.raises(ValueError, match=message):
        vdiso.marching_cubes(volume, level)


def test_bad_spacing_and_threads_are_value_errors():
    with pytest.raises(ValueError, match="spacing"):
        vdiso.marching_cubes(blob(), 30.0, spacing=(1.0, 0.0, 1.0))
    with pytest.raises(ValueError, match="threads"):
        vdiso.marching_cubes(blob(), 30.0, threads=0)


def test_help_reads_well():
    assert ("marching_cubes(volume, level=None, spacing=(1.0, 1.0, 1.0), *, gradient_direction=\"descent\",\n"
            "    step_size=1, allow_degenerate=True, method=\"lewiner\", mask=None, threads=None, progress=None,\n"
            "    client=None)" in vdiso.marching_cubes.__doc__)
    assert "extract(iso, *, method=" in vdiso.Store.extract.__doc__


def test_bad_arguments_are_named_in_the_librarys_words():
    # Integers beyond what C++ holds, of the wrong type, and negative: a ValueError or a
    # TypeError naming the argument, never pybind11's signature dump.
    with pytest.raises(ValueError, match="threads expects 1 to 256, not 2147483648"):
        vdiso.marching_cubes(blob(), 30.0, threads=2 ** 31)
    with pytest.raises(ValueError, match="threads"):
        vdiso.marching_cubes(blob(), 30.0, threads=2 ** 70)
    with pytest.raises(TypeError, match="threads: expects an integer, not str"):
        vdiso.marching_cubes(blob(), 30.0, threads="2")
    with pytest.raises(TypeError, match="level: expects a number"):
        vdiso.marching_cubes(blob(), "high")


def test_no_level_checks_the_array_before_reading_it():
    # A zero-stride view of 2^50 samples, beyond what a volume may hold: refused for its size at
    # once, not after minutes of np.nanmin over it.
    import time
    huge = np.lib.stride_tricks.as_strided(np.zeros(1, np.float32), shape=(2 ** 16, 2 ** 17, 2 ** 17),
                                           strides=(0, 0, 0))
    start = time.monotonic()
    with pytest.raises(ValueError, match="at most 2\\^48 samples"):
        vdiso.marching_cubes(huge)
    assert time.monotonic() - start < 5
    # The level the library takes without one: the middle of the values, NaN left out.
    v = blob().astype(np.float32)
    v[0, 0, 0] = np.nan
    verts, faces, _, _ = vdiso.marching_cubes(v)
    verts2, faces2, _, _ = vdiso.marching_cubes(v, 0.5 * (float(np.nanmin(v)) + float(np.nanmax(v))))
    np.testing.assert_array_equal(verts, verts2)
    np.testing.assert_array_equal(faces, faces2)
    with pytest.raises(ValueError, match="no finite sample"):
        vdiso.marching_cubes(np.full((4, 4, 4), np.nan, np.float32))


def test_an_output_that_cannot_be_allocated_is_a_memory_error():
    # A child with its address space capped a little above what it holds: the noise's surface
    # (about 20 M triangles, some 500 MB) cannot be allocated. MemoryError names the size, and
    # the module goes on working (nothing half-made is left).
    from conftest import python_child
    code = """
import resource, numpy as np, vdiso
volume = np.random.default_rng(0).integers(0, 256, (200, 200, 200), dtype=np.uint8)
small = np.zeros((8, 8, 8), np.float32); small[3:5, 3:5, 3:5] = 1
print('before:', len(vdiso.marching_cubes(small, 0.5, threads=1)[1]))
held = int([l for l in open('/proc/self/status') if l.startswith('VmSize')][0].split()[1]) * 1024
resource.setrlimit(resource.RLIMIT_AS, (held + 300 * 2**20, resource.RLIM_INFINITY))
try:
    vdiso.marching_cubes(volume, 127.5, threads=1)
    print('no error')
except MemoryError as e:
    print('MemoryError:', e)
v, f, n, values = vdiso.marching_cubes(small, 0.5, threads=1)
print('after:', len(f))
"""
    child = python_child(code)
    out, err = child.communicate(timeout=120)
    assert child.returncode == 0, err
    assert "MemoryError: cannot allocate the surface:" in out and " MB" in out, out
    before = [l for l in out.splitlines() if l.startswith("before:")]
    assert before and before[0].replace("before", "after") in out, out


def euler_and_pieces(verts, faces):
    """The surface's Euler characteristic (V - E + F) and its connected pieces."""
    import scipy.sparse
    import scipy.sparse.csgraph
    edges = np.unique(np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1), axis=0)
    used = np.unique(faces)
    graph = scipy.sparse.coo_matrix((np.ones(len(edges)), (edges[:, 0], edges[:, 1])), shape=(len(verts), len(verts)))
    labels = scipy.sparse.csgraph.connected_components(graph, directed=False)[1]
    return len(used) - len(edges) + len(faces), len(np.unique(labels[used]))


def test_lorensen_is_scikit_images_and_lewiner_is_the_trilinear_topology():
    """Noise makes ambiguous cells everywhere. method="lorensen": scikit-image's vertices and as
    many triangles. method="lewiner" (the default, as scikit-image's): the topology of the
    trilinear interpolant, which the volume sampled 24 times finer shows (its pieces and Euler
    characteristic); a closed, edge-manifold, consistently wound surface; the same points on
    the cells' edges as lorensen, and vertices inside a few cells. scikit-image's own lewiner
    disagrees with the interpolant on three of these four volumes."""
    from scipy.ndimage import map_coordinates
    volume = np.random.default_rng(3).random((20, 22, 24)).astype(np.float32)
    verts, faces, _, _ = vdiso.marching_cubes(volume, 0.5, method="lorensen")
    lorensen = skimage.measure.marching_cubes(volume, 0.5, method="lorensen")
    assert (len(verts), len(faces)) == (len(lorensen[0]), len(lorensen[1]))
    rounded = [np.unique(np.round(v.astype(np.float64), 3), axis=0) for v in (verts, lorensen[0])]
    assert np.array_equal(rounded[0], rounded[1])
    lewiner = vdiso.marching_cubes(volume, 0.5)
    assert len(lewiner[1]) > len(faces)
    on_edges = (np.abs(lewiner[0] - np.round(lewiner[0])) > 1e-3).sum(axis=1) <= 1
    assert 0 < (~on_edges).sum() < 0.02 * len(lewiner[0])
    assert np.array_equal(np.unique(np.round(lewiner[0][on_edges].astype(np.float64), 3), axis=0), rounded[0])
    # A vertex inside a cell has that cell's spread about the level as its value.
    cells = np.floor(lewiner[0][~on_edges]).astype(int)
    corners = np.stack([volume[cells[:, 0] + dz, cells[:, 1] + dy, cells[:, 2] + dx]
                        for dz in (0, 1) for dy in (0, 1) for dx in (0, 1)], axis=1).astype(np.float64)
    spread = np.maximum(0, corners.max(axis=1) - 0.5) - np.minimum(0, corners.min(axis=1) - 0.5)
    np.testing.assert_array_equal(lewiner[3][~on_edges], spread.astype(np.float32))
    f = lewiner[1]
    directed = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
    assert len(np.unique(directed, axis=0)) == len(directed)  # wound one way: no directed edge twice
    undirected, uses = np.unique(np.sort(directed, axis=1), axis=0, return_counts=True)
    assert (uses <= 2).all()  # edge-manifold
    ends = lewiner[0][undirected[uses == 1]]  # open edges lie on the volume's faces only: closed inside
    on_face = np.zeros(len(ends), bool)
    for a, n in enumerate(volume.shape):
        on_face |= (np.abs(ends[:, :, a]) < 1e-6).all(1) | (np.abs(ends[:, :, a] - (n - 1)) < 1e-6).all(1)
    assert len(ends) > 0 and on_face.all()
    for seed, expected in ((1, (-63, 6)), (2, (-49, 5)), (3, (-45, 4)), (4, (-39, 9))):
        small = np.random.default_rng(seed).random((7, 8, 9)).astype(np.float32)
        grid = np.mgrid[tuple(slice(0, n - 1, complex(0, (n - 1) * 24 + 1)) for n in small.shape)]
        fine = map_coordinates(small.astype(np.float64), grid, order=1).astype(np.float32)
        assert euler_and_pieces(*vdiso.marching_cubes(fine, 0.5, method="lorensen")[:2]) == expected
        assert euler_and_pieces(*vdiso.marching_cubes(small, 0.5)[:2]) == expected
    # The same arrays on any thread count.
    assert all(np.array_equal(a, b) for a, b in zip(vdiso.marching_cubes(volume, 0.5, threads=1),
                                                    vdiso.marching_cubes(volume, 0.5, threads=2)))


@pytest.mark.parametrize("dtype", [np.bool_, np.float16, np.int64, np.uint64], ids=lambda d: np.dtype(d).name)
def test_the_other_dtypes_scikit_image_takes(dtype):
    # bool (a mask), float16, and 64-bit integers such as skimage.measure.label's labels.
    volume = blob(dtype=np.float32)
    if dtype is np.bool_:
        volume, level = volume > 40, 0.5
    else:
        volume, level = volume.astype(dtype), 40.5
    ours = vdiso.marching_cubes(volume, level)
    # A mask's cells are often ambiguous: compared with lorensen's, the same vertices and as many
    # triangles (an ambiguous cell may be cut along the other diagonal: area within 1 %).
    theirs = skimage.measure.marching_cubes(volume, level, method="lorensen")
    assert len(ours[1]) == len(theirs[1]) > 100
    assert abs(area(ours[0], ours[1]) / area(theirs[0], theirs[1]) - 1) < 0.01
    assert nearest(ours[0], theirs[0].astype(np.float32))[1].max() < 1e-3
    # The same surface as the dtype the library reads it as.
    as_read = volume.view(np.uint8) if dtype is np.bool_ else volume.astype(np.float32)
    assert np.array_equal(ours[1], vdiso.marching_cubes(as_read, level)[1])
    # A label beyond 32 bits goes through float64.
    if dtype is np.int64:
        wide = volume.copy()
        wide[0, 0, 0] = 1 << 40
        assert len(vdiso.marching_cubes(wide, level)[1]) > 100


def test_scikit_images_keywords():
    volume = blob(shape=(23, 27, 31))
    lorensen = dict(method="lorensen")

    def same(ours, theirs):
        assert len(ours[0]) == len(theirs[0]) and len(ours[1]) == len(theirs[1]) > 50
        assert ours[0].dtype == theirs[0].dtype and ours[1].dtype == theirs[1].dtype
        assert nearest(ours[0], theirs[0])[1].max() < 1e-4
        assert abs(area(ours[0], ours[1]) / area(theirs[0], theirs[1]) - 1) < 0.005

    for step in (2, 3):
        for spacing in ((1, 1, 1), (0.5, 1.0, 2.0)):
            same(vdiso.marching_cubes(volume, 30.5, spacing, step_size=step),
                 skimage.measure.marching_cubes(volume, 30.5, spacing=spacing, step_size=step, **lorensen))
    rng = np.random.default_rng(7)
    for _ in range(3):
        mask = rng.random(volume.shape) > 0.4
        ours = vdiso.marching_cubes(volume, 30.5, mask=mask)
        theirs = skimage.measure.marching_cubes(volume, 30.5, mask=mask, **lorensen)
        same(ours, theirs)
        # The values count the cells the mask keeps only, as scikit-image's.
        np.testing.assert_array_equal(ours[3], theirs[3][nearest(ours[0], theirs[0])[0]])
    # No level given: the middle of the values, the masked values about it.
    half = np.zeros(volume.shape, bool)
    half[:, :, :16] = True
    # A mask that leaves a brick of 32 cells out whole: the vertices on its face count the kept
    # side's cells only, though no triangle of the brick was made to drop.
    z, y, x = np.mgrid[:23, :27, :70].astype(np.float64)
    long = (100.0 - 7.0 * np.sqrt((x - 31.6) ** 2 + (y - 13.2) ** 2 + (z - 11.4) ** 2) + 0.3 * y).astype(np.float32)
    first = np.zeros(long.shape, bool)
    first[:, :, :33] = True
    assert len(vdiso._marching_cubes._bricks_marked(first, 1)) < 2
    ours, theirs = vdiso.marching_cubes(long, 30.5, mask=first), skimage.measure.marching_cubes(long, 30.5, mask=first, **lorensen)
    same(ours, theirs)
    np.testing.assert_array_equal(ours[3], theirs[3][nearest(ours[0], theirs[0])[0]])
    ours, theirs = vdiso.marching_cubes(volume, mask=half), skimage.measure.marching_cubes(volume, mask=half, **lorensen)
    same(ours, theirs)
    np.testing.assert_array_equal(ours[3], theirs[3][nearest(ours[0], theirs[0])[0]])
    # Integer samples at the level make triangles of no area, which allow_degenerate=False drops
    # with the vertices that coincide. (scikit-image's float32 interpolation leaves some of its
    # coincident vertices a rounding apart, so it drops fewer: 4784 triangles against 4724 here.)
    whole = np.round(volume).astype(np.int16)
    every = vdiso.marching_cubes(whole, 30)
    kept = vdiso.marching_cubes(whole, 30, allow_degenerate=False)
    assert len(kept[1]) < len(every[1])
    assert len(np.unique(kept[0], axis=0)) == len(kept[0])
    f = kept[1]
    assert ((f[:, 0] != f[:, 1]) & (f[:, 1] != f[:, 2]) & (f[:, 0] != f[:, 2])).all()
    assert abs(area(kept[0], kept[1]) / area(every[0], every[1]) - 1) < 1e-6
    theirs = skimage.measure.marching_cubes(whole, 30, allow_degenerate=False, **lorensen)
    assert abs(area(kept[0], kept[1]) / area(theirs[0], theirs[1]) - 1) < 0.005
    # ascent: the winding reversed against the normals, as scikit-image's.
    ours = vdiso.marching_cubes(volume, 30.5, gradient_direction="ascent")
    theirs = skimage.measure.marching_cubes(volume, 30.5, gradient_direction="ascent", **lorensen)
    for v, f, n, _ in (ours, theirs):
        t = v[f]
        assert (np.sum(np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]) * n[f[:, 0]], axis=1) > 0).mean() > 0.99
    # What it cannot do is refused by name, never answered with another surface.
    for keywords, message in ((dict(method="marching"), "method: expects \"lewiner\" or \"lorensen\""),
                              (dict(gradient_direction="up"), "gradient_direction"),
                              (dict(step_size=0), "step_size"),
                              (dict(mask=np.ones((2, 2, 2), bool)), "mask: expects the volume's shape")):
        with pytest.raises(ValueError, match=message):
            vdiso.marching_cubes(volume, 30.5, **keywords)


@pytest.mark.parametrize("step", [1, 2, 3])
def test_a_mask_meshes_only_the_bricks_it_marks_and_keeps_the_same_surface(monkeypatch, step):
    # Only the bricks holding a marked cell are meshed: the arrays are those of the whole volume
    # meshed and then filtered, as before bricks were left out.
    import vdiso._marching_cubes as mc
    v = blob((90, 100, 110))
    corner = np.zeros(v.shape, bool)
    corner[:30, :30, :30] = True  # about the blob
    scattered = np.random.default_rng(4).random(v.shape) > 0.97
    for mask in (corner, scattered, np.zeros(v.shape, bool)):
        marked = mc._bricks_marked(mask, step)
        ours = vdiso.marching_cubes(v, 80.0, mask=mask, step_size=step)
        monkeypatch.setattr(mc, "_bricks_marked", lambda mask, step: None)
        whole = vdiso.marching_cubes(v, 80.0, mask=mask, step_size=step)
        monkeypatch.undo()
        for got, want in zip(ours, whole):
            assert got.dtype == want.dtype and np.array_equal(got, want)
        if mask is corner:
            assert 0 < len(marked) <= 8  # of the 3x4x4 bricks at step 1
    assert len(vdiso.marching_cubes(v, 80.0, mask=corner)[1]) > 1000
