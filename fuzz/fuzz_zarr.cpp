// One Zarr array's metadata and one chunk: the first byte picks the format (even: .zarray of
// Zarr v2, odd: zarr.json of v3), the metadata runs to the first NUL byte, the chunk's stored
// bytes follow. Reaches the metadata parser (dtype, codecs, chunk grid, fill value) and the chunk
// decoders (blosc, zstd, gzip/zlib, none) with their size checks.
#include <cstring>
#include <string>
#include <vector>

#include "fuzz/fuzz_input.h"
#include "io/readers/zarr_array.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    if (size < 1) return 0;
    const int format = (data[0] & 1) ? 3 : 2;
    const auto* begin = reinterpret_cast<const char*>(data + 1);
    const auto* end = begin + (size - 1);
    const char* nul = static_cast<const char*>(std::memchr(begin, 0, size_t(end - begin)));
    const std::string json(begin, nul ? nul : end);
    const auto* chunk = reinterpret_cast<const unsigned char*>(nul ? nul + 1 : end);
    const size_t chunkSize = size_t(reinterpret_cast<const unsigned char*>(end) - chunk);
    vdiso::fuzz::expectAnswer([&] {
        const vdiso::ZarrArrayMeta meta = vdiso::parseZarrArrayMeta(json, format, "fuzz/.zarray");
        if (meta.chunkBytes() > (uint64_t(64) << 20)) return;  // accepted: its size is its own
        std::vector<unsigned char> out(size_t(meta.chunkBytes()));
        vdiso::decodeZarrChunk(meta, chunk, chunkSize, out.data(), "fuzz/0.0.0");
    });
    return 0;
}
