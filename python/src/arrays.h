// NumPy arrays to and from the library: a 3-D array read in place as strided samples, and mesh
// arrays over C++ buffers, owned by a Python object (the array's base), without a copy.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include "app/array_brick_source.h"
#include "io/readers/sample_decode.h"

namespace vdiso::py {

// The file scalar of a NumPy dtype (u8, i8, u16, i16, u32, i32, f32, f64, native byte order);
// throws std::invalid_argument naming `what` and the dtype otherwise.
FileScalar fileScalarOfDtype(const pybind11::dtype& dtype, const char* what);
pybind11::dtype dtypeOf(ScalarType type);

// A 3-D array in place: NumPy's axis 0 is the slowest (z), axis 2 the x the kernel walks.
// Throws std::invalid_argument for another ndim, an axis under 2 samples or a bad dtype.
StridedSamples stridedSamplesOf(const pybind11::array& volume, const char* what);

// A pointer NumPy accepts for an array of no rows (a vector without storage gives null).
template <class T>
const T* rowsOrEmpty(const T* data) {
    static const T kNone[3] = {};
    return data ? data : kNone;
}

// An (rows, columns) array of T over `data`, kept alive by `owner`.
template <class T>
pybind11::array_t<T> arrayOver(const T* data, size_t rows, size_t columns, pybind11::handle owner) {
    return pybind11::array_t<T>({rows, columns}, {columns * sizeof(T), sizeof(T)}, data, owner);
}

}  // namespace vdiso::py
