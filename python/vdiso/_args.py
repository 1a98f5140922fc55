"""Arguments checked as the library takes them, naming the keyword (vdiso's Python side)."""

import operator as _operator


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
