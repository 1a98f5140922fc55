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
