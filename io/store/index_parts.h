// The store's index as stored from format version 5 (docs/store-format.md, "Index"): the raw
// index cut into parts of kIndexPartBytes, each compressed on its own with zstd, behind a
// directory of their stored sizes and CRC-32s. The raw index is 160 bytes a brick (94 MB for a
// 2560^3 store with levels); stored, it is several times smaller, which is what crosses the
// network when the store is remote, and its parts decompress in parallel or one at a time, as
// they are needed (io/store/lazy_index.h). Internal to io/.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace vdiso::store_format {

constexpr uint32_t kIndexPartBytes = uint32_t(1) << 20;

// The stored form of a raw index (parts compressed in parallel).
std::vector<unsigned char> packIndex(const std::vector<unsigned char>& raw);

// The stored size's bounds for a raw index of rawBytes: the directory alone, and every part
// at zstd's worst.
uint64_t packedIndexMin(uint64_t rawBytes);
uint64_t packedIndexMax(uint64_t rawBytes);

// The directory in front of the parts, validated: where part i lies in the stored index
// ([offsets[i], offsets[i+1]), from the stored index's first byte) and its CRC-32.
struct IndexDirectory {
    uint64_t rawBytes = 0;
    std::vector<uint64_t> offsets;  // parts + 1
    std::vector<uint32_t> crcs;

    uint64_t parts() const { return crcs.size(); }
    // The part holding raw byte `at`, and the raw bytes part i unpacks to.
    uint64_t partOf(uint64_t at) const { return at / kIndexPartBytes; }
    size_t rawBytesOf(uint64_t i) const;
};

// The directory's size in bytes for a raw index of rawBytes (it is the stored index's start).
uint64_t indexDirectoryBytes(uint64_t rawBytes);

// Validates the directory (magic, sizes, its CRC, that its parts fill exactly storedBytes).
// `bytes` holds its indexDirectoryBytes(rawBytes) bytes. Throws IoError naming `path`.
IndexDirectory decodeIndexDirectory(const unsigned char* bytes, uint64_t storedBytes, uint64_t rawBytes,
                                    const std::string& path);

// Part i from its stored bytes into `raw` (its rawBytesOf(i) bytes): false when its CRC or its
// zstd data is wrong, or it unpacks to another size.
bool unpackIndexPart(const IndexDirectory& directory, uint64_t i, const unsigned char* stored, unsigned char* raw);

// Validates and decompresses a whole packed index held in memory (`n` bytes) into the raw index
// of rawBytes, in parallel. Throws IoError naming `path` and the part.
std::unique_ptr<unsigned char[]> unpackIndex(const unsigned char* stored, size_t n, uint64_t rawBytes,
                                             const std::string& path);

}  // namespace vdiso::store_format
