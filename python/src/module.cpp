// The compiled module behind `import vdiso` (python/vdiso/__init__.py holds the Python side).
// Errors are translated once, here: a setting or an argument -> ValueError naming the keyword,
// I/O -> OSError with the library's message (which names the file or URL), an interrupt ->
// KeyboardInterrupt, memory that cannot be had -> MemoryError (the library's message names the
// size), anything else -> vdiso.Error (a RuntimeError).
#include <pybind11/pybind11.h>

#include "app/extract_settings.h"
#include "core/camera.h"
#include "core/settings_error.h"
#include "bindings.h"
#include "cache/brick_cache.h"
#include "core/interrupt.h"
#include "io/atomic_output.h"
#include "io/error.h"

namespace vdiso::py {

namespace pyb = pybind11;

int64_t checkedInt(const char* name, int64_t value, int64_t lo, int64_t hi) {
    if (value < lo || value > hi)
        throw SettingsError(name, "expects " + std::to_string(lo) + " to " + std::to_string(hi) + ", not " +
                                      std::to_string(value));
    return value;
}

void bindErrors(pyb::module_& m) {
    static pyb::exception<std::runtime_error> error(m, "Error", PyExc_RuntimeError);
    error.doc() = "What vdiso raises when neither a bad argument (ValueError, TypeError) nor I/O (OSError)\n"
                  "is the cause: a RuntimeError with the library's message.";
    pyb::register_exception_translator([](std::exception_ptr p) {
        try {
            if (p) std::rethrow_exception(p);
        } catch (const SettingsError& e) {
            PyErr_SetString(PyExc_ValueError, (e.setting() + " " + e.what()).c_str());
        } catch (const CacheBudgetError& e) {
            PyErr_SetString(PyExc_ValueError, (std::string(e.what()) + " (cache_mb)").c_str());
        } catch (const OutputExistsError& e) {
            PyErr_SetString(PyExc_FileExistsError, (std::string(e.what()) + " (pass overwrite=True to replace it)").c_str());
        } catch (const Interrupted& e) {
            PyErr_SetString(PyExc_KeyboardInterrupt, e.what());
        } catch (const IoError& e) {
            PyErr_SetString(PyExc_OSError, e.what());
        } catch (const std::invalid_argument& e) {
            PyErr_SetString(PyExc_ValueError, e.what());
        } catch (const std::bad_alloc& e) {
            PyErr_SetString(PyExc_MemoryError, e.what());
        } catch (const std::exception& e) {
            error(e.what());
        }
    });
}

}  // namespace vdiso::py

PYBIND11_MODULE(_vdiso, m) {
    m.doc() = "vdiso's compiled core; use the vdiso package.";
    vdiso::py::bindErrors(m);
    vdiso::py::bindMarchingCubes(m);
    vdiso::py::bindStore(m);
    vdiso::py::bindConvert(m);
    vdiso::py::bindServe(m);
    m.attr("_web_root") = VDISO_WEB_DIR;
    m.attr("__version__") = VDISO_VERSION;  // the project's (CMakeLists.txt)
    // The image sides a camera may have (core/camera.h), for the arguments' checks in Python.
    m.attr("_min_image_side") = vdiso::kMinImageSide;
    m.attr("_max_image_side") = vdiso::kMaxImageSide;
    // The library's defaults, where Python's signatures say None (app/extract_settings.h).
    m.attr("_default_size") = pybind11::make_tuple(vdiso::kDefaultImageWidth, vdiso::kDefaultImageHeight);
}
