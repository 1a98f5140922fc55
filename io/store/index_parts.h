// The store's index as stored from format version 5 (docs/store-format.md, "Index"): the raw
// index cut into parts of kIndexPartBytes, each compressed on its own with zstd, behind a
// directory of their stored sizes and CRC-32s. The raw index is 160 bytes a brick (94 MB for a
// 2560^3 store with levels); stored, it is several times smaller, which is what crosses the
// network when the store is remote, and its parts decompress in parallel. Internal to io/.
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

// Validates the directory (magic, sizes, its CRC) and every part (its CRC, and that it
// decompresses to exactly its share), decompressing in parallel into the raw index of
// rawBytes. Throws IoError naming `path` and the part.
// (The raw bytes are not zeroed first: at 94 MB that was a pass of page faults for nothing.)
std::unique_ptr<unsigned char[]> unpackIndex(const unsigned char* stored, size_t n, uint64_t rawBytes,
                                             const std::string& path);

}  // namespace vdiso::store_format
