// Byte layout of the brick store's header and index (docs/store-format.md), shared by the
// writer and the reader so the format is spelled out once. Internal to io/.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "io/store/brick_store.h"

namespace vdiso::store_format {

static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "the store is little-endian on disk");

constexpr char kHeaderMagic[8] = {'V', 'D', 'I', 'S', 'O', 'B', 'S', 'T'};
constexpr char kIndexMagic[8] = {'V', 'D', 'I', 'S', 'O', 'I', 'D', 'X'};
constexpr size_t kEntryBytes = 32;

std::array<unsigned char, kStoreHeaderBytes> encodeHeader(const StoreHeader& header);

// Validates and decodes; throws IoError("<path>: ...") on anything wrong.
StoreHeader decodeHeader(const unsigned char* bytes, size_t n, const std::string& path);

// `subBlocks`: kSubBlocksPerBrick codes per entry. The index as the current version stores it
// (packed).
std::vector<unsigned char> encodeIndex(const std::vector<BrickEntry>& entries,
                                       const ValueHistogram& histogram,
                                       const std::vector<SubBlockCode>& subBlocks);

// Bricks of every level of detail the header describes.
int64_t totalBricks(const StoreHeader& header);

// Size in bytes of the raw index of a store with `brickCount` bricks (stored as such before
// version 5; packed in compressed parts from 5: io/store/index_parts.h).
uint64_t indexBytes(uint64_t brickCount);

// Where the sub-block codes start in the raw index: after the entries and the histogram.
// The codes are (lo, hi) byte pairs, kSubBlocksPerBrick per brick in brick order, then the CRC.
uint64_t subBlockCodesAt(uint64_t brickCount);

// Validates (magic, count, every entry's offset and size against the file, the histogram) and
// decodes the raw index's entries and histogram. `whole`: `bytes` holds the whole raw index
// (`n` bytes), stored as such before version 5, and its CRC is checked too; otherwise its first
// subBlockCodesAt(count) bytes (version 5, whose parts carry CRCs of their own). Throws IoError
// naming the file and, for a bad entry, the brick.
void decodeIndex(const unsigned char* bytes, size_t n, bool whole, const StoreHeader& header,
                 const BrickLayout& layout, const std::string& path, std::vector<BrickEntry>& entries,
                 ValueHistogram& histogram);

}  // namespace vdiso::store_format
