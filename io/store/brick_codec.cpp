#include "io/store/brick_codec.h"

#include <algorithm>
#include <cstring>
#include <stdexcept>

#include <lz4.h>
#include <zstd.h>

#include "io/store/byte_shuffle.h"

namespace vdiso {

BrickCodecScratch::~BrickCodecScratch() { ZSTD_freeCCtx(static_cast<ZSTD_CCtx*>(mZstd)); }

bool encodeBrickBytes(std::span<const unsigned char> raw, size_t sampleBytes, Compression compression,
                      BrickFilter filter, int level, BrickCodecScratch& scratch, std::vector<unsigned char>& stored) {
    if (compression != Compression::None) {
        const unsigned char* input = raw.data();
        if (filter == BrickFilter::ByteShuffle && sampleBytes > 1) {
            scratch.mShuffled.resize(raw.size());
            shuffleBytes(input, raw.size() / sampleBytes, sampleBytes, scratch.mShuffled.data());
            input = scratch.mShuffled.data();
        }
        size_t n = 0;
        if (compression == Compression::Lz4) {
            stored.resize(size_t(LZ4_compressBound(int(raw.size()))));
            n = size_t(LZ4_compress_default(reinterpret_cast<const char*>(input), reinterpret_cast<char*>(stored.data()),
                                            int(raw.size()), int(stored.size())));
            if (n == 0) throw std::runtime_error("lz4: cannot compress a brick");
        } else {
            if (!scratch.mZstd) scratch.mZstd = ZSTD_createCCtx();
            stored.resize(ZSTD_compressBound(raw.size()));
            n = ZSTD_compressCCtx(static_cast<ZSTD_CCtx*>(scratch.mZstd), stored.data(), stored.size(), input,
                                  raw.size(), level);
            if (ZSTD_isError(n)) throw std::runtime_error(std::string("zstd: ") + ZSTD_getErrorName(n));
        }
        // Incompressible bricks (noise) are stored raw: reading them is then a plain copy.
        if (n < raw.size()) {
            stored.resize(n);
            return true;
        }
    }
    stored.assign(raw.begin(), raw.end());
    return false;
}

std::string decodeBrickBytes(std::span<const unsigned char> stored, bool compressed, size_t sampleBytes,
                             Compression compression, BrickFilter filter, void* dst, size_t raw) {
    if (!compressed) {
        if (stored.size() != raw) return "stored size does not match the brick size";
        std::memcpy(dst, stored.data(), raw);
        return "";
    }
    const bool shuffled = filter == BrickFilter::ByteShuffle && sampleBytes > 1;
    thread_local std::vector<unsigned char> planes;
    if (shuffled) planes.resize(raw);
    unsigned char* out = shuffled ? planes.data() : static_cast<unsigned char*>(dst);
    if (compression == Compression::Lz4) {
        const int got = LZ4_decompress_safe(reinterpret_cast<const char*>(stored.data()), reinterpret_cast<char*>(out),
                                            int(stored.size()), int(raw));
        if (got < 0) return "cannot decompress: malformed LZ4 data";
        if (size_t(got) != raw) return "decompressed to the wrong size";
    } else {
        const size_t got = ZSTD_decompress(out, raw, stored.data(), stored.size());
        if (ZSTD_isError(got)) return std::string("cannot decompress: ") + ZSTD_getErrorName(got);
        if (got != raw) return "decompressed to the wrong size";
    }
    if (shuffled) unshuffleBytes(planes.data(), raw / sampleBytes, sampleBytes, static_cast<unsigned char*>(dst));
    return "";
}

uint64_t maxStoredBrickBytes(uint64_t raw) {
    return std::max<uint64_t>({raw, ZSTD_compressBound(raw), uint64_t(LZ4_compressBound(int(raw)))});
}

}  // namespace vdiso
