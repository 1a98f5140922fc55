// The generated volumes' randomness (core/synth/synth.h): every random number is a hash of (seed,
// integer position), so a sample never depends on which were generated before it. Internal to
// the generators (synth_*.cpp).
#pragma once

#include <cstdint>

namespace vdiso::synth_detail {


constexpr uint64_t kGolden64 = 0x9E3779B97F4A7C15ull;
// Odd multipliers that spread lattice coordinates before mixing.
constexpr uint64_t kLatticeX = 0xD6E8FEB86659FD93ull;
constexpr uint64_t kLatticeY = 0xA0761D6478BD642Full;
constexpr uint64_t kLatticeZ = 0xE7037ED1A0B428DBull;

// SplitMix64's finaliser: a bijection whose output bits each depend on every input bit.
inline uint64_t mix64(uint64_t x) {
    x ^= x >> 30;
    x *= 0xBF58476D1CE4E5B9ull;
    x ^= x >> 27;
    x *= 0x94D049BB133111EBull;
    return x ^ (x >> 31);
}

inline uint64_t latticeKey(uint64_t key, int64_t y, int64_t z) {
    return key + uint64_t(y) * kLatticeY + uint64_t(z) * kLatticeZ;
}

inline uint64_t latticeHash(uint64_t rowKey, int64_t x) {
    return mix64(rowKey + uint64_t(x) * kLatticeX);
}

// A 32-bit finaliser (Wellons' lowbias32): cheap enough to run once per sample, and 32-bit
// multiplies vectorise where 64-bit ones do not.
inline uint32_t mix32(uint32_t x) {
    x ^= x >> 16;
    x *= 0x7FEB352Du;
    x ^= x >> 15;
    x *= 0x846CA68Bu;
    return x ^ (x >> 16);
}

// Uniform white noise in [-1, 1), one value per sample of the row.
inline void whiteNoiseRow(uint64_t rowKey, int nx, float* out) {
    const uint32_t key = uint32_t(mix64(rowKey));
    constexpr float kScale = 2.0f / 16777216.0f;
    for (int x = 0; x < nx; ++x)
        out[x] = float(mix32(key + uint32_t(x) * 0x9E3779B9u) >> 8) * kScale - 1.0f;
}


}  // namespace vdiso::synth_detail
