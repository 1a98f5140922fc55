// Arithmetic on sizes that may derive from untrusted numbers (file headers, command lines):
// products and sums that throw std::overflow_error instead of wrapping. Readers check their
// inputs against the limits of core/volume.h first, with a message naming the file; these are
// the second guard, so that no unchecked path can wrap a size into a small allocation.
#pragma once

#include <cstdint>
#include <stdexcept>

namespace vdiso {

inline int64_t checkedMul(int64_t a, int64_t b) {
    int64_t r;
    if (__builtin_mul_overflow(a, b, &r)) throw std::overflow_error("a size overflows 64 bits");
    return r;
}

inline uint64_t checkedMul(uint64_t a, uint64_t b) {
    uint64_t r;
    if (__builtin_mul_overflow(a, b, &r)) throw std::overflow_error("a size overflows 64 bits");
    return r;
}

inline uint64_t checkedAdd(uint64_t a, uint64_t b) {
    uint64_t r;
    if (__builtin_add_overflow(a, b, &r)) throw std::overflow_error("a size overflows 64 bits");
    return r;
}

}  // namespace vdiso
