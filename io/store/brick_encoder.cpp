#include "io/store/brick_encoder.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>

#include <sys/mman.h>

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <zstd.h>

#include "core/brick_levels.h"
#include "core/checked_math.h"
#include "core/huge_pages.h"
#include "core/lod/downsample.h"
#include "core/kernel/iso.h"
#include "core/orientation.h"
#include "io/atomic_output.h"
#include "io/store/brick_codec.h"
#include "io/store/brick_measure.h"
#include "io/crc32.h"
#include "io/error.h"
#include "io/store/index_parts.h"
#include "io/store/store_format.h"

namespace vdiso {

namespace {

// A fine histogram of 65536 bins (io/store/brick_measure.h fineKey), coarsened to
// kHistogramBins over [min, max] at the end.
constexpr int kFineBins = kFineHistogramBins;

// The float whose remapped bits are k.
double remappedFloat(uint32_t k) {
    const uint32_t u = (k & 0x80000000u) ? (k & 0x7fffffffu) : ~k;
    return double(std::bit_cast<float>(u));
}

// The value at a fine bin's low end (part 0), middle (1) or high end (2): one value for integers.
double fineKeyValue(ScalarType type, uint32_t key, int part = 1) {
    switch (type) {
        case ScalarType::U8:
        case ScalarType::U16: return double(key);
        case ScalarType::I16: return double(int32_t(key) - 32768);
        case ScalarType::F32: break;
    }
    static constexpr uint32_t kPart[3] = {0x0000u, 0x8000u, 0xffffu};
    return remappedFloat((key << 16) | kPart[part]);
}

enum class KeyKind { Finite, NaN, NegativeInfinity, PositiveInfinity };

KeyKind fineKeyKind(ScalarType type, uint32_t key) {
    if (type != ScalarType::F32) return KeyKind::Finite;
    if (key == kNanKey) return KeyKind::NaN;
    if (key <= kNegativeInfinityKey) return KeyKind::NegativeInfinity;
    if (key >= kPositiveInfinityKey) return KeyKind::PositiveInfinity;
    return KeyKind::Finite;
}

// Copies brick (bi, bj) of the window's layer into dst, (B+3)^3 samples, clamping at borders.
template <class T>
void gatherBrick(const SliceWindow& window, const BrickLayout& layout, int64_t bi, int64_t bj,
                 int64_t bk, T* dst) {
    const int side = layout.side();
    const int64_t nx = layout.dims[0];
    const int64_t x0 = layout.firstSample(bi);
    // The part of each row inside the volume is one copy; only border bricks clamp the ends.
    const int begin = int(std::max<int64_t>(0, -x0));
    const int end = int(std::min<int64_t>(side, nx - x0));
    for (int lz = 0; lz < side; ++lz) {
        const int64_t z = layout.clampSample(2, layout.firstSample(bk) + lz);
        const T* slice = reinterpret_cast<const T*>(window.slice(z));
        for (int ly = 0; ly < side; ++ly) {
            const int64_t y = layout.clampSample(1, layout.firstSample(bj) + ly);
            const T* row = slice + y * nx;
            std::memcpy(dst + begin, row + x0 + begin, size_t(end - begin) * sizeof(T));
            for (int lx = 0; lx < begin; ++lx) dst[lx] = row[0];
            for (int lx = end; lx < side; ++lx) dst[lx] = row[nx - 1];
            dst += side;
        }
    }
}

struct BrickScratch {
    std::vector<unsigned char> raw;
    std::vector<uint64_t> histogramEven = std::vector<uint64_t>(kFineBins, 0);
    std::vector<uint64_t> histogramOdd = std::vector<uint64_t>(kFineBins, 0);
    BrickCodecScratch codec;
};

// Brick `id` of the level whose slices `window` holds, in `layout`; its owned samples count in
// the histogram when `countSamples` (level 0); with `external` (an index's level lying in the
// indexed data) it is measured only.
void encodeBrick(const SliceWindow& window, const BrickLayout& layout, ScalarType type,
                 const StoreWriteOptions& options, int64_t id, bool countSamples, bool external, BrickScratch& scratch,
                 EncodedBrick& out) {
    const Dims3 coord = layout.brickCoord(id);
    measureBrickInSlices(type, window, layout, coord, out.entry, out.subBlocks,
                         countSamples ? scratch.histogramEven.data() : nullptr,
                         countSamples ? scratch.histogramOdd.data() : nullptr);
    out.entry.external = external;
    if (external) {  // measured, its samples left where they are
        out.bytes.clear();
        out.entry.compressed = false;
        out.entry.storedBytes = 0;
        out.entry.checksum = 0;
        return;
    }
    scratch.raw.resize(size_t(layout.samplesPerBrick()) * scalarSize(type));
    visitScalarType(type, [&](auto zero) {
        using T = decltype(zero);
        gatherBrick<T>(window, layout, coord[0], coord[1], coord[2], reinterpret_cast<T*>(scratch.raw.data()));
    });
    out.entry.compressed = encodeBrickBytes(scratch.raw, scalarSize(type), options.compression,
                                            storeFilterFor(type, options), options.compressionLevel,
                                            scratch.codec, out.bytes);
    out.entry.storedBytes = uint32_t(out.bytes.size());
    out.entry.checksum = crc32Of(out.bytes.data(), out.bytes.size());
}

}  // namespace

BrickFilter storeFilterFor(ScalarType type, const StoreWriteOptions& options) {
    return options.compression != Compression::None && options.shuffle && scalarSize(type) > 1
               ? BrickFilter::ByteShuffle
               : BrickFilter::None;
}

VolumeInfo storeVolumeFor(const VolumeInfo& source, const StoreWriteOptions& options,
                          const std::string& sourceName) {
    if (options.brickSize < 2 || options.brickSize > 512)
        throw std::invalid_argument("brick size must be between 2 and 512 cells, not " +
                                    std::to_string(options.brickSize));
    if (options.compressionLevel < ZSTD_minCLevel() || options.compressionLevel > ZSTD_maxCLevel())
        throw std::invalid_argument("zstd level must be between " +
                                    std::to_string(ZSTD_minCLevel()) + " and " +
                                    std::to_string(ZSTD_maxCLevel()));
    for (int a = 0; a < 3; ++a)
        if (source.dims[a] < 2)
            throwIoError(sourceName, "every axis needs at least 2 samples to hold cells");
    requireVolumeDims(sourceName, source.dims);
    // Readers refuse these; a source that did not would make a store that cannot be opened.
    if (const std::string problem = directionProblem(source.direction); !problem.empty())
        throwIoError(sourceName, problem);
    if (!source.hasOrientation && source.direction != glm::dmat3(1.0))
        throw std::invalid_argument(sourceName + ": a direction matrix without an orientation");
    const BrickLayout layout(source.dims, options.brickSize);
    if (const std::string problem = brickLayoutProblem(layout); !problem.empty())
        throwIoError(sourceName, problem);
    const int most = levelsUntilOneBrick(layout) - 1;
    if (options.coarseLevels != StoreWriteOptions::kLevelsUntilOneBrick &&
        (options.coarseLevels < 0 || options.coarseLevels > most))
        throw std::invalid_argument("--levels " + std::to_string(options.coarseLevels) + ": " +
                                    sourceName + " in bricks of " + std::to_string(options.brickSize) +
                                    " cells has at most " + std::to_string(most) +
                                    " coarser levels (the coarsest is then one brick)");
    VolumeInfo info = source;
    info.direction = normalizedColumns(info.direction);  // the store holds unit columns
    return info;
}

int storeLevelCount(const BrickLayout& level0, const StoreWriteOptions& options) {
    return options.coarseLevels == StoreWriteOptions::kLevelsUntilOneBrick ? levelsUntilOneBrick(level0)
                                                                          : options.coarseLevels + 1;
}

MappedSlices::MappedSlices(const Dims3& dims, size_t sampleBytes, int64_t slots, const std::string& sourceName) {
    mSliceBytes = size_t(dims[0] * dims[1]) * sampleBytes;
    mSlots = std::min<int64_t>(slots, dims[2]);
    const uint64_t bytes = checkedMul(uint64_t(mSlots), uint64_t(mSliceBytes));
    void* p = bytes > SIZE_MAX ? MAP_FAILED
                               : ::mmap(nullptr, size_t(bytes), PROT_READ | PROT_WRITE,
                                        MAP_PRIVATE | MAP_ANONYMOUS | MAP_NORESERVE, -1, 0);
    if (p == MAP_FAILED)
        throwIoError(sourceName, "converting it needs " + std::to_string(bytes >> 20) + " MiB for " +
                                     std::to_string(mSlots) + " slices of " + std::to_string(dims[0]) +
                                     " x " + std::to_string(dims[1]) +
                                     " samples, more memory than the process may allocate");
    mBytes = static_cast<unsigned char*>(p);
    mMappedBytes = size_t(bytes);
    // Rows of a slice lie a slice's width apart: measuring a brick walks 33 x 33 of them, each a
    // page of its own on a 2048-wide u16 volume (a TLB miss a row). In huge pages, `vdiso index`
    // of a 2048^3 OME-Zarr took 0.94x the wall time (5 pairs).
    adviseHugePages(p, size_t(bytes));
}

MappedSlices::~MappedSlices() {
    if (mBytes) ::munmap(mBytes, mMappedBytes);
}

void readSlices(SliceReader& source, const SliceWindow& window, int64_t z0, int64_t z1) {
    while (z0 < z1) {
        const int64_t run = std::min(z1 - z0, window.slots - (z0 - window.first) % window.slots);
        source.read(window.slice(z0), run);
        z0 += run;
    }
}

void downsampleSlice(ScalarType type, const SliceWindow& fine, const Dims3& fineDims,
                     const Dims3& coarseDims, int64_t z, unsigned char* dst) {
    auto fineSlice = [&](int64_t s) { return fine.slice(std::clamp<int64_t>(s, 0, fineDims[2] - 1)); };
    visitScalarType(type, [&](auto zero) {
        using T = decltype(zero);
        const T* planes[3] = {reinterpret_cast<const T*>(fineSlice(2 * z - 1)),
                              reinterpret_cast<const T*>(fineSlice(2 * z)),
                              reinterpret_cast<const T*>(fineSlice(2 * z + 1))};
        T* out = reinterpret_cast<T*>(dst);
        tbb::parallel_for(tbb::blocked_range<int64_t>(0, coarseDims[1], 16), [&](const auto& r) {
            downsampleRows<T>(planes[0], planes[1], planes[2], fineDims, coarseDims, r.begin(), r.end(), out);
        });
    });
}

struct BrickEncoder::Impl {
    ScalarType type;
    StoreWriteOptions options;
    tbb::enumerable_thread_specific<BrickScratch> scratch;
};

BrickEncoder::BrickEncoder(ScalarType type, const StoreWriteOptions& options)
    : mImpl(std::make_unique<Impl>()) {
    mImpl->type = type;
    mImpl->options = options;
}

BrickEncoder::~BrickEncoder() = default;

void BrickEncoder::encode(const SliceWindow& window, const BrickLayout& layout, int64_t firstId,
                          int64_t count, bool countSamples, bool external, std::vector<EncodedBrick>& out) {
    if (out.size() < size_t(count)) out.resize(size_t(count));
    Impl& m = *mImpl;
    tbb::parallel_for(tbb::blocked_range<int64_t>(0, count, 2), [&](const auto& r) {
        BrickScratch& s = m.scratch.local();
        for (int64_t b = r.begin(); b != r.end(); ++b)
            encodeBrick(window, layout, m.type, m.options, firstId + b, countSamples, external, s, out[size_t(b)]);
    });
}

std::vector<uint64_t> BrickEncoder::fineHistogram() const {
    std::vector<uint64_t> fine(kFineBins, 0);
    for (const BrickScratch& s : mImpl->scratch)
        for (size_t key = 0; key < size_t(kFineBins); ++key)
            fine[key] += s.histogramEven[key] + s.histogramOdd[key];
    return fine;
}

uint64_t placeBricks(std::vector<EncodedBrick>& bricks, int64_t count, uint64_t start) {
    for (int64_t b = 0; b < count; ++b) {
        if (bricks[size_t(b)].entry.external) {  // no bytes in the file
            bricks[size_t(b)].entry.offset = 0;
            continue;
        }
        bricks[size_t(b)].entry.offset = start;
        start = alignToStore(start + bricks[size_t(b)].bytes.size());
    }
    return start;
}

uint64_t placedBytes(const std::vector<EncodedBrick>& bricks, int64_t count) {
    uint64_t n = 0;
    for (int64_t b = 0; b < count; ++b) n += alignToStore(bricks[size_t(b)].bytes.size());
    return n;
}

BrickGroupWriter::~BrickGroupWriter() {
    if (mPending.valid()) mPending.wait();
}

void BrickGroupWriter::write(int64_t count, uint64_t start, uint64_t end) {
    std::vector<EncodedBrick>& group = mGroups[mNext % 2];
    if (mPending.valid()) mPending.get();
    mPending = std::async(std::launch::async, [this, &group, count, start, end] {
        for (int64_t b = 0; b < count; ++b)
            if (!group[size_t(b)].bytes.empty())
                writeAllAt(mFd, group[size_t(b)].bytes.data(), group[size_t(b)].bytes.size(),
                       group[size_t(b)].entry.offset, mPath);
        startWriteback(mFd, start, end - start);
    });
    ++mNext;
}

void BrickGroupWriter::finish() {
    if (mPending.valid()) mPending.get();
}

StoreTail finishStore(const VolumeInfo& volume, const StoreWriteOptions& options, int levelCount,
                      int64_t level0Bricks, const std::vector<BrickEntry>& entries,
                      const std::vector<SubBlockCode>& subBlocks, const std::vector<uint64_t>& fine,
                      uint64_t indexOffset, const std::string& inputName) {
    if (fine.size() != size_t(kFineBins))
        throw std::invalid_argument("finishStore: the fine histogram has " + std::to_string(fine.size()) +
                                    " bins, not " + std::to_string(kFineBins));
    StoreTail tail;
    StoreHeader& header = tail.header;
    header.volume = volume;
    header.brickSize = options.brickSize;
    header.levelCount = levelCount;
    header.compression = options.compression;
    header.filter = storeFilterFor(volume.type, options);
    header.valueMin = std::numeric_limits<double>::max();
    header.valueMax = std::numeric_limits<double>::lowest();
    for (size_t id = 0; id < entries.size(); ++id) {
        const BrickEntry& e = entries[id];
        header.storedBrickBytes += e.storedBytes;
        if (int64_t(id) >= level0Bricks) continue;  // coarse samples lie within level 0's
        tail.level0Bytes += e.storedBytes;
        header.valueMin = std::min(header.valueMin, double(e.minValue));
        header.valueMax = std::max(header.valueMax, double(e.maxValue));
    }

    // The histogram spans the finite samples (docs/store-format.md): -inf counts in the first
    // bin, +inf in the last, NaN nowhere. Where the volume's range is infinite, the finite end
    // is the edge of the extreme finite fine bin.
    const ScalarType type = volume.type;
    ValueHistogram histogram;
    histogram.lo = std::isfinite(header.valueMin) ? header.valueMin : 0.0;
    histogram.hi = std::isfinite(header.valueMax) ? header.valueMax : 0.0;
    bool anyFinite = false;
    for (uint32_t key = 0; key < uint32_t(kFineBins); ++key) {
        if (!fine[key] || fineKeyKind(type, key) != KeyKind::Finite) continue;
        if (!std::isfinite(header.valueMin) && !anyFinite) histogram.lo = fineKeyValue(type, key, 0);
        if (!std::isfinite(header.valueMax)) histogram.hi = fineKeyValue(type, key, 2);
        anyFinite = true;
    }
    if (!anyFinite)
        throwIoError(inputName, "has no finite sample (every one is NaN or infinite): there is no isosurface "
                                "to extract from it");
    const double binScale =
        histogram.hi > histogram.lo ? kHistogramBins / (histogram.hi - histogram.lo) : 0.0;
    for (uint32_t key = 0; key < uint32_t(kFineBins); ++key) {
        if (!fine[key]) continue;
        int bin = 0;
        switch (fineKeyKind(type, key)) {
            case KeyKind::NaN: continue;  // NaN samples have no place on the value axis
            case KeyKind::NegativeInfinity: bin = 0; break;
            case KeyKind::PositiveInfinity: bin = kHistogramBins - 1; break;
            case KeyKind::Finite: {
                const double v = std::clamp(fineKeyValue(type, key), histogram.lo, histogram.hi);
                bin = std::min(kHistogramBins - 1, int((v - histogram.lo) * binScale));
                break;
            }
        }
        histogram.counts[size_t(bin)] += fine[key];
    }

    header.indexOffset = indexOffset;
    tail.index = store_format::encodeIndex(entries, histogram, subBlocks);
    header.indexBytes = tail.index.size();
    // The index's directory (its first bytes) copied into the header where it fits.
    const uint64_t directoryBytes = store_format::indexDirectoryBytes(store_format::indexBytes(entries.size()));
    if (directoryBytes <= store_format::kDirectoryCopyMost && directoryBytes <= tail.index.size())
        header.indexDirectoryCopy.assign(tail.index.begin(), tail.index.begin() + ptrdiff_t(directoryBytes));
    tail.headerBytes = store_format::encodeHeader(header);
    return tail;
}

}  // namespace vdiso
