// The brick store: one self-describing, versioned file per volume (docs/store-format.md).
//
//   [header: 4096 bytes] [brick 0] [brick 1] ... (each at a 4096-byte aligned offset) [index]
//
// The header holds dimensions, spacing, origin, orientation, scalar type, brick size, ghost layout,
// compression, checksum algorithm and where the index is. The index holds, per brick, its file
// offset, stored size, checksum and the min and max of the samples its cells touch, then a
// histogram of the whole volume. Both are written last: a file whose header or index is
// incomplete is refused at open.
//
// BrickStoreReader opens a store by reading only the header and the index, then returns any
// brick's (B+3)^3 samples by brick id. It is safe to read bricks from several threads at once.
#pragma once

#include <array>
#include <memory>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "core/brick_layout.h"
#include "core/brick_levels.h"
#include "core/brick_source.h"
#include "core/volume.h"
#include "io/store/byte_source.h"

namespace vdiso {

class LazyIndex;

// 5: the index stored in compressed parts (io/store/index_parts.h): several times smaller, which is
// what a remote store's open fetches. Version 4 stores open as before.
// 4: the volume's orientation (direction matrix and whether the input had one) in the header.
// 3: levels of detail (the header's level count; every level's bricks in the index). Version
// 2 and 3 stores open as before, without orientation; version 2 ones with level 0 only.
constexpr uint32_t kStoreFormatVersion = 5;
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

// One brick's entry in the index.
struct BrickEntry {
    uint64_t offset = 0;       // byte offset of the stored brick in the file
    uint32_t storedBytes = 0;  // bytes on disk (compressed, or raw when compression did not pay)
    uint32_t checksum = 0;     // CRC-32 of the stored bytes
    float minValue = 0;        // min and max over the samples of the brick's cells
    float maxValue = 0;        //   (ghosts excluded: they only feed normals)
    bool compressed = false;
};

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
};

// How a store is opened: local files by ReadMode (io/store/byte_source.h), remote ones by their URL
// and RemoteOptions.
struct StoreOpenOptions {
    ReadMode mode = ReadMode::Buffered;
    RemoteOptions remote;
};

class BrickStoreReader {
public:
    // Reads and validates header and index, from a file or a URL (http://, https://, s3://).
    // Throws IoError naming the file and the problem (wrong magic, newer version, bad header
    // checksum, truncated or corrupt index, a server's refusal, ...).
    explicit BrickStoreReader(std::string path, ReadMode mode = ReadMode::Buffered);
    BrickStoreReader(std::string path, const StoreOpenOptions& options);
    ~BrickStoreReader();
    BrickStoreReader(const BrickStoreReader&) = delete;
    BrickStoreReader& operator=(const BrickStoreReader&) = delete;

    // The path, or the URL without its query (which may hold a signature).
    const std::string& path() const { return mPath; }
    const StoreHeader& header() const { return mHeader; }
    const VolumeInfo& volume() const { return mHeader.volume; }
    // Level 0's bricks.
    const BrickLayout& layout() const { return mLayout; }
    // Every level, level 0 first; brick ids run through them (core/brick_levels.h).
    const std::vector<BrickLevel>& levels() const { return mLevels; }
    // Every level's bricks, by brick id.
    const std::vector<BrickEntry>& index() const { return mIndex; }
    const ValueHistogram& histogram() const { return mHistogram; }
    // The sub-block codes (core/trees/sub_blocks.h): kSubBlocksPerBrick per brick, in brick order.
    // A remote store fetches them after its open, in the background, coarse levels first
    // (io/store/lazy_index.h): these may wait for them, and throw IoError if they cannot be read.
    // Every brick's:
    std::span<const SubBlockCode> subBlockCodes() const;
    // Brick `id`'s kSubBlocksPerBrick (waiting only for the part holding them).
    std::span<const SubBlockCode> subBlockCodesOf(int64_t id) const;
    uint64_t fileBytes() const { return mFileBytes; }
    ReadMode readMode() const { return mMode; }
    // "buffered", "direct" (O_DIRECT) or "fadvise" (pages dropped after each read); "http",
    // "https" or "s3" for a remote store.
    const char* readMethod() const { return mSource->method(); }
    // The remote object a URL opened, or null for a local file.
    const RemoteFile* remote() const { return mSource->remote(); }
    // Bytes one decoded brick takes: (B+3)^3 samples.
    size_t brickBytes() const { return size_t(mLayout.samplesPerBrick()) * scalarSize(volume().type); }

    // Reads brick `id` into dst (brickBytes() bytes), checking its checksum and size. Throws
    // IoError naming the file, the brick and its byte offset on a short read, a checksum
    // mismatch or a decompression failure.
    void readBrick(int64_t id, void* dst) const;

    // The two halves of readBrick, for a cache that times them apart: the stored bytes
    // (checksum verified), then decoding them into dst. The stored bytes live in a buffer of
    // the calling thread, valid until its next readStoredBrick: with O_DIRECT the read lands
    // in it, aligned, and is decoded from there without a copy.
    std::span<const unsigned char> readStoredBrick(int64_t id) const;
    // Whether brick id + 1 is stored right after brick id (only alignment padding between), so
    // that readStoredBricks reads both in one request: x-neighbours in a row of bricks are.
    bool nextInFile(int64_t id) const;
    // Bricks first .. first + count - 1, each stored right after the one before (nextInFile),
    // read in one request: the stored bytes of each (checksums verified), in the calling
    // thread's buffer as readStoredBrick says.
    std::vector<std::span<const unsigned char>> readStoredBricks(int64_t first, int count) const;
    void decodeBrick(int64_t id, std::span<const unsigned char> stored, void* dst) const;

private:
    [[noreturn]] void failBrick(int64_t id, const std::string& what) const;

    std::unique_ptr<ByteSource> mSource;
    std::string mPath;
    ReadMode mMode = ReadMode::Buffered;
    uint64_t mFileBytes = 0;
    StoreHeader mHeader;
    BrickLayout mLayout;
    std::vector<BrickLevel> mLevels;
    std::vector<BrickEntry> mIndex;
    ValueHistogram mHistogram;
    // The raw index, which mSubBlocks points into: as read (before version 5), or unpacked by parts.
    std::unique_ptr<unsigned char[]> mRawIndex;
    std::unique_ptr<LazyIndex> mLazyIndex;
    uint64_t mCodesAt = 0;  // where the codes start in the raw index
    std::span<const SubBlockCode> mSubBlocks;
};

}  // namespace vdiso
