#include "io/brick_store.h"

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <new>

#include <fcntl.h>
#include <unistd.h>
#include <lz4.h>
#include <zstd.h>

#include "io/byte_shuffle.h"
#include "io/error.h"
#include "io/store_format.h"

namespace vdiso {

const char* compressionName(Compression c) {
    return c == Compression::Zstd ? "zstd" : c == Compression::Lz4 ? "lz4" : "none";
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

namespace {

void preadExact(int fd, void* dst, size_t n, uint64_t offset, const std::string& path,
                const char* what) {
    auto* p = static_cast<char*>(dst);
    size_t done = 0;
    while (done < n) {
        ssize_t r = ::pread(fd, p + done, n - done, off_t(offset + done));
        if (r < 0) {
            if (errno == EINTR) continue;
            throwSystemError(path, std::string("cannot read ") + what + " at byte offset " +
                                       std::to_string(offset + done), errno);
        }
        if (r == 0)
            throwIoError(path, std::string("ends inside the ") + what + " (byte offset " +
                                   std::to_string(offset + done) + "): the file is truncated");
        done += size_t(r);
    }
}

}  // namespace

BrickStoreReader::BrickStoreReader(std::string path, ReadMode mode)
    : mPath(std::move(path)), mMode(mode) {
    mFd = ::open(mPath.c_str(), O_RDONLY | O_CLOEXEC);
    if (mFd < 0) throwSystemError(mPath, "cannot open", errno);
    try {
        const off_t end = ::lseek(mFd, 0, SEEK_END);
        if (end < 0) throwSystemError(mPath, "cannot seek", errno);
        mFileBytes = uint64_t(end);
        if (mFileBytes < kStoreHeaderBytes) {
            unsigned char magic[8] = {};
            ssize_t got = ::pread(mFd, magic, 8, 0);
            if (got == 8 && std::equal(magic, magic + 8, store_format::kHeaderMagic))
                throwIoError(mPath, "is truncated inside its header (" +
                                        std::to_string(mFileBytes) + " bytes)");
            throwIoError(mPath, "not a vdiso brick store (wrong magic; convert volumes with "
                                "'vdiso convert' first)");
        }
        std::vector<unsigned char> headerBytes(kStoreHeaderBytes);
        preadExact(mFd, headerBytes.data(), headerBytes.size(), 0, mPath, "header");
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
        std::vector<unsigned char> indexBytes(mHeader.indexBytes);
        preadExact(mFd, indexBytes.data(), indexBytes.size(), mHeader.indexOffset, mPath, "index");
        store_format::decodeIndex(indexBytes.data(), indexBytes.size(), mHeader, mLayout, mPath,
                                  mIndex, mHistogram, mSubBlocks);
        if (mMode == ReadMode::Cold) {
            // Start cold: whatever of the file the page cache holds (from conversion, an
            // earlier run, or the header and index just read) is dropped.
            ::posix_fadvise(mFd, 0, 0, POSIX_FADV_DONTNEED);
            mDirectFd = ::open(mPath.c_str(), O_RDONLY | O_CLOEXEC | O_DIRECT);
        }
    } catch (...) {
        ::close(mFd);
        throw;
    }
}

BrickStoreReader::~BrickStoreReader() {
    ::close(mFd);
    if (mDirectFd >= 0) ::close(mDirectFd);
}

const char* BrickStoreReader::readMethod() const {
    if (mMode == ReadMode::Buffered) return "buffered";
    return mDirectFd >= 0 ? "direct" : "fadvise";
}

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
    if (mDirectFd >= 0) {
        // Whole aligned blocks; the padding after a brick (or the index) fills the last one.
        const size_t blocks = (size_t(e.storedBytes) + kStoreAlignment - 1) / kStoreAlignment;
        const size_t length = std::min<uint64_t>(blocks * kStoreAlignment, mFileBytes - e.offset);
        const size_t aligned = (length + kStoreAlignment - 1) / kStoreAlignment * kStoreAlignment;
        unsigned char* block = buffer.reserve(aligned);
        size_t done = 0;
        while (done < e.storedBytes) {
            const ssize_t r = ::pread(mDirectFd, block + done, aligned - done, off_t(e.offset + done));
            if (r < 0 && errno == EINTR) continue;
            if (r < 0) throwSystemError(mPath, "cannot read brick " + std::to_string(id), errno);
            if (r == 0) failBrick(id, "the file ends inside the brick: it is truncated");
            done += size_t(r);
        }
    } else {
        preadExact(mFd, buffer.reserve(e.storedBytes), e.storedBytes, e.offset, mPath, "brick data");
        if (mMode == ReadMode::Cold)
            ::posix_fadvise(mFd, off_t(e.offset), off_t(e.storedBytes), POSIX_FADV_DONTNEED);
    }
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
