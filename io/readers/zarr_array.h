// One Zarr array's metadata and chunks, Zarr v2 (.zarray) and v3 (zarr.json), written by hand
// on nlohmann-json after the Zarr specifications (Debian has no C++ Zarr library).
//
// Supported: C order; data types int8..int32, uint8..uint32, float32, float64 in either byte
// order; a regular chunk grid; the default and v2 chunk key encodings with "." or "/"; no
// compressor, or blosc, zstd, gzip or zlib (v2 "compressor"; v3 "bytes" then one of
// blosc/zstd/gzip, or v3's sharding_indexed codec holding those, its index little-endian with
// or without crc32c, at the shard's end or start); fill_value a number, null (0), "NaN",
// "Infinity" or "-Infinity". Refused with a message saying so: F order, v2 filters, v3
// array-to-array codecs (transpose), sharding nested or after other codecs, 64-bit integers,
// booleans, complex and structured types, fill values as raw bits.
// A chunk is at most 1 GiB decoded.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "io/readers/sample_decode.h"

namespace vdiso {

enum class ZarrCompressor { None, Blosc, Zstd, Gzip };  // Gzip also inflates zlib streams

struct ZarrArrayMeta {
    int format = 2;                      // 2 or 3
    std::vector<int64_t> shape, chunks;  // slowest axis first
    FileScalar type = FileScalar::U8;
    bool bigEndian = false;
    ZarrCompressor compressor = ZarrCompressor::None;
    double fill = 0.0;
    std::string keyPrefix;  // "c" for v3's default encoding, else empty
    char separator = '.';
    // Sharded (v3 sharding_indexed): `chunks` are the inner chunks, what is decoded, and
    // `shards` the chunk grid's chunks, the keys; each shard ends (or starts) with an index of
    // its inner chunks in C order, (offset, size) as little-endian u64 pairs, (2^64-1, 2^64-1)
    // for one not stored, followed by its CRC-32C when `indexCrc`. Empty when not sharded.
    std::vector<int64_t> shards;
    bool indexAtEnd = true, indexCrc = false;

    // Bytes of one decoded chunk (every chunk is full size, edge chunks padded).
    uint64_t chunkBytes() const;
    // The chunk's key, relative to the array's folder ("0.1.2", "c/0/1/2"); for a sharded
    // array, `index` is a shard's.
    std::string chunkKey(const std::vector<int64_t>& index) const;
    // Inner chunks per shard (1 when not sharded), and the bytes of a shard's index.
    uint64_t chunksPerShard() const;
    uint64_t shardIndexBytes() const { return chunksPerShard() * 16 + (indexCrc ? 4 : 0); }
};

// Parses .zarray (format 2) or zarr.json (format 3) text. Throws IoError "<where>: ..." for
// malformed or unsupported metadata.
ZarrArrayMeta parseZarrArrayMeta(const std::string& json, int format, const std::string& where);

// Decodes one stored chunk (`size` bytes) into out (meta.chunkBytes() bytes: samples of
// meta.type in the array's byte order). Throws IoError "<where>: ..." (where names the chunk)
// when the data is corrupt or decodes to another size.
void decodeZarrChunk(const ZarrArrayMeta& meta, const unsigned char* data, size_t size,
                     unsigned char* out, const std::string& where);

}  // namespace vdiso
