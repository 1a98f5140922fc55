#include "io/store/byte_shuffle.h"

#include <cstdint>
#include <cstring>
#include <type_traits>

namespace vdiso {

namespace {

// Fixed sample sizes let the compiler unroll and vectorise the strided loops.
// Samples are loaded and stored whole, planes byte by byte: shifts and masks on whole words
// vectorise, where a strided byte copy does not. Little-endian hosts only (as the store).
template <size_t K>
void shuffleFixed(const unsigned char* in, size_t n, unsigned char* out) {
    using Word = std::conditional_t<K == 2, uint16_t, uint32_t>;
    for (size_t i = 0; i < n; ++i) {
        Word w;
        std::memcpy(&w, in + i * K, K);
        for (size_t k = 0; k < K; ++k) out[k * n + i] = uint8_t(w >> (8 * k));
    }
}

template <size_t K>
void unshuffleFixed(const unsigned char* in, size_t n, unsigned char* out) {
    using Word = std::conditional_t<K == 2, uint16_t, uint32_t>;
    for (size_t i = 0; i < n; ++i) {
        Word w = 0;
        for (size_t k = 0; k < K; ++k) w |= Word(Word(in[k * n + i]) << (8 * k));
        std::memcpy(out + i * K, &w, K);
    }
}

}  // namespace

void shuffleBytes(const unsigned char* in, size_t n, size_t sampleBytes, unsigned char* out) {
    switch (sampleBytes) {
        case 2: return shuffleFixed<2>(in, n, out);
        case 4: return shuffleFixed<4>(in, n, out);
        default: break;
    }
    if (sampleBytes == 1) {
        std::memcpy(out, in, n);
        return;
    }
    for (size_t i = 0; i < n; ++i)
        for (size_t k = 0; k < sampleBytes; ++k) out[k * n + i] = in[i * sampleBytes + k];
}

void unshuffleBytes(const unsigned char* in, size_t n, size_t sampleBytes, unsigned char* out) {
    switch (sampleBytes) {
        case 2: return unshuffleFixed<2>(in, n, out);
        case 4: return unshuffleFixed<4>(in, n, out);
        default: break;
    }
    if (sampleBytes == 1) {
        std::memcpy(out, in, n);
        return;
    }
    for (size_t i = 0; i < n; ++i)
        for (size_t k = 0; k < sampleBytes; ++k) out[i * sampleBytes + k] = in[k * n + i];
}

}  // namespace vdiso
