#include "io/store/store_format.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <memory>

#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "core/orientation.h"
#include "core/trees/sub_blocks.h"
#include "io/crc32.h"
#include "io/error.h"
#include "io/store/brick_codec.h"
#include "io/store/index_parts.h"

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

}  // namespace vdiso

namespace vdiso::store_format {

namespace {

constexpr size_t kHeaderChecksumAt = 160;  // the header's CRC covers bytes [0, 160)
// Version 4's orientation follows the first checksum, which keeps its place and span so that
// the layout up to it is every version's; a second checksum covers the whole header up to it.
constexpr size_t kOrientationAt = 164;
constexpr size_t kWholeHeaderChecksumAt = 240;  // covers bytes [0, 240)
// Version 6's record of indexed data (offset, size) after the second checksum, and a third
// covering the header up to it.
constexpr size_t kExternalAt = 244;
constexpr size_t kExternalChecksumAt = 260;  // covers bytes [0, 260)
// Version 7's count of levels lying in the indexed data, and a fourth checksum.
constexpr size_t kExternalLevelsAt = 264;
constexpr size_t kExternalLevelsChecksumAt = 268;  // covers bytes [0, 268)
// How far from unit length a stored direction column may be (they are written normalised).
constexpr double kUnitTolerance = 1e-9;

class ByteWriter {
public:
    explicit ByteWriter(unsigned char* out) : mOut(out) {}
    template <class T>
    void put(T v) {
        std::memcpy(mOut + mAt, &v, sizeof v);
        mAt += sizeof v;
    }
    void putBytes(const void* p, size_t n) {
        std::memcpy(mOut + mAt, p, n);
        mAt += n;
    }
    void skip(size_t n) { mAt += n; }
    size_t at() const { return mAt; }

private:
    unsigned char* mOut;
    size_t mAt = 0;
};

class ByteReader {
public:
    ByteReader(const unsigned char* in, size_t n) : mIn(in), mSize(n) {}
    template <class T>
    T get() {
        T v;
        std::memcpy(&v, mIn + mAt, sizeof v);
        mAt += sizeof v;
        return v;
    }
    void skip(size_t n) { mAt += n; }
    size_t at() const { return mAt; }
    size_t size() const { return mSize; }

private:
    const unsigned char* mIn;
    size_t mSize;
    size_t mAt = 0;
};

}  // namespace

namespace {

// Version 4's orientation (bytes 164..243). Before it, every store is unoriented: identity.
void decodeOrientation(const unsigned char* bytes, const std::string& path, VolumeInfo& volume) {
    uint32_t storedCrc;
    std::memcpy(&storedCrc, bytes + kWholeHeaderChecksumAt, 4);
    if (storedCrc != crc32Of(bytes, kWholeHeaderChecksumAt))
        throwIoError(path, "header checksum mismatch in its orientation (the header is corrupt)");
    ByteReader r(bytes + kOrientationAt, kWholeHeaderChecksumAt - kOrientationAt);
    const uint32_t flag = r.get<uint32_t>();
    glm::dmat3 direction;
    for (int c = 0; c < 3; ++c)
        for (int row = 0; row < 3; ++row) direction[c][row] = r.get<double>();
    if (flag > 1) throwIoError(path, "header's orientation flag " + std::to_string(flag) + " is neither 0 nor 1");
    if (flag == 0 && direction != glm::dmat3(1.0))
        throwIoError(path, "header has no orientation but a direction matrix other than the identity");
    if (const std::string problem = directionProblem(direction); !problem.empty())
        throwIoError(path, "header's orientation is invalid: " + problem);
    for (int c = 0; c < 3; ++c)
        if (!(std::abs(glm::length(direction[c]) - 1.0) <= kUnitTolerance))
            throwIoError(path, "header's direction matrix has a column that is not of unit length");
    volume.direction = direction;
    volume.hasOrientation = flag == 1;
}

}  // namespace

std::array<unsigned char, kStoreHeaderBytes> encodeHeader(const StoreHeader& h) {
    std::array<unsigned char, kStoreHeaderBytes> bytes{};
    ByteWriter w(bytes.data());
    w.putBytes(kHeaderMagic, 8);
    // The oldest version that holds what is written: a store without indexed data stays
    // readable by builds that read up to version 5, an index of level 0 only by those up to 6.
    w.put<uint32_t>(h.externalLevels > 1 ? 7u : h.externalBytes ? 6u : 5u);
    w.put<uint32_t>(kStoreHeaderBytes);
    for (int a = 0; a < 3; ++a) w.put<uint64_t>(uint64_t(h.volume.dims[a]));
    for (int a = 0; a < 3; ++a) w.put<double>(h.volume.spacing[a]);
    for (int a = 0; a < 3; ++a) w.put<double>(h.volume.origin[a]);
    w.put<uint8_t>(uint8_t(h.volume.type));
    w.put<uint8_t>(uint8_t(h.compression));
    w.put<uint8_t>(uint8_t(h.checksum));
    w.put<uint8_t>(uint8_t(h.filter));
    w.put<uint32_t>(uint32_t(h.brickSize));
    w.put<uint32_t>(kGhostBefore);
    w.put<uint32_t>(kGhostAfter);
    w.put<uint32_t>(kStoreAlignment);
    w.put<uint32_t>(uint32_t(h.levelCount));
    w.put<uint64_t>(uint64_t(totalBricks(h)));
    w.put<uint64_t>(h.indexOffset);
    w.put<uint64_t>(h.indexBytes);
    w.put<double>(h.valueMin);
    w.put<double>(h.valueMax);
    w.put<uint64_t>(h.storedBrickBytes);
    w.put<uint32_t>(crc32Of(bytes.data(), kHeaderChecksumAt));
    w.put<uint32_t>(h.volume.hasOrientation ? 1u : 0u);
    for (int c = 0; c < 3; ++c)
        for (int r = 0; r < 3; ++r) w.put<double>(h.volume.direction[c][r]);
    w.put<uint32_t>(crc32Of(bytes.data(), kWholeHeaderChecksumAt));
    if (h.externalBytes) {
        w.put<uint64_t>(h.externalOffset);
        w.put<uint64_t>(h.externalBytes);
        w.put<uint32_t>(crc32Of(bytes.data(), kExternalChecksumAt));
        if (h.externalLevels > 1) {
            w.put<uint32_t>(uint32_t(h.externalLevels));
            w.put<uint32_t>(crc32Of(bytes.data(), kExternalLevelsChecksumAt));
        }
    }
    if (const size_t n = h.indexDirectoryCopy.size(); n > 0 && n <= kDirectoryCopyMost) {
        ByteWriter copy(bytes.data() + kDirectoryCopyAt);
        copy.putBytes(kDirectoryCopyMagic, 8);
        copy.put<uint32_t>(uint32_t(n));
        copy.putBytes(h.indexDirectoryCopy.data(), n);
    }
    return bytes;
}

StoreHeader decodeHeader(const unsigned char* bytes, size_t n, const std::string& path) {
    if (n < kStoreHeaderBytes || std::memcmp(bytes, kHeaderMagic, 8) != 0)
        throwIoError(path, "not a vdiso brick store (wrong magic; convert volumes with "
                           "'vdiso convert' first)");
    ByteReader r(bytes, n);
    r.skip(8);
    const uint32_t version = r.get<uint32_t>();
    if (version > kStoreFormatVersion)
        throwIoError(path, "was written by a newer vdiso (store format version " +
                               std::to_string(version) + "; this build reads up to version " +
                               std::to_string(kStoreFormatVersion) + ")");
    if (version == 0) throwIoError(path, "has an invalid format version 0");
    if (version == 1)
        throwIoError(path, "is in store format version 1, which lacks the sub-block ranges this "
                           "build culls reads with; convert the volume again");
    const uint32_t storedCrc = [&] {
        uint32_t c;
        std::memcpy(&c, bytes + kHeaderChecksumAt, 4);
        return c;
    }();
    if (storedCrc != crc32Of(bytes, kHeaderChecksumAt))
        throwIoError(path, "header checksum mismatch (the header is corrupt)");
    if (r.get<uint32_t>() != kStoreHeaderBytes) throwIoError(path, "unexpected header size");

    StoreHeader h;
    h.formatVersion = version;
    for (int a = 0; a < 3; ++a) h.volume.dims[a] = int64_t(r.get<uint64_t>());
    for (int a = 0; a < 3; ++a) h.volume.spacing[a] = r.get<double>();
    for (int a = 0; a < 3; ++a) h.volume.origin[a] = r.get<double>();
    const uint8_t type = r.get<uint8_t>(), compression = r.get<uint8_t>(),
                  checksum = r.get<uint8_t>(), filter = r.get<uint8_t>();
    if (!isValidScalarCode(type))
        throwIoError(path, "unknown scalar type code " + std::to_string(type));
    if (compression > uint8_t(Compression::Lz4))
        throwIoError(path, "unknown compression code " + std::to_string(compression));
    if (checksum != uint8_t(ChecksumAlgorithm::Crc32))
        throwIoError(path, "unknown checksum algorithm code " + std::to_string(checksum));
    if (filter > uint8_t(BrickFilter::ByteShuffle))
        throwIoError(path, "unknown brick filter code " + std::to_string(filter));
    h.volume.type = ScalarType(type);
    h.filter = BrickFilter(filter);
    h.compression = Compression(compression);
    h.checksum = ChecksumAlgorithm(checksum);
    h.brickSize = int(r.get<uint32_t>());
    const uint32_t ghostBefore = r.get<uint32_t>(), ghostAfter = r.get<uint32_t>();
    const uint32_t alignment = r.get<uint32_t>();
    const uint32_t levelCount = r.get<uint32_t>();  // reserved (0) before version 3
    const uint64_t brickCount = r.get<uint64_t>();
    h.indexOffset = r.get<uint64_t>();
    h.indexBytes = r.get<uint64_t>();
    h.valueMin = r.get<double>();
    h.valueMax = r.get<double>();
    h.storedBrickBytes = r.get<uint64_t>();

    if (const std::string problem = volumeDimsProblem(h.volume.dims); !problem.empty())
        throwIoError(path, "header has invalid dimensions " + problem);
    if (h.brickSize < 2 || h.brickSize > 1024)
        throwIoError(path, "header has invalid brick size " + std::to_string(h.brickSize));
    if (const std::string problem = brickLayoutProblem(BrickLayout(h.volume.dims, h.brickSize));
        !problem.empty())
        throwIoError(path, problem);
    static const char* kAxis[3] = {"x", "y", "z"};
    for (int a = 0; a < 3; ++a) {
        // Spacing 0 gives NaN normals; a negative or non-finite one, no volume at all.
        if (!(std::isfinite(h.volume.spacing[a]) && h.volume.spacing[a] > 0))
            throwIoError(path, std::string("header's spacing along ") + kAxis[a] + " is " +
                                   std::to_string(h.volume.spacing[a]) +
                                   "; it must be a finite number above 0");
        if (!std::isfinite(h.volume.origin[a]))
            throwIoError(path, std::string("header's origin along ") + kAxis[a] + " is " +
                                   std::to_string(h.volume.origin[a]) + "; it must be finite");
        if (!std::isfinite(h.volume.worldMax()[a]))
            throwIoError(path, std::string("header's spacing and origin along ") + kAxis[a] +
                                   " put the volume's far end beyond the range of numbers");
    }
    // The value range is never NaN (docs/store-format.md, "Non-finite samples").
    if (!(h.valueMin <= h.valueMax))
        throwIoError(path, "header's value range [" + std::to_string(h.valueMin) + ", " +
                               std::to_string(h.valueMax) + "] is invalid");
    if (ghostBefore != kGhostBefore || ghostAfter != kGhostAfter)
        throwIoError(path, "unsupported ghost layout");
    if (alignment != kStoreAlignment) throwIoError(path, "unsupported brick alignment");
    if (version < 3) {
        h.levelCount = 1;
    } else {
        const int most = levelsUntilOneBrick(BrickLayout(h.volume.dims, h.brickSize));
        if (levelCount < 1 || levelCount > uint32_t(most))
            throwIoError(path, "header's level count " + std::to_string(levelCount) +
                                   " is invalid: this volume has between 1 and " + std::to_string(most) +
                                   " levels of detail");
        h.levelCount = int(levelCount);
    }
    if (version >= 4) decodeOrientation(bytes, path, h.volume);
    if (version >= 6) {
        uint32_t crc;
        std::memcpy(&crc, bytes + kExternalChecksumAt, 4);
        if (crc != crc32Of(bytes, kExternalChecksumAt))
            throwIoError(path, "header checksum mismatch in its record of indexed data (the header is corrupt)");
        std::memcpy(&h.externalOffset, bytes + kExternalAt, 8);
        std::memcpy(&h.externalBytes, bytes + kExternalAt + 8, 8);
        if (h.externalBytes < 28 || h.externalBytes > (uint64_t(1) << 36) || h.externalOffset < kStoreHeaderBytes ||
            h.externalOffset > h.indexOffset || h.externalBytes > h.indexOffset - h.externalOffset)
            throwIoError(path, "header's record of indexed data lies outside the file's bricks");
        h.externalLevels = 1;
    }
    if (version >= 7) {
        uint32_t crc, levels;
        std::memcpy(&crc, bytes + kExternalLevelsChecksumAt, 4);
        if (crc != crc32Of(bytes, kExternalLevelsChecksumAt))
            throwIoError(path, "header checksum mismatch in its record of indexed data (the header is corrupt)");
        std::memcpy(&levels, bytes + kExternalLevelsAt, 4);
        if (levels < 2 || levels > uint32_t(h.levelCount))
            throwIoError(path, "header says " + std::to_string(levels) + " of its " + std::to_string(h.levelCount) +
                                   " levels lie in the indexed data");
        h.externalLevels = int(levels);
    }
    if (brickCount != uint64_t(totalBricks(h)))
        throwIoError(path, "header's brick count does not match its dimensions and levels");
    // Before version 5 the index is stored raw; from 5, in compressed parts (io/store/index_parts.h).
    const uint64_t raw = indexBytes(brickCount);
    if (version < 5 ? h.indexBytes != raw
                    : h.indexBytes < packedIndexMin(raw) || h.indexBytes > packedIndexMax(raw))
        throwIoError(path, "header's index size does not match its brick count");
    // The directory's copy, when there is one; checked where it is used (io/store/lazy_index.h).
    if (version >= 5 && std::memcmp(bytes + kDirectoryCopyAt, kDirectoryCopyMagic, 8) == 0) {
        uint32_t copyBytes;
        std::memcpy(&copyBytes, bytes + kDirectoryCopyAt + 8, 4);
        if (copyBytes > 0 && copyBytes <= kDirectoryCopyMost)
            h.indexDirectoryCopy.assign(bytes + kDirectoryCopyAt + 12, bytes + kDirectoryCopyAt + 12 + copyBytes);
    }
    return h;
}

int64_t totalBricks(const StoreHeader& header) { return firstBrickOfLevel(header, header.levelCount); }

int64_t firstBrickOfLevel(const StoreHeader& header, int level) {
    if (level <= 0) return 0;
    const std::vector<BrickLevel> levels = brickLevels(header.volume, header.brickSize, level);
    return levels.back().firstBrick + levels.back().layout.brickCount();
}

uint64_t indexBytes(uint64_t brickCount) {
    return checkedAdd(checkedAdd(subBlockCodesAt(brickCount), checkedMul(brickCount, uint64_t(kSubBlocksPerBrick) * 2)), 4);
}

void encodeEntry(const BrickEntry& e, unsigned char* out) {
    ByteWriter w(out);
    w.put<uint64_t>(e.offset);
    w.put<uint32_t>(e.storedBytes);
    w.put<uint32_t>(e.checksum);
    w.put<float>(e.minValue);
    w.put<float>(e.maxValue);
    w.put<uint32_t>((e.compressed ? 1u : 0u) | (e.external ? 2u : 0u));
    w.put<uint32_t>(0);
}

BrickEntry decodeEntry(const unsigned char* in, uint32_t& flags) {
    ByteReader r(in, kEntryBytes);
    BrickEntry e{};
    e.offset = r.get<uint64_t>();
    e.storedBytes = r.get<uint32_t>();
    e.checksum = r.get<uint32_t>();
    e.minValue = r.get<float>();
    e.maxValue = r.get<float>();
    flags = r.get<uint32_t>();
    e.compressed = (flags & 1u) != 0;
    e.external = (flags & 2u) != 0;
    return e;
}

std::vector<unsigned char> encodeIndex(const std::vector<BrickEntry>& entries,
                                       const ValueHistogram& histogram,
                                       const std::vector<SubBlockCode>& subBlocks) {
    std::vector<unsigned char> bytes(indexBytes(entries.size()));
    ByteWriter w(bytes.data());
    w.putBytes(kIndexMagic, 8);
    w.put<uint64_t>(entries.size());
    for (const BrickEntry& e : entries) {
        encodeEntry(e, bytes.data() + w.at());
        w.skip(kEntryBytes);
    }
    w.put<double>(histogram.lo);
    w.put<double>(histogram.hi);
    w.put<uint32_t>(kHistogramBins);
    w.put<uint32_t>(0);
    for (uint64_t c : histogram.counts) w.put<uint64_t>(c);
    w.put<uint32_t>(kSubBlocksPerAxis);
    w.put<uint32_t>(0);
    for (const SubBlockCode& code : subBlocks) {
        w.put<uint8_t>(code.lo);
        w.put<uint8_t>(code.hi);
    }
    w.put<uint32_t>(crc32Of(bytes.data(), w.at()));
    return packIndex(bytes);
}

uint64_t subBlockCodesAt(uint64_t brickCount) {
    return checkedAdd(checkedMul(brickCount, kEntryBytes), 16 + 24 + uint64_t(kHistogramBins) * 8 + 8);
}

void decodeIndex(const unsigned char* bytes, size_t n, bool whole, const StoreHeader& header,
                 const BrickLayout& layout, const std::string& path, BrickIndex& entries,
                 ValueHistogram& histogram) {
    const uint64_t count = uint64_t(totalBricks(header));
    if (n != (whole ? indexBytes(count) : subBlockCodesAt(count)) || std::memcmp(bytes, kIndexMagic, 8) != 0)
        throwIoError(path, "index is missing or corrupt (wrong magic at byte offset " +
                               std::to_string(header.indexOffset) + ")");
    if (whole) {
        uint32_t storedCrc;
        std::memcpy(&storedCrc, bytes + n - 4, 4);
        if (storedCrc != crc32Of(bytes, n - 4)) throwIoError(path, "index checksum mismatch (the index is corrupt)");
    }
    ByteReader r(bytes, n);
    r.skip(8);
    if (r.get<uint64_t>() != count) throwIoError(path, "index brick count does not match header");

    const uint64_t rawBytes = uint64_t(layout.samplesPerBrick()) * scalarSize(header.volume.type);
    const int64_t externalEnd = firstBrickOfLevel(header, header.externalLevels);
    const uint64_t maxStored = maxStoredBrickBytes(rawBytes);
    // Whether entry `id` (decoded into e) is valid.
    auto valid = [&](uint64_t id, const BrickEntry& e, uint32_t flags) {
        // An index's levels that lie in the indexed data, and only those, are external: no bytes here.
        if (e.external != (id < uint64_t(externalEnd)) || flags > 3) return false;
        if (e.external) return !e.offset && !e.storedBytes && !e.checksum && !e.compressed && e.minValue <= e.maxValue;
        return e.offset >= kStoreHeaderBytes && e.offset % kStoreAlignment == 0 && e.storedBytes > 0 &&
               e.storedBytes <= maxStored && e.offset <= header.indexOffset &&
               e.storedBytes <= header.indexOffset - e.offset && (e.compressed || e.storedBytes == rawBytes) &&
               (e.compressed == false || header.compression != Compression::None) &&
               e.minValue <= e.maxValue;  // false for NaN too
    };
    // Decoded in blocks on TBB's threads (a 2560^3 store's 585 K entries took 18-21 ms on one, at
    // every open); an error names the first invalid entry, as one pass in order would.
    entries.resize(count);
    const unsigned char* first = bytes + r.at();
    std::atomic<uint64_t> firstInvalid{count};
    auto decodeBlock = [&](uint64_t begin, uint64_t end) {
        for (uint64_t id = begin; id < end; ++id) {
            uint32_t flags = 0;
            const BrickEntry& e = entries[id] = decodeEntry(first + id * kEntryBytes, flags);
            if (!valid(id, e, flags)) {
                uint64_t seen = firstInvalid.load();
                while (id < seen && !firstInvalid.compare_exchange_weak(seen, id)) {
                }
                return;
            }
        }
    };
    constexpr uint64_t kBlock = 16384;  // a store of fewer bricks is decoded on this thread
    if (count <= kBlock)
        decodeBlock(0, count);
    else
        tbb::parallel_for(tbb::blocked_range<uint64_t>(0, count, kBlock),
                          [&](const tbb::blocked_range<uint64_t>& block) { decodeBlock(block.begin(), block.end()); });
    if (firstInvalid < count) throwIoError(path, "index entry of brick " + std::to_string(firstInvalid.load()) + " is invalid");
    r.skip(size_t(count * kEntryBytes));
    histogram.lo = r.get<double>();
    histogram.hi = r.get<double>();
    if (r.get<uint32_t>() != kHistogramBins || !std::isfinite(histogram.lo) ||
        !std::isfinite(histogram.hi) || !(histogram.lo <= histogram.hi))
        throwIoError(path, "index histogram is invalid");
    r.skip(4);
    for (uint64_t& c : histogram.counts) c = r.get<uint64_t>();
    if (r.get<uint32_t>() != kSubBlocksPerAxis) throwIoError(path, "index sub-block ranges are invalid");
}

}  // namespace vdiso::store_format
