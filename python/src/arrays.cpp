#include "arrays.h"

#include <stdexcept>
#include <string>

namespace vdiso::py {

namespace pyb = pybind11;

FileScalar fileScalarOfDtype(const pyb::dtype& dtype, const char* what) {
    const char kind = dtype.kind();
    const auto size = dtype.itemsize();
    const std::string name = pyb::str(pyb::handle(dtype)).cast<std::string>();
    const char order = pyb::cast<char>(dtype.attr("byteorder"));
    if (order == '>' || (order == '<' && hostIsBigEndian()))
        throw std::invalid_argument(std::string(what) + ": samples of " + name +
                                    " are not in this machine's byte order (use .astype(dtype.newbyteorder('=')))");
    if (kind == 'u' && size == 1) return FileScalar::U8;
    if (kind == 'i' && size == 1) return FileScalar::I8;
    if (kind == 'u' && size == 2) return FileScalar::U16;
    if (kind == 'i' && size == 2) return FileScalar::I16;
    if (kind == 'u' && size == 4) return FileScalar::U32;
    if (kind == 'i' && size == 4) return FileScalar::I32;
    if (kind == 'f' && size == 4) return FileScalar::F32;
    if (kind == 'f' && size == 8) return FileScalar::F64;
    throw std::invalid_argument(std::string(what) + ": samples of " + name +
                                " are not supported (uint8, int8, uint16, int16, uint32, int32, float32, float64)");
}

pyb::dtype dtypeOf(ScalarType type) {
    switch (type) {
        case ScalarType::U8: return pyb::dtype::of<uint8_t>();
        case ScalarType::I16: return pyb::dtype::of<int16_t>();
        case ScalarType::U16: return pyb::dtype::of<uint16_t>();
        case ScalarType::F32: break;
    }
    return pyb::dtype::of<float>();
}

StridedSamples stridedSamplesOf(const pyb::array& volume, const char* what) {
    if (volume.ndim() != 3)
        throw std::invalid_argument(std::string(what) + ": expects a 3-D array, not one of " +
                                    std::to_string(volume.ndim()) + " dimensions");
    StridedSamples s;
    s.type = fileScalarOfDtype(volume.dtype(), what);
    for (int a = 0; a < 3; ++a) {
        if (volume.shape(a) < 2)
            throw std::invalid_argument(std::string(what) + ": axis " + std::to_string(a) + " has " +
                                        std::to_string(volume.shape(a)) +
                                        " samples; every axis needs at least 2 (cells lie between samples)");
        s.dims[size_t(2 - a)] = volume.shape(a);
        s.strides[size_t(2 - a)] = volume.strides(a);
    }
    s.data = volume.data();
    return s;
}

}  // namespace vdiso::py
