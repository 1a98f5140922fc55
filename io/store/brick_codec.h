// The bytes a brick is stored as (docs/store-format.md): its samples, byte-shuffled when the
// store's filter says so (io/store/byte_shuffle.h), then compressed on their own by the store's
// codec, and kept raw when compressing does not make them smaller. The one place a brick is
// encoded (io/store/brick_encoder.h) and decoded (io/store/brick_store.h).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "io/store/store_format.h"

namespace vdiso {

// What encoding keeps between bricks on one thread (a zstd context, the shuffled samples).
class BrickCodecScratch {
public:
    BrickCodecScratch() = default;
    ~BrickCodecScratch();
    BrickCodecScratch(const BrickCodecScratch&) = delete;
    BrickCodecScratch& operator=(const BrickCodecScratch&) = delete;

private:
    friend bool encodeBrickBytes(std::span<const unsigned char>, size_t, Compression, BrickFilter, int,
                                 BrickCodecScratch&, std::vector<unsigned char>&);
    void* mZstd = nullptr;  // ZSTD_CCtx
    std::vector<unsigned char> mShuffled;
};

// Encodes a brick's `raw` samples (`sampleBytes` each) into `stored`: filtered, then compressed
// with `compression` (`level`: zstd's). Returns whether `stored` is compressed; false, it holds
// `raw` as is (no compression asked, or none that made it smaller). Throws std::runtime_error
// when the codec fails.
bool encodeBrickBytes(std::span<const unsigned char> raw, size_t sampleBytes, Compression compression,
                      BrickFilter filter, int level, BrickCodecScratch& scratch, std::vector<unsigned char>& stored);

// Decodes `stored` (compressed or not, as its index entry says) into the brick's `raw` bytes at
// `dst`. Returns "" or what is wrong with the stored bytes ("cannot decompress: ...",
// "decompressed to the wrong size", "stored size does not match the brick size"), for the caller
// to name the file and the brick.
std::string decodeBrickBytes(std::span<const unsigned char> stored, bool compressed, size_t sampleBytes,
                             Compression compression, BrickFilter filter, void* dst, size_t raw);

// The most bytes a brick of `raw` bytes may be stored as, by any codec: an index entry that says
// more is corrupt.
uint64_t maxStoredBrickBytes(uint64_t raw);

}  // namespace vdiso
