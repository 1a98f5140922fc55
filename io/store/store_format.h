// The brick store's on-disk types (its header, an index entry, the histogram, the codecs a
// brick may be stored with) and the byte layout of its header and index (docs/store-format.md),
// shared by the writer and the reader so the format is spelled out once. The types are the
// store's public vocabulary; the functions in store_format:: are internal to io/store.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "core/brick_layout.h"
#include "core/brick_source.h"
#include "core/huge_pages.h"
#include "core/volume.h"

namespace vdiso {

// 7: an index whose coarser levels lie in the indexed data too (an OME-Zarr's own scales): how
// many levels do, in the header, and their entries flagged external. Indexes of level 0 only
// are written as version 6.
// 6: an index of data kept elsewhere (vdiso index; io/store/external_level.h): where its record
// is, in the header, and level 0's entries flagged external. Stores without one are written as
// version 5, which older builds read.
// 5: the index stored in compressed parts (io/store/index_parts.h): several times smaller, which is
// what a remote store's open fetches. Version 4 stores open as before.
// 4: the volume's orientation (direction matrix and whether the input had one) in the header.
// 3: levels of detail (the header's level count; every level's bricks in the index). Version
// 2 and 3 stores open as before, without orientation; version 2 ones with level 0 only.
constexpr uint32_t kStoreFormatVersion = 7;
constexpr uint32_t kStoreHeaderBytes = 4096;
constexpr uint32_t kStoreAlignment = 4096;  // brick offsets: direct I/O needs 4 KiB alignment
constexpr int kHistogramBins = 256;

// How each brick is compressed (on its own). zstd stores about a fifth smaller; LZ4 decodes
// about five times faster (head volume, byte-shuffled: 1.99x at 1.2 GB/s against 1.61x at
// 5.6 GB/s), which matters when one core decodes for a view that another extracts.
enum class Compression : uint8_t { None = 0, Zstd = 1, Lz4 = 2 };
const char* compressionName(Compression c);
// The codec compressionName names ("zstd", "lz4", "none"); nullopt for anything else.
std::optional<Compression> parseCompression(std::string_view name);

enum class ChecksumAlgorithm : uint8_t { Crc32 = 1 };  // zlib's CRC-32 of the stored bytes

// A reversible transform applied to a brick's bytes before compression. Byte shuffle groups
// the k-th byte of every sample together (as Blosc and HDF5 do): the high bytes of smooth data
// become long runs, which zstd compresses about twice as well and 2.5x faster on CT-like u16.
enum class BrickFilter : uint8_t { None = 0, ByteShuffle = 1 };
const char* brickFilterName(BrickFilter f);

// One brick's entry in the index. No initializers, so that a store's array of them is made
// without writing it (BrickIndex): make one as BrickEntry{} (all zero) where it is not filled.
struct BrickEntry {
    uint64_t offset;       // byte offset of the stored brick in the file
    uint32_t storedBytes;  // bytes on disk (compressed, or raw when compression did not pay)
    uint32_t checksum;     // CRC-32 of the stored bytes
    float minValue;        // min and max over the samples of the brick's cells
    float maxValue;        //   (ghosts excluded: they only feed normals)
    bool compressed;
    bool external;         // a level of an index that lies in the indexed data (level 0, own scales): no bytes here
};

// A store's entries as decodeIndex makes them: sized without being written (resize leaves the
// entries unset; huge pages past 2 MB), so that the threads decoding them touch their pages
// first. A 2560^3 store's 18.7 MB of entries took 10-13 ms to zero on one thread before a 4 ms
// decode.
using BrickIndex = std::vector<BrickEntry, UninitializedAllocator<BrickEntry>>;

// A histogram of every sample in the volume, counted once each: bins of equal width over
// [valueMin, valueMax].
struct ValueHistogram {
    double lo = 0, hi = 0;
    std::array<uint64_t, kHistogramBins> counts{};

