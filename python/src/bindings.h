// The pieces of the compiled module _vdiso, each bound by its own file.
#pragma once

#include <pybind11/pybind11.h>

namespace vdiso::py {

void bindErrors(pybind11::module_& m);
void bindMarchingCubes(pybind11::module_& m);
void bindStore(pybind11::module_& m);
void bindConvert(pybind11::module_& m);
void bindServe(pybind11::module_& m);

}  // namespace vdiso::py
