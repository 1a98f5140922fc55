#include "io/readers/sample_decode.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

namespace vdiso {

const char* fileScalarName(FileScalar t) {
    switch (t) {
        case FileScalar::I8: return "int8";
        case FileScalar::U8: return "uint8";
        case FileScalar::I16: return "int16";
        case FileScalar::U16: return "uint16";
        case FileScalar::I32: return "int32";
        case FileScalar::U32: return "uint32";
        case FileScalar::F32: return "float32";
        case FileScalar::F64: return "float64";
    }
    return "?";
}

ScalarType storeTypeFor(FileScalar t, bool scaled) {
    if (scaled) return ScalarType::F32;
    switch (t) {
        case FileScalar::U8: return ScalarType::U8;
        case FileScalar::I8:
        case FileScalar::I16: return ScalarType::I16;
        case FileScalar::U16: return ScalarType::U16;
        default: return ScalarType::F32;
    }
}

namespace {

template <class T>
T loadSample(const unsigned char* p, bool swapBytes) {
    unsigned char bytes[sizeof(T)];
    if (swapBytes)
        std::reverse_copy(p, p + sizeof(T), bytes);
    else
        std::memcpy(bytes, p, sizeof(T));
    T v;
    std::memcpy(&v, bytes, sizeof(T));
    return v;
}

template <class Dst>
Dst toStore(double v) {
    if constexpr (std::is_floating_point_v<Dst>) {
        return Dst(v);
    } else {
        // NaN has no integer: it becomes 0, as a missing sample does.
        v = std::isnan(v) ? 0.0 : std::nearbyint(v);
        v = std::clamp(v, double(std::numeric_limits<Dst>::lowest()),
                       double(std::numeric_limits<Dst>::max()));
        return Dst(v);
    }
}

template <class Src, class Dst>
void decodeTyped(const unsigned char* src, bool swapBytes, size_t n, Dst* dst, bool scaled,
                 double slope, double intercept) {
    // The common case (same type, native order, unscaled) is a copy.
    if constexpr (std::is_same_v<Src, Dst>) {
        if (!swapBytes && !scaled) {
            std::memcpy(dst, src, n * sizeof(Dst));
            return;
        }
    }
    for (size_t i = 0; i < n; ++i) {
        Src s = loadSample<Src>(src + i * sizeof(Src), swapBytes);
        if (scaled)
            dst[i] = toStore<Dst>(double(s) * slope + intercept);
        else if constexpr (std::is_convertible_v<Src, Dst> && std::is_integral_v<Src> &&
                           std::is_integral_v<Dst> && sizeof(Src) < sizeof(Dst))
            dst[i] = Dst(s);
        else
            dst[i] = toStore<Dst>(double(s));
    }
}

template <class Dst>
void decodeTo(const unsigned char* src, FileScalar t, bool swapBytes, size_t n, Dst* dst,
              bool scaled, double slope, double intercept) {
    switch (t) {
        case FileScalar::I8: return decodeTyped<int8_t>(src, swapBytes, n, dst, scaled, slope, intercept);
        case FileScalar::U8: return decodeTyped<uint8_t>(src, swapBytes, n, dst, scaled, slope, intercept);
        case FileScalar::I16: return decodeTyped<int16_t>(src, swapBytes, n, dst, scaled, slope, intercept);
        case FileScalar::U16: return decodeTyped<uint16_t>(src, swapBytes, n, dst, scaled, slope, intercept);
        case FileScalar::I32: return decodeTyped<int32_t>(src, swapBytes, n, dst, scaled, slope, intercept);
        case FileScalar::U32: return decodeTyped<uint32_t>(src, swapBytes, n, dst, scaled, slope, intercept);
        case FileScalar::F32: return decodeTyped<float>(src, swapBytes, n, dst, scaled, slope, intercept);
        case FileScalar::F64: return decodeTyped<double>(src, swapBytes, n, dst, scaled, slope, intercept);
    }
}

}  // namespace

void decodeSamples(const void* src, FileScalar srcType, bool swapBytes, size_t n, void* dst,
                   ScalarType dstType, bool scaled, double slope, double intercept) {
    if (fileScalarSize(srcType) == 1) swapBytes = false;
    const auto* bytes = static_cast<const unsigned char*>(src);
    visitScalarType(dstType, [&](auto zero) {
        using Dst = decltype(zero);
        decodeTo(bytes, srcType, swapBytes, n, static_cast<Dst*>(dst), scaled, slope, intercept);
    });
}

}  // namespace vdiso