    // The value below which `fraction` of the samples lie, to within one bin.
    double quantile(double fraction) const;
    // Otsu's threshold: the bin edge that best splits the samples into two classes (the least
    // within-class variance), a default isovalue for scans (air against tissue).
    double otsuThreshold() const;
};

struct StoreHeader {
    uint32_t formatVersion = kStoreFormatVersion;  // as read; written is always the current
    VolumeInfo volume;
    int brickSize = 32;
    int levelCount = 1;  // levels of detail, level 0 included (core/brick_levels.h)
    Compression compression = Compression::Zstd;
    ChecksumAlgorithm checksum = ChecksumAlgorithm::Crc32;
    BrickFilter filter = BrickFilter::None;  // applied to compressed bricks only
    uint64_t indexOffset = 0, indexBytes = 0;
    double valueMin = 0, valueMax = 0;
    uint64_t storedBrickBytes = 0;  // sum of the bricks' stored bytes (padding excluded), all levels
    // An index's record of the data it indexes (version 6; 0, 0 for a store holding its data),
    // and how many of its levels, from level 0, lie there (1 in version 6; 0 for a store; from
    // version 7 more: an OME-Zarr's own scales).
    uint64_t externalOffset = 0, externalBytes = 0;
    int externalLevels = 0;
    // A copy of the packed index's directory (io/store/index_parts.h), kept in the header's
    // spare bytes when it fits (store_format::kDirectoryCopyMost): a remote open then reads
    // the header and goes straight to the index's parts, one round trip fewer. Empty when it
    // does not fit or the file has none. Not part of any format version: builds that do not
    // know it leave those bytes alone, and a copy that does not decode is ignored (the
    // directory is read where it lies).
    std::vector<unsigned char> indexDirectoryCopy;
};

}  // namespace vdiso

namespace vdiso::store_format {

static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "the store is little-endian on disk");

constexpr char kHeaderMagic[8] = {'V', 'D', 'I', 'S', 'O', 'B', 'S', 'T'};
constexpr char kIndexMagic[8] = {'V', 'D', 'I', 'S', 'O', 'I', 'D', 'X'};
constexpr size_t kEntryBytes = 32;

// The directory's copy in the header: its magic at kDirectoryCopyAt, then its length (uint32)
// and its bytes, at most kDirectoryCopyMost.
constexpr size_t kDirectoryCopyAt = 1024;
constexpr char kDirectoryCopyMagic[8] = {'V', 'D', 'I', 'S', 'O', 'D', 'I', 'R'};
constexpr size_t kDirectoryCopyMost = kStoreHeaderBytes - kDirectoryCopyAt - 12;

std::array<unsigned char, kStoreHeaderBytes> encodeHeader(const StoreHeader& header);

// Validates and decodes; throws IoError("<path>: ...") on anything wrong.
StoreHeader decodeHeader(const unsigned char* bytes, size_t n, const std::string& path);

// One entry as the raw index stores it, kEntryBytes bytes: offset u64, stored bytes u32,
// CRC-32 u32, min f32, max f32, flags u32 (1 compressed, 2 external), 4 zero bytes. decodeEntry
// gives the flags too, for the caller's checks (bits beyond 3 are not a valid entry).
void encodeEntry(const BrickEntry& entry, unsigned char* out);
BrickEntry decodeEntry(const unsigned char* in, uint32_t& flags);

// `subBlocks`: kSubBlocksPerBrick codes per entry. The index as the current version stores it
// (packed).
std::vector<unsigned char> encodeIndex(const std::vector<BrickEntry>& entries,
                                       const ValueHistogram& histogram,
                                       const std::vector<SubBlockCode>& subBlocks);

// Bricks of every level of detail the header describes.
int64_t totalBricks(const StoreHeader& header);
// The number of level `level`'s first brick: the bricks of the levels before it (0 for level 0).
int64_t firstBrickOfLevel(const StoreHeader& header, int level);

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
                 const BrickLayout& layout, const std::string& path, BrickIndex& entries,
                 ValueHistogram& histogram);

}  // namespace vdiso::store_format
