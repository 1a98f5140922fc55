// Which samples of a row lie above an isovalue, as one word: bit i set when s[i] > iso
// (core/kernel/iso.h), for rows of at most 64 samples. SSE2, which every x86-64 has, compares
// 16 samples at a time, the last group too (its bits past the row dropped): so the samples
// s[0, 16 * ceil(n / 16)) are read, and must lie in one array. The kernel's rows do: a brick's
// samples ((B+3)^3, core/brick_layout.h) go on for a ghost plane past the last row it classifies.
// (A meta-cell's rows are 5 corners: one by one, they were the classification's whole cost.)
// Exactly IsoThreshold::above for every sample, NaN and infinities included.
#pragma once

#include <cmath>
#include <cstdint>
#include <type_traits>

#include <emmintrin.h>

namespace vdiso {

// Comparisons against the isovalue in the samples' own type: for integers, s > iso exactly
// when s > floor(iso), so the cell loop compares integers.
template <class T>
struct IsoThreshold {
    using Compare = std::conditional_t<std::is_integral_v<T>, int64_t, double>;
    Compare value;
    explicit IsoThreshold(double iso) {
        if constexpr (std::is_integral_v<T>)
            value = int64_t(std::fmin(std::fmax(std::floor(iso), -1e18), 1e18));
        else
            value = iso;
    }
    bool above(T s) const { return Compare(s) > value; }
};

namespace row_classify_detail {

// 16 samples from `s` against the threshold in the lanes' own terms: bit k for s[k].
template <class T>
inline uint32_t above16(const T* s, __m128i threshold) {
    if constexpr (std::is_same_v<T, uint8_t>) {
        const __m128i bias = _mm_set1_epi8(char(0x80));
        const __m128i v = _mm_xor_si128(_mm_loadu_si128(reinterpret_cast<const __m128i*>(s)), bias);
        return uint32_t(_mm_movemask_epi8(_mm_cmpgt_epi8(v, threshold)));
    } else if constexpr (std::is_same_v<T, uint16_t> || std::is_same_v<T, int16_t>) {
        const __m128i bias = _mm_set1_epi16(std::is_same_v<T, uint16_t> ? short(0x8000) : short(0));
        const __m128i a = _mm_xor_si128(_mm_loadu_si128(reinterpret_cast<const __m128i*>(s)), bias);
        const __m128i b = _mm_xor_si128(_mm_loadu_si128(reinterpret_cast<const __m128i*>(s + 8)), bias);
        return uint32_t(_mm_movemask_epi8(_mm_packs_epi16(_mm_cmpgt_epi16(a, threshold), _mm_cmpgt_epi16(b, threshold))));
    } else {
        const __m128 t = _mm_castsi128_ps(threshold);
        uint32_t bits = 0;
        for (int k = 0; k < 4; ++k) bits |= uint32_t(_mm_movemask_ps(_mm_cmpgt_ps(_mm_loadu_ps(s + 4 * k), t))) << (4 * k);
        return bits;
    }
}

}  // namespace row_classify_detail

// The set bits of x: the baseline x86-64 has no POPCNT instruction, and the compiler's own
// fallback is a call.
inline int bitCount(uint64_t x) {
    x -= (x >> 1) & 0x5555555555555555ull;
    x = (x & 0x3333333333333333ull) + ((x >> 2) & 0x3333333333333333ull);
    x = (x + (x >> 4)) & 0x0f0f0f0f0f0f0f0full;
    return int((x * 0x0101010101010101ull) >> 56);
}

// Bits of s[0..n) above the threshold (n <= 64; reads up to the 16-sample group that holds s[n - 1]).
template <class T>
[[gnu::always_inline]] inline uint64_t aboveBits(const T* s, int n, const IsoThreshold<T>& threshold) {
    using namespace row_classify_detail;
    uint64_t bits = 0;
    // The threshold in the lanes' terms; where every sample, or none, of the type is above it,
    // the whole row is known at once.
    __m128i t;
    if constexpr (std::is_integral_v<T>) {
        constexpr int64_t lowest = std::is_same_v<T, int16_t> ? -32768 : 0;
        constexpr int64_t highest = std::is_same_v<T, uint8_t> ? 255 : std::is_same_v<T, int16_t> ? 32767 : 65535;
        if (threshold.value < lowest) return n == 64 ? ~uint64_t(0) : (uint64_t(1) << n) - 1;
        if (threshold.value >= highest) return 0;
        if constexpr (std::is_same_v<T, uint8_t>)
            t = _mm_set1_epi8(char(threshold.value ^ 0x80));
        else if constexpr (std::is_same_v<T, uint16_t>)
            t = _mm_set1_epi16(short(threshold.value ^ 0x8000));
        else
            t = _mm_set1_epi16(short(threshold.value));
    } else {
        // s > iso (in double) exactly when s > the largest float not above iso.
        float f = float(threshold.value);
        if (double(f) > threshold.value) f = std::nextafter(f, -INFINITY);
        t = _mm_castps_si128(_mm_set1_ps(f));
    }
    for (int i = 0; i < n; i += 16) bits |= uint64_t(above16(s + i, t)) << i;
    return n == 64 ? bits : bits & ((uint64_t(1) << n) - 1);
}

}  // namespace vdiso
