#include "io/store/brick_store.h"

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>
#include <new>
#include <optional>
#include <stdexcept>

#include <fcntl.h>
#include <unistd.h>

#include "io/crc32.h"
#include "io/error.h"
#include "io/readers/zarr_reader.h"
#include "io/remote/remote_file.h"
#include "io/store/brick_codec.h"
#include "io/store/external_bricks.h"
#include "io/store/lazy_index.h"
#include "io/store/store_format.h"
#include "core/trees/sub_blocks.h"

namespace vdiso {

namespace {

// A remote store's sub-block code parts read at once in the background (about 130 KB each, one
// a request): half the session's requests (16 of the default 32), leaving the rest to the bricks
// a view reads.
size_t codeRequestsAtOnce(const RemoteOptions& remote) { return size_t(std::clamp(remote.connections / 2, 1, 16)); }

// A local folder of Zarr data opens as the index beside it.
std::string storePathFor(const std::string& path) {
    if (isRemoteLocation(path) || !looksLikeZarr(path)) return path;
    const std::string index = defaultIndexPath(path);
    std::error_code ec;
    if (!std::filesystem::exists(index, ec))
        throwIoError(path, "is Zarr data without an index beside it (" + index + "): make one with 'vdiso index " +
                               path + "', or open an index made elsewhere");
    return index;
}

}  // namespace


BrickStoreReader::BrickStoreReader(std::string path, ReadMode mode)
    : BrickStoreReader(std::move(path), StoreOpenOptions{mode, {}}) {}

BrickStoreReader::BrickStoreReader(std::string path, const StoreOpenOptions& options)
    : mSource(openByteSource(storePathFor(path), options.mode, options.remote, kStoreHeaderBytes)),
      mPath(mSource->name()),
      mMode(options.mode) {
    mFileBytes = mSource->size();
    if (mFileBytes < kStoreHeaderBytes) {
        unsigned char magic[8] = {};
        if (mFileBytes >= 8) mSource->read(0, 8, magic, "header");
        if (mFileBytes >= 8 && std::equal(magic, magic + 8, store_format::kHeaderMagic))
            throwIoError(mPath, "is truncated inside its header (" + std::to_string(mFileBytes) + " bytes)");
        throwIoError(mPath, "not a vdiso brick store (wrong magic; convert volumes with "
                            "'vdiso convert' first)");
    }
    std::vector<unsigned char> headerBytes(kStoreHeaderBytes);
    mSource->read(0, headerBytes.size(), headerBytes.data(), "header");
    mHeader = store_format::decodeHeader(headerBytes.data(), headerBytes.size(), mPath);
    mLayout = BrickLayout(mHeader.volume.dims, mHeader.brickSize);
    mLevels = brickLevels(mHeader.volume, mHeader.brickSize, mHeader.levelCount);
    // Compared without a sum that could wrap: both numbers come from the file.
    if (mHeader.indexOffset < kStoreHeaderBytes || mHeader.indexBytes > mFileBytes ||
        mHeader.indexOffset > mFileBytes - mHeader.indexBytes)
        throwIoError(mPath, "index is missing or truncated: it needs " +
                                std::to_string(mHeader.indexBytes) + " bytes from byte offset " +
                                std::to_string(mHeader.indexOffset) + " but the file has " +
                                std::to_string(mFileBytes));
    const uint64_t count = uint64_t(store_format::totalBricks(mHeader));
    mCodesAt = store_format::subBlockCodesAt(count);
    const unsigned char* raw = nullptr;
    if (mHeader.formatVersion >= 5) {
        // The entries now; the sub-block codes as they are asked for (io/store/lazy_index.h): a
        // local 2560^3 store's views opened in two thirds of the time, unpacking 19 MB of
        // entries instead of 94 MB of index. Over the network the codes also come in the
        // background.
        // The header's copy of the directory saves a remote open a round trip; a local one reads
        // the directory where it lies (a pread), so that a damaged one is refused there too.
        const std::span<const unsigned char> directoryCopy =
            mSource->remote() ? std::span<const unsigned char>(mHeader.indexDirectoryCopy) : std::span<const unsigned char>();
        mLazyIndex = std::make_unique<LazyIndex>(*mSource, mHeader.indexOffset, mHeader.indexBytes,
                                                 store_format::indexBytes(count), directoryCopy);
        mLazyIndex->need(0, mCodesAt);
        raw = mLazyIndex->raw();
        store_format::decodeIndex(raw, size_t(mCodesAt), false, mHeader, mLayout, mPath, mIndex, mHistogram);
        if (mSource->remote()) mLazyIndex->readInBackground(mCodesAt, codeRequestsAtOnce(options.remote));
    } else {
        // The index as stored before version 5: raw, whole.
        const size_t indexBytes = size_t(mHeader.indexBytes);
        mRawIndex = std::make_unique_for_overwrite<unsigned char[]>(roomForRead(indexBytes));
        // Its CRC, last, is the check a remote read needs to keep it in a disk cache.
        mSource->read(mHeader.indexOffset, indexBytes, mRawIndex.get(), "index", [&](size_t) {
            uint32_t stored = 0;
            if (indexBytes < 4) return false;
            std::memcpy(&stored, mRawIndex.get() + indexBytes - 4, 4);
            return stored == crc32Of(mRawIndex.get(), indexBytes - 4);
        });
        raw = mRawIndex.get();
        store_format::decodeIndex(raw, indexBytes, true, mHeader, mLayout, mPath, mIndex, mHistogram);
    }
    // The codes are (lo, hi) byte pairs, as SubBlockCode lays them out: used where they lie
    // (a 2560^3 store's 75 MB are not copied).
    static_assert(sizeof(SubBlockCode) == 2 && alignof(SubBlockCode) == 1);
    mSubBlocks = {reinterpret_cast<const SubBlockCode*>(raw + mCodesAt), size_t(count) * kSubBlocksPerBrick};
    if (mHeader.externalBytes) {
        const size_t recordBytes = size_t(mHeader.externalBytes);
        std::vector<unsigned char> record(roomForRead(recordBytes));
        // Its decoding is its check (a disk cache keeps it only when that passes); the last
        // decoding is of what the read left (RangeCheck), and a read without a disk cache, which
        // asks no check, decodes after it, with the error naming what is wrong.
        std::optional<std::vector<ExternalLevel>> records;
        mSource->read(mHeader.externalOffset, recordBytes, record.data(), "record of indexed data", [&](size_t) {
            try {
                records = decodeExternalLevels(record.data(), recordBytes, mPath);
            } catch (const IoError&) {
                records.reset();
            }
            return records.has_value();
        });
        if (!records) records = decodeExternalLevels(record.data(), recordBytes, mPath);
        mExternal = std::make_unique<ExternalBricks>(mPath, mHeader, std::move(*records), options.remote,
                                                     options.chunkCacheBytes);
    }
}

bool BrickStoreReader::readsRemotely() const { return remote() || (mExternal && mExternal->isRemote()); }

std::span<const SubBlockCode> BrickStoreReader::subBlockCodes() const {
    if (mLazyIndex) mLazyIndex->need(mCodesAt, mLazyIndex->rawBytes());
    return mSubBlocks;
}

std::span<const SubBlockCode> BrickStoreReader::subBlockCodesOf(int64_t brick) const {
    const size_t first = size_t(brick) * kSubBlocksPerBrick;
    if (mLazyIndex) mLazyIndex->need(mCodesAt + 2 * first, mCodesAt + 2 * (first + kSubBlocksPerBrick));
    return mSubBlocks.subspan(first, kSubBlocksPerBrick);
}

BrickStoreReader::~BrickStoreReader() = default;

namespace {

// A buffer per thread for stored bricks, 4 KiB-aligned so that O_DIRECT reads land in it.
struct AlignedBuffer {
    unsigned char* data = nullptr;
    size_t size = 0;
    ~AlignedBuffer() { std::free(data); }
    unsigned char* reserve(size_t n) {
        if (n > size) {
            std::free(data);
            data = nullptr;
            size = 0;
            // aligned_alloc wants a multiple of the alignment.
            const size_t bytes = (n + kStoreAlignment - 1) / kStoreAlignment * kStoreAlignment;
            data = static_cast<unsigned char*>(std::aligned_alloc(kStoreAlignment, bytes));
            if (!data) throw std::bad_alloc();
            size = bytes;
        }
        return data;
    }
};

}  // namespace

void BrickStoreReader::failBrick(int64_t id, const std::string& what) const {
    const int level = levelOfBrick(mLevels, id);
    const Dims3 c = mLevels[size_t(level)].layout.brickCoord(id - mLevels[size_t(level)].firstBrick);
    throwIoError(mPath, "brick " + std::to_string(id) + " (" + std::to_string(c[0]) + "," +
                            std::to_string(c[1]) + "," + std::to_string(c[2]) +
                            (level > 0 ? " of level " + std::to_string(level) : std::string()) +
                            ") at byte offset " + std::to_string(mIndex[size_t(id)].offset) +
                            ": " + what);
}

std::span<const unsigned char> BrickStoreReader::readStoredBrick(int64_t id) const {
    return readStoredBricks(std::span<const int64_t>(&id, 1))[0];
}

bool BrickStoreReader::readsTogether(int64_t a, int64_t b) const {
    const int64_t n = int64_t(mIndex.size());
    if (a < 0 || b < 0 || a >= n || b >= n || a == b) return false;
    const BrickEntry* x = &mIndex[size_t(a)];
    const BrickEntry* y = &mIndex[size_t(b)];
    if (x->external || y->external) return false;
    if (y->offset < x->offset) std::swap(x, y);
    const uint64_t end = x->offset + x->storedBytes;
    return y->offset >= end && y->offset - end < kStoreAlignment;  // only alignment padding between
}

uint64_t BrickStoreReader::coveringRange(std::span<const int64_t> ids, size_t& bytes) const {
    // In file order, each stored right after the one before.
    const size_t count = ids.size();
    std::vector<size_t> order(count);
    for (size_t k = 0; k < count; ++k) order[k] = k;
    std::sort(order.begin(), order.end(),
              [&](size_t i, size_t j) { return mIndex[size_t(ids[i])].offset < mIndex[size_t(ids[j])].offset; });
    for (size_t k = 0; k + 1 < count; ++k)
        if (!readsTogether(ids[order[k]], ids[order[k + 1]]))
            throw std::logic_error("readStoredBricks: bricks not stored one after another");
    const BrickEntry& firstEntry = mIndex[size_t(ids[order.front()])];
    const BrickEntry& lastEntry = mIndex[size_t(ids[order.back()])];
    bytes = size_t(lastEntry.offset - firstEntry.offset) + lastEntry.storedBytes;
    return firstEntry.offset;
}

std::vector<ByteRange> BrickStoreReader::piecesOf(std::span<const int64_t> ids, uint64_t first,
                                                  unsigned char* dst) const {
    std::vector<ByteRange> pieces;  // in the order of ids
    pieces.reserve(ids.size());
    for (const int64_t id : ids) {
        const BrickEntry& e = mIndex[size_t(id)];
        pieces.push_back({e.offset, e.storedBytes, dst + (e.offset - first)});
    }
    return pieces;
}

std::vector<std::span<const unsigned char>> BrickStoreReader::checkedPieces(std::span<const int64_t> ids,
                                                                            std::span<const ByteRange> pieces,
                                                                            std::span<const int8_t> intact) const {
    std::vector<std::span<const unsigned char>> stored;
    stored.reserve(ids.size());
    for (size_t k = 0; k < ids.size(); ++k) {
        stored.emplace_back(static_cast<const unsigned char*>(pieces[k].dst), pieces[k].bytes);
        const bool good = intact[k] < 0 ? crc32Of(pieces[k].dst, pieces[k].bytes) == mIndex[size_t(ids[k])].checksum
                                        : intact[k] == 1;
        if (!good) failBrick(ids[k], "checksum mismatch (the brick is corrupt)");
    }
    return stored;
}

namespace {

void checkBrickIds(std::span<const int64_t> ids, size_t bricks, const std::string& path) {
    for (const int64_t id : ids)
        if (id < 0 || id >= int64_t(bricks))
            throwIoError(path, "no brick " + std::to_string(id) + " (the store has " + std::to_string(bricks) + ")");
    if (ids.empty()) throw std::logic_error("readStoredBricks: no bricks");
}

}  // namespace

std::vector<std::span<const unsigned char>> BrickStoreReader::readStoredBricks(std::span<const int64_t> ids) const {
    checkBrickIds(ids, mIndex.size(), mPath);
    const size_t count = ids.size();
    if (mIndex[size_t(ids[0])].external) {  // its samples as they are, from the indexed array's chunks
        if (count > 1) throw std::logic_error("readStoredBricks: an indexed array's bricks are read one at a time");
        thread_local AlignedBuffer buffer;
        unsigned char* dst = buffer.reserve(brickBytes());
        mExternal->assemble(ids[0], dst);
        return {std::span<const unsigned char>(dst, brickBytes())};
    }
    size_t bytes = 0;
    const uint64_t first = coveringRange(ids, bytes);
    thread_local AlignedBuffer buffer;
    unsigned char* dst = buffer.reserve(bytes);
    const std::vector<ByteRange> pieces = piecesOf(ids, first, dst);
    // A remote source's disk cache keeps a brick only once its checksum passes; what its last
    // check of a piece found (the bytes as read) is not computed again.
    std::vector<int8_t> intact(count, -1);  // -1: not checked by the source
    auto check = [&](size_t k) {
        intact[k] = crc32Of(pieces[k].dst, pieces[k].bytes) == mIndex[size_t(ids[k])].checksum;
        return intact[k] == 1;
    };
    mSource->readCovering(first, bytes, dst, pieces, "brick data", check);
    return checkedPieces(ids, pieces, intact);
}

struct BrickStoreReader::StoredRead {
    std::vector<int64_t> ids;
    AlignedBuffer buffer;
    std::vector<ByteRange> pieces;
    std::vector<int8_t> intact;  // as readStoredBricks keeps it
    std::exception_ptr error;
};

bool BrickStoreReader::readsInBackground() const { return !mExternal && mSource->readsInBackground(); }

std::shared_ptr<BrickStoreReader::StoredRead> BrickStoreReader::startStoredBricks(std::span<const int64_t> ids,
                                                                                   std::function<void()> arrived,
                                                                                   const std::atomic<bool>* cancel) const {
    // Every failure goes through the read (to finishStoredBricks) and `arrived`, called once and
    // outside the try: the caller may have claimed what the read is for.
    auto read = std::make_shared<StoredRead>();
    StoredRead* r = read.get();
    try {
        checkBrickIds(ids, mIndex.size(), mPath);
        r->ids.assign(ids.begin(), ids.end());
        if (mIndex[size_t(ids[0])].external) throw std::logic_error("startStoredBricks: an indexed array's brick");
        size_t bytes = 0;
        const uint64_t first = coveringRange(ids, bytes);
        unsigned char* dst = r->buffer.reserve(bytes);
        r->pieces = piecesOf(ids, first, dst);
        r->intact.assign(ids.size(), -1);
        auto check = [this, r](size_t k) {
            r->intact[k] = crc32Of(r->pieces[k].dst, r->pieces[k].bytes) == mIndex[size_t(r->ids[k])].checksum;
            return r->intact[k] == 1;
        };
        mSource->readCoveringAsync(first, bytes, dst, r->pieces, "brick data", check, cancel,
                                   [r, arrived](std::exception_ptr e) {
                                       r->error = e;
                                       arrived();
                                   });
        return read;
    } catch (...) {
        r->error = std::current_exception();
    }
    arrived();
    return read;
}

std::vector<std::span<const unsigned char>> BrickStoreReader::finishStoredBricks(StoredRead& read) const {
    if (read.error) std::rethrow_exception(read.error);
    return checkedPieces(read.ids, read.pieces, read.intact);
}

void BrickStoreReader::decodeBrick(int64_t id, std::span<const unsigned char> stored,
                                   void* dst) const {
    const std::string problem = decodeBrickBytes(stored, mIndex[size_t(id)].compressed, scalarSize(volume().type),
                                                 mHeader.compression, mHeader.filter, dst, brickBytes());
    if (!problem.empty()) failBrick(id, problem);
}

void BrickStoreReader::readBrick(int64_t id, void* dst) const {
    decodeBrick(id, readStoredBrick(id), dst);
}

}  // namespace vdiso
