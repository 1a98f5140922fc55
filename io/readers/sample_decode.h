// Decoding samples as files store them into the scalar types the brick store holds.
//
// Files carry more types than the store (int8, int32, float64, big-endian, scaled); each maps
// to one store type (storeTypeFor), chosen so no value is lost except where noted:
// i8 -> i16, i32/u32/f64 -> f32 (values beyond 2^24 lose low bits), any scaled type -> f32.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string_view>

#include "core/scalar_type.h"

namespace vdiso {

enum class FileScalar { I8, U8, I16, U16, I32, U32, F32, F64 };

// Inline: the GDCM module (io/readers/gdcm_module/gdcm_module.h) uses it without linking vdiso_io.
inline size_t fileScalarSize(FileScalar t) {
    switch (t) {
        case FileScalar::I8:
        case FileScalar::U8: return 1;
        case FileScalar::I16:
        case FileScalar::U16: return 2;
        case FileScalar::I32:
        case FileScalar::U32:
        case FileScalar::F32: return 4;
        case FileScalar::F64: return 8;
    }
    return 0;
}
const char* fileScalarName(FileScalar t);

// The store type that holds every value of `t`; with `scaled` (slope/intercept), f32.
ScalarType storeTypeFor(FileScalar t, bool scaled);

// Converts n samples: src (type srcType, byte-swapped first if swapBytes) to dst (dstType),
// applying value * slope + intercept when `scaled`. Floats converted to an integer store type
// are rounded and clamped; storeTypeFor never asks for that.
void decodeSamples(const void* src, FileScalar srcType, bool swapBytes, size_t n, void* dst,
                   ScalarType dstType, bool scaled = false, double slope = 1.0,
                   double intercept = 0.0);

constexpr FileScalar fileScalarOf(ScalarType t) {
    switch (t) {
        case ScalarType::U8: return FileScalar::U8;
        case ScalarType::I16: return FileScalar::I16;
        case ScalarType::U16: return FileScalar::U16;
        case ScalarType::F32: break;
    }
    return FileScalar::F32;
}

// Calls f(T{}) with T the C++ type of file scalar `t`; returns what f returns.
template <class F>
decltype(auto) visitFileScalar(FileScalar t, F&& f) {
    switch (t) {
        case FileScalar::I8: return f(int8_t{});
        case FileScalar::U8: return f(uint8_t{});
        case FileScalar::I16: return f(int16_t{});
        case FileScalar::U16: return f(uint16_t{});
        case FileScalar::I32: return f(int32_t{});
        case FileScalar::U32: return f(uint32_t{});
        case FileScalar::F32: return f(float{});
        case FileScalar::F64: break;
    }
    return f(double{});
}

// True on a big-endian host (never on the machines we build for, but readers ask).
constexpr bool hostIsBigEndian() {
    return __BYTE_ORDER__ == __ORDER_BIG_ENDIAN__;
}

}  // namespace vdiso
