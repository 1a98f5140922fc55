// The byte-shuffle filter of the brick store (BrickFilter::ByteShuffle): n samples of
// `sampleBytes` bytes each are regrouped so that byte k of every sample is contiguous.
// `in` and `out` hold n * sampleBytes bytes and must not overlap. sampleBytes 1 is a copy.
#pragma once

#include <cstddef>

namespace vdiso {

void shuffleBytes(const unsigned char* in, size_t n, size_t sampleBytes, unsigned char* out);
void unshuffleBytes(const unsigned char* in, size_t n, size_t sampleBytes, unsigned char* out);

}  // namespace vdiso
