#include "io/byte_shuffle.h"

#include <cstring>

namespace vdiso {

namespace {

// Fixed sample sizes let the compiler unroll and vectorise the strided loops.
template <size_t K>
void shuffleFixed(const unsigned char* in, size_t n, unsigned char* out) {
    for (size_t i = 0; i < n; ++i)
        for (size_t k = 0; k < K; ++k) out[k * n + i] = in[i * K + k];
}

template <size_t K>
void unshuffleFixed(const unsigned char* in, size_t n, unsigned char* out) {
    for (size_t i = 0; i < n; ++i)
        for (size_t k = 0; k < K; ++k) out[i * K + k] = in[k * n + i];
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
