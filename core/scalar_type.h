// Scalar types a volume may hold, and the one place that dispatches on them.
//
// Stores hold u8, i16, u16 or f32 samples. Algorithms are templates over the sample type;
// visitScalarType() instantiates them once per type, at the brick boundary, so inner loops
// never branch on the type.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string_view>

namespace vdiso {

enum class ScalarType : uint8_t { U8 = 1, I16 = 2, U16 = 3, F32 = 4 };

constexpr size_t scalarSize(ScalarType t) {
    switch (t) {
        case ScalarType::U8: return 1;
        case ScalarType::I16:
        case ScalarType::U16: return 2;
        case ScalarType::F32: return 4;
    }
    return 0;
}

constexpr const char* scalarTypeName(ScalarType t) {
    switch (t) {
        case ScalarType::U8: return "u8";
        case ScalarType::I16: return "i16";
        case ScalarType::U16: return "u16";
        case ScalarType::F32: return "f32";
    }
    return "?";
}

// Parses "u8", "i16", "u16", "f32"; nullopt for anything else.
std::optional<ScalarType> parseScalarType(std::string_view name);

// True for the numeric codes ScalarType uses (1..4); lets readers validate bytes from disk.
constexpr bool isValidScalarCode(uint8_t code) { return code >= 1 && code <= 4; }

template <class T>
constexpr ScalarType scalarTypeOf();
template <> constexpr ScalarType scalarTypeOf<uint8_t>() { return ScalarType::U8; }
template <> constexpr ScalarType scalarTypeOf<int16_t>() { return ScalarType::I16; }
template <> constexpr ScalarType scalarTypeOf<uint16_t>() { return ScalarType::U16; }
template <> constexpr ScalarType scalarTypeOf<float>() { return ScalarType::F32; }

// Calls f(T{}) with T the C++ type of `t`; returns what f returns.
template <class F>
decltype(auto) visitScalarType(ScalarType t, F&& f) {
    switch (t) {
        case ScalarType::U8: return f(uint8_t{});
        case ScalarType::I16: return f(int16_t{});
        case ScalarType::U16: return f(uint16_t{});
        case ScalarType::F32: break;
    }
    return f(float{});
}

}  // namespace vdiso
