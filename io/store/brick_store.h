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
// BrickStoreReader opens a store by reading only the header and the index's entries (from
// format 5 the sub-block codes, three fifths of the index, are read by parts as they are asked
// for), then returns any brick's (B+3)^3 samples by brick id. It is safe to read bricks from
// several threads at once.
//
// An index (vdiso index: a store whose level 0 stays in the Zarr array it indexes) opens the
// same way, by its path or by the indexed folder's (whose index is beside it,
// io/store/external_level.h defaultIndexPath); level 0's bricks are then assembled from the
// array's chunks (io/store/external_bricks.h), and so are an OME-Zarr's own scales' where the
// index takes its coarser levels from them; other coarser levels are read from the index file.
#pragma once

#include <array>
#include <atomic>
#include <functional>
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
#include "io/store/store_format.h"

namespace vdiso {

class ExternalBricks;
class LazyIndex;

// How a store is opened: local files by ReadMode (io/store/byte_source.h), remote ones by their URL
// and RemoteOptions.
struct StoreOpenOptions {
    ReadMode mode = ReadMode::Buffered;
    RemoteOptions remote;
    // An index's (vdiso index) decoded chunks of the indexed array held at most.
    size_t chunkCacheBytes = size_t(512) << 20;
};

class BrickStoreReader {
public:
    // Reads and validates header and index, from a file or a URL (http://, https://, s3://).
    // Throws IoError naming the file and the problem (wrong magic, newer version, bad header
    // checksum, truncated or corrupt index, a server's refusal, an index of data that is not
    // there or not as indexed, ...). A local folder holding Zarr opens the index beside it.
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
    std::span<const BrickEntry> index() const { return mIndex; }
    const ValueHistogram& histogram() const { return mHistogram; }
    // The sub-block codes (core/trees/sub_blocks.h): kSubBlocksPerBrick per brick, in brick order.
    // From format 5 they are read and checked by parts as they are asked for (io/store/lazy_index.h;
    // a remote store also fetches them after its open, in the background, coarse levels first):
    // these may read or wait for them, and throw IoError if a part cannot be read or is corrupt.
    // Every brick's (every part read and checked):
    std::span<const SubBlockCode> subBlockCodes() const;
    // Brick `id`'s kSubBlocksPerBrick (waiting only for the part holding them).
    std::span<const SubBlockCode> subBlockCodesOf(int64_t id) const;
    uint64_t fileBytes() const { return mFileBytes; }
    ReadMode readMode() const { return mMode; }
    // "buffered", "direct" (O_DIRECT) or "fadvise" (pages dropped after each read); "http",
    // "https" or "s3" for a remote store.
    const char* readMethod() const { return mSource->method(); }
    // Bytes read from the store's file or fetched from its URL since the open (ByteSource::bytesRead).
    uint64_t sourceBytesRead() const { return mSource->bytesRead(); }
    // The remote object a URL opened, or null for a local file.
    const RemoteFile* remote() const { return mSource->remote(); }
    // The indexed array of an index (vdiso index), or null for a store holding its data.
    const ExternalBricks* external() const { return mExternal.get(); }
    // Whether bricks come over the network (the store, or the array an index indexes, at a
    // URL): read-ahead is set for round trips then (app/extract_settings.h adaptToRemoteStore).
    bool readsRemotely() const;
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
    // Whether bricks a and b are read in one request (readStoredBricks): both stored in this
    // file, one right after the other (only alignment padding between), in either order:
    // x-neighbours in a row of bricks are. (Reading across other bricks' bytes too was measured
    // and cost more than the requests it saved: bench/log.md, "Remote views at the speed of the
    // link".)
    bool readsTogether(int64_t a, int64_t b) const;
    // Bricks `ids` (distinct), read in one request covering them all: the stored bytes of each,
    // in the order of `ids` (checksums verified), in the calling thread's buffer as
    // readStoredBrick says. In file order each must follow the one before (readsTogether chains
    // them); std::logic_error otherwise.
    std::vector<std::span<const unsigned char>> readStoredBricks(std::span<const int64_t> ids) const;
    // readStoredBricks in two halves, for a caller that keeps many requests in flight without a
    // thread waiting on each (readsInBackground: a store at a URL). startStoredBricks sends the
    // request and returns; `arrived` is called once, on any thread (quick: it may note and wake,
    // not read or decode), when finishStoredBricks will not wait, and the read must live until
    // then. finishStoredBricks gives the stored bytes, in the read's own buffer (valid while it
    // lives), or throws what readStoredBricks throws. Once `cancel` (if given) is set, the request
    // ends and finishStoredBricks throws. Not for an indexed array's bricks (readsInBackground
    // says false for an index).
    struct StoredRead;
    bool readsInBackground() const;
    std::shared_ptr<StoredRead> startStoredBricks(std::span<const int64_t> ids, std::function<void()> arrived,
                                                  const std::atomic<bool>* cancel) const;
    std::vector<std::span<const unsigned char>> finishStoredBricks(StoredRead& read) const;
    void decodeBrick(int64_t id, std::span<const unsigned char> stored, void* dst) const;

private:
    [[noreturn]] void failBrick(int64_t id, const std::string& what) const;
    // Where bricks `ids` (a chain readStoredBricks takes) lie: the range covering them, and each
    // one's piece of it at dst + (its offset - the range's).
    uint64_t coveringRange(std::span<const int64_t> ids, size_t& bytes) const;
    std::vector<ByteRange> piecesOf(std::span<const int64_t> ids, uint64_t first, unsigned char* dst) const;
    // The stored bytes of pieces read, each checked unless intact[k] says (1 good, 0 bad, -1 not
    // checked yet); throws naming the brick whose checksum fails.
    std::vector<std::span<const unsigned char>> checkedPieces(std::span<const int64_t> ids,
                                                               std::span<const ByteRange> pieces,
                                                               std::span<const int8_t> intact) const;

    std::unique_ptr<ByteSource> mSource;
    std::string mPath;
    ReadMode mMode = ReadMode::Buffered;
    uint64_t mFileBytes = 0;
    StoreHeader mHeader;
    BrickLayout mLayout;
    std::vector<BrickLevel> mLevels;
    BrickIndex mIndex;
    ValueHistogram mHistogram;
    // The raw index, which mSubBlocks points into: as read before version 5, else mLazyIndex's,
    // unpacked by parts as they are asked for.
    std::unique_ptr<unsigned char[]> mRawIndex;
    std::unique_ptr<LazyIndex> mLazyIndex;
    std::unique_ptr<ExternalBricks> mExternal;
    uint64_t mCodesAt = 0;  // where the codes start in the raw index
    std::span<const SubBlockCode> mSubBlocks;
};

}  // namespace vdiso
