// The pieces of the compiled module _vdiso, each bound by its own file.
#pragma once

#include <pybind11/pybind11.h>

#include <cstdint>

namespace vdiso::py {

// `value`, given as the keyword `name`, when it lies in [lo, hi]; else a SettingsError (a
// ValueError naming it). Integers cross from Python as int64_t and are narrowed only after this.
int64_t checkedInt(const char* name, int64_t value, int64_t lo, int64_t hi);

void bindErrors(pybind11::module_& m);
void bindMarchingCubes(pybind11::module_& m);
void bindStore(pybind11::module_& m);
void bindConvert(pybind11::module_& m);
void bindServe(pybind11::module_& m);

}  // namespace vdiso::py
