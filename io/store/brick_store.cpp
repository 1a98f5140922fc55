#include "io/store/brick_store.h"

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <new>

#include <fcntl.h>
#include <unistd.h>
#include <lz4.h>
#include <zstd.h>

#include "io/store/byte_shuffle.h"
#include "io/error.h"
#include "io/store/store_format.h"

namespace vdiso {

const char* compressionName(Compression c) {
    return c == Compression::Zstd ? "zstd" : c == Compression::Lz4 ? "lz4" : "none";
}

std::optional<Compression> parseCompression(std::string_view name) {
    for (Compression c : {Compression::Zstd, Compression::Lz4, Compression::None})
        if (name == compressionName(c)) return c;
    return std::nullopt;
}

const char* brickFilterName(BrickFilter f) {
    return f == BrickFilter::ByteShuffle ? "byte shuffle" : "none";
}

double ValueHistogram::otsuThreshold() const {
    double total = 0, sum = 0;
    for (int b = 0; b < kHistogramBins; ++b) {
        total += double(counts[b]);
        sum += double(counts[b]) * (b + 0.5);
    }
    double below = 0, sumBelow = 0, best = -1;
    int bestEdge = kHistogramBins / 2;
    for (int edge = 1; edge < kHistogramBins; ++edge) {  // classes [0, edge) and [edge, end)
        below += double(counts[edge - 1]);
        sumBelow += double(counts[edge - 1]) * (edge - 0.5);
        const double above = total - below;
        if (below == 0 || above == 0) continue;
        const double meanBelow = sumBelow / below, meanAbove = (sum - sumBelow) / above;
        const double between = below * above * (meanBelow - meanAbove) * (meanBelow - meanAbove);
        if (between > best) {
            best = between;
            bestEdge = edge;
        }
    }
    return lo + (hi - lo) * bestEdge / kHistogramBins;
}

double ValueHistogram::quantile(double fraction) const {
    uint64_t total = 0;
    for (uint64_t c : counts) total += c;
    if (total == 0) return lo;
    const double target = fraction * double(total);
    const double binWidth = (hi - lo) / kHistogramBins;
    uint64_t seen = 0;
    for (int b = 0; b < kHistogramBins; ++b) {
        if (double(seen + counts[b]) >= target && counts[b] > 0) {
            // Interpolate inside the bin: samples are assumed spread evenly across it.
            const double within = (target - double(seen)) / double(counts[b]);
            return lo + (b + std::clamp(within, 0.0, 1.0)) * binWidth;
        }
        seen += counts[b];
    }
    return hi;
}

BrickStoreReader::BrickStoreReader(std::string path, ReadMode mode)
    : BrickStoreReader(std::move(path), StoreOpenOptions{mode, {}}) {}

BrickStoreReader::BrickStoreReader(std::string path, const StoreOpenOptions& options)
    : mSource(openByteSource(path, options.mode, options.remote, kStoreHeaderBytes)),
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
    // In pieces, which a remote source fetches at once.
    const size_t indexBytes = size_t(mHeader.indexBytes);
    auto stored = std::make_unique_for_overwrite<unsigned char[]>(indexBytes);
    std::vector<ByteRange> pieces;
    constexpr size_t kIndexPiece = size_t(1) << 20;
    for (size_t at = 0; at < indexBytes; at += kIndexPiece)
        pieces.push_back({mHeader.indexOffset + at, std::min(kIndexPiece, indexBytes - at), stored.get() + at});
    mSource->readMany(pieces, "index");
    mRawIndex = store_format::decodeIndex(std::move(stored), indexBytes, mHeader, mLayout, mPath, mIndex,
                                          mHistogram, mSubBlocks);
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
    if (id < 0 || id >= int64_t(mIndex.size()))
        throwIoError(mPath, "no brick " + std::to_string(id) + " (the store has " +
                                std::to_string(mIndex.size()) + ")");
    const BrickEntry& e = mIndex[size_t(id)];
    thread_local AlignedBuffer buffer;
    mSource->read(e.offset, e.storedBytes, buffer.reserve(e.storedBytes), "brick data");
    const std::span<const unsigned char> bytes(buffer.data, e.storedBytes);
    if (store_format::crc32Of(bytes.data(), bytes.size()) != e.checksum)
        failBrick(id, "checksum mismatch (the brick is corrupt)");
    return bytes;
}

void BrickStoreReader::decodeBrick(int64_t id, std::span<const unsigned char> stored,
                                   void* dst) const {
    const BrickEntry& e = mIndex[size_t(id)];
    const size_t raw = brickBytes();
    if (!e.compressed) {
        if (stored.size() != raw) failBrick(id, "stored size does not match the brick size");
        std::memcpy(dst, stored.data(), raw);
        return;
    }
    const size_t sampleBytes = scalarSize(volume().type);
    const bool shuffled = mHeader.filter == BrickFilter::ByteShuffle && sampleBytes > 1;
    thread_local std::vector<unsigned char> planes;
    if (shuffled) planes.resize(raw);
    unsigned char* out = shuffled ? planes.data() : static_cast<unsigned char*>(dst);
    if (mHeader.compression == Compression::Lz4) {
        const int got = LZ4_decompress_safe(reinterpret_cast<const char*>(stored.data()),
                                            reinterpret_cast<char*>(out), int(stored.size()), int(raw));
        if (got < 0) failBrick(id, "cannot decompress: malformed LZ4 data");
        if (size_t(got) != raw) failBrick(id, "decompressed to the wrong size");
    } else {
        const size_t got = ZSTD_decompress(out, raw, stored.data(), stored.size());
        if (ZSTD_isError(got)) failBrick(id, std::string("cannot decompress: ") + ZSTD_getErrorName(got));
        if (got != raw) failBrick(id, "decompressed to the wrong size");
    }
    if (shuffled)
        unshuffleBytes(planes.data(), raw / sampleBytes, sampleBytes, static_cast<unsigned char*>(dst));
}

void BrickStoreReader::readBrick(int64_t id, void* dst) const {
    decodeBrick(id, readStoredBrick(id), dst);
}

}  // namespace vdiso
