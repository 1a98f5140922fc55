#include "io/store_writer.h"

#include <algorithm>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstring>

#include <sys/mman.h>
#include <functional>
#include <future>
#include <limits>
#include <memory>
#include <new>
#include <stdexcept>

#include <tbb/blocked_range2d.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <lz4.h>
#include <zstd.h>

#include "core/interrupt.h"
#include "core/iso.h"
#include "core/orientation.h"
#include "core/brick_levels.h"
#include "core/downsample.h"
#include "core/sub_blocks.h"
#include "io/atomic_output.h"
#include "io/byte_shuffle.h"
#include "io/error.h"
#include "io/store_format.h"

namespace vdiso {

namespace {

// A fine histogram of 65536 bins, keyed so that key order is value order for every type:
// exact for 8- and 16-bit integers; for floats, the top 16 bits of an order-preserving
// remapping of the IEEE bits. Coarsened to kHistogramBins over [min, max] at the end.
constexpr int kFineBins = 1 << 16;

inline uint32_t fineKey(uint8_t v) { return v; }
inline uint32_t fineKey(uint16_t v) { return v; }
inline uint32_t fineKey(int16_t v) { return uint32_t(int32_t(v) + 32768); }
// Floats: every NaN goes to key 0 (a bin that otherwise holds only NaN bit patterns), so that
// the keys of -inf (0x7f) and +inf (0xff80) hold nothing but infinities.
constexpr uint32_t kNanKey = 0;
constexpr uint32_t kNegativeInfinityKey = 0x7f;
constexpr uint32_t kPositiveInfinityKey = 0xff80;
inline uint32_t fineKey(float v) {
    if (v != v) return kNanKey;
    const uint32_t u = std::bit_cast<uint32_t>(v);
    return ((u & 0x80000000u) ? ~u : (u | 0x80000000u)) >> 16;
}

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

// Slices held in memory: a ring of 2B+3 (or of the volume's depth, if smaller), slice z in slot
// z mod slots. A layer of bricks needs B+3 consecutive slices; the other B slots receive the
// next layer's new slices while this layer is encoded, so reading overlaps compression. The
// ring's memory is address space mapped without reserving memory (MAP_NORESERVE), so its pages
// are only taken as slices arrive: a header that promises more data than its (compressed) file
// holds costs the memory of what it does hold. (An allocation from the heap would be the same
// on Linux, but a sanitizer's heap takes its size at its word.)
struct SliceRing {
    unsigned char* bytes = nullptr;
    size_t mappedBytes = 0;
    size_t sliceBytes = 0;
    int64_t slots = 0;
    SliceRing() = default;
    SliceRing(const SliceRing&) = delete;
    SliceRing& operator=(const SliceRing&) = delete;
    ~SliceRing() {
        if (bytes) ::munmap(bytes, mappedBytes);
    }
    // False when the address space is not there (an address-space limit).
    bool map(size_t n) {
        void* p = ::mmap(nullptr, n, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS | MAP_NORESERVE, -1, 0);
        if (p == MAP_FAILED) return false;
        bytes = static_cast<unsigned char*>(p);
        mappedBytes = n;
        return true;
    }
    const unsigned char* slice(int64_t z) const { return bytes + size_t(z % slots) * sliceBytes; }
    unsigned char* slice(int64_t z) { return bytes + size_t(z % slots) * sliceBytes; }
};

// Reads slices [z0, z1) from the source into their ring slots, in runs that do not wrap.
void readSlices(SliceReader& source, SliceRing& ring, int64_t z0, int64_t z1) {
    while (z0 < z1) {
        const int64_t run = std::min(z1 - z0, ring.slots - z0 % ring.slots);
        source.read(ring.slice(z0), run);
        z0 += run;
    }
}

// Copies brick (bi, bj) of the window's layer into dst, (B+3)^3 samples, clamping at borders.
template <class T>
void gatherBrick(const SliceRing& window, const BrickLayout& layout, int64_t bi, int64_t bj,
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

// Min and max over the samples of the brick's cells, and the histogram of the samples the
// brick owns (each volume sample is owned by exactly one brick). Separate loops per row: the
// min/max reduction vectorises; the histogram alternates two tables so that runs of equal
// values (smooth data) do not wait on the same counter.
template <class T>
void measureBrick(const T* brick, const BrickLayout& layout, const Dims3& coord, float& minValue,
                  float& maxValue, uint64_t* histogramEven, uint64_t* histogramOdd) {
    const int side = layout.side();
    int cells[3], owned[3];
    for (int a = 0; a < 3; ++a) {
        cells[a] = layout.cellsOnAxis(a, coord[a]);
        owned[a] = layout.ownedSamplesOnAxis(a, coord[a]);
    }
    // NaN samples count as -inf in the range (core/iso.h), so a range is never NaN.
    T lo = rangeValue(brick[(size_t(kGhostBefore) * side + kGhostBefore) * side + kGhostBefore]);
    T hi = lo;
    for (int lz = kGhostBefore; lz <= kGhostBefore + cells[2]; ++lz) {
        for (int ly = kGhostBefore; ly <= kGhostBefore + cells[1]; ++ly) {
            const T* row = brick + (size_t(lz) * side + ly) * side + kGhostBefore;
            T rowLo = rangeValue(row[0]), rowHi = rowLo;
            for (int i = 1; i <= cells[0]; ++i) {
                const T v = rangeValue(row[i]);
                rowLo = v < rowLo ? v : rowLo;
                rowHi = v > rowHi ? v : rowHi;
            }
            lo = std::min(lo, rowLo);
            hi = std::max(hi, rowHi);
            if (!histogramEven) continue;  // a coarse level: the histogram is level 0's
            if (lz >= kGhostBefore + owned[2] || ly >= kGhostBefore + owned[1]) continue;
            int i = 0;
            for (; i + 1 < owned[0]; i += 2) {
                ++histogramEven[fineKey(row[i])];
                ++histogramOdd[fineKey(row[i + 1])];
            }
            if (i < owned[0]) ++histogramEven[fineKey(row[i])];
        }
    }
    minValue = float(lo);
    maxValue = float(hi);
}

struct BrickScratch {
    std::vector<unsigned char> raw, shuffled;
    std::vector<uint64_t> histogramEven = std::vector<uint64_t>(kFineBins, 0);
    std::vector<uint64_t> histogramOdd = std::vector<uint64_t>(kFineBins, 0);
    ZSTD_CCtx* cctx = nullptr;
    BrickScratch() = default;
    BrickScratch(const BrickScratch&) = delete;
    ~BrickScratch() { ZSTD_freeCCtx(cctx); }
};

struct StoredBrick {
    std::vector<unsigned char> bytes;
    BrickEntry entry;
    SubBlockCode subBlocks[kSubBlocksPerBrick];
};

BrickFilter filterFor(ScalarType type, const StoreWriteOptions& options) {
    return options.compression != Compression::None && options.shuffle && scalarSize(type) > 1
               ? BrickFilter::ByteShuffle
               : BrickFilter::None;
}

// Brick `id` of the level whose slices `window` holds, in `layout`; its owned samples count in
// the histogram when `countSamples` (level 0).
void encodeBrick(const SliceRing& window, const BrickLayout& layout, ScalarType type,
                 const StoreWriteOptions& options, int64_t id, bool countSamples, BrickScratch& scratch,
                 StoredBrick& out) {
    const Dims3 coord = layout.brickCoord(id);
    const size_t rawBytes = size_t(layout.samplesPerBrick()) * scalarSize(type);
    scratch.raw.resize(rawBytes);
    visitScalarType(type, [&](auto zero) {
        using T = decltype(zero);
        T* brick = reinterpret_cast<T*>(scratch.raw.data());
        gatherBrick<T>(window, layout, coord[0], coord[1], coord[2], brick);
        measureBrick<T>(brick, layout, coord, out.entry.minValue, out.entry.maxValue,
                        countSamples ? scratch.histogramEven.data() : nullptr,
                        countSamples ? scratch.histogramOdd.data() : nullptr);
    });
    measureSubBlocks(type, scratch.raw.data(), layout, coord,
                     {out.entry.minValue, out.entry.maxValue}, out.subBlocks);
    out.entry.compressed = false;
    if (options.compression != Compression::None) {
        const unsigned char* input = scratch.raw.data();
        if (filterFor(type, options) == BrickFilter::ByteShuffle) {
            scratch.shuffled.resize(rawBytes);
            shuffleBytes(input, rawBytes / scalarSize(type), scalarSize(type), scratch.shuffled.data());
            input = scratch.shuffled.data();
        }
        size_t n = 0;
        if (options.compression == Compression::Lz4) {
            out.bytes.resize(size_t(LZ4_compressBound(int(rawBytes))));
            n = size_t(LZ4_compress_default(reinterpret_cast<const char*>(input),
                                            reinterpret_cast<char*>(out.bytes.data()),
                                            int(rawBytes), int(out.bytes.size())));
            if (n == 0) throw std::runtime_error("lz4: cannot compress a brick");
        } else {
            if (!scratch.cctx) scratch.cctx = ZSTD_createCCtx();
            out.bytes.resize(ZSTD_compressBound(rawBytes));
            n = ZSTD_compressCCtx(scratch.cctx, out.bytes.data(), out.bytes.size(), input, rawBytes,
                                  options.compressionLevel);
            if (ZSTD_isError(n)) throw std::runtime_error(std::string("zstd: ") + ZSTD_getErrorName(n));
        }
        // Incompressible bricks (noise) are stored raw: reading them is then a plain copy.
        if (n < rawBytes) {
            out.bytes.resize(n);
            out.entry.compressed = true;
        }
    }
    if (!out.entry.compressed) out.bytes.assign(scratch.raw.begin(), scratch.raw.end());
    out.entry.storedBytes = uint32_t(out.bytes.size());
    out.entry.checksum = store_format::crc32Of(out.bytes.data(), out.bytes.size());
}

uint64_t alignUp(uint64_t v) { return (v + kStoreAlignment - 1) / kStoreAlignment * kStoreAlignment; }

void validateOptions(const VolumeInfo& info, const StoreWriteOptions& options,
                     const std::string& sourceName) {
    if (options.brickSize < 2 || options.brickSize > 512)
        throw std::invalid_argument("brick size must be between 2 and 512 cells, not " +
                                    std::to_string(options.brickSize));
    if (options.compressionLevel < ZSTD_minCLevel() || options.compressionLevel > ZSTD_maxCLevel())
        throw std::invalid_argument("zstd level must be between " +
                                    std::to_string(ZSTD_minCLevel()) + " and " +
                                    std::to_string(ZSTD_maxCLevel()));
    for (int a = 0; a < 3; ++a)
        if (info.dims[a] < 2)
            throwIoError(sourceName, "every axis needs at least 2 samples to hold cells");
    requireVolumeDims(sourceName, info.dims);
    // Readers refuse these; a source that did not would make a store that cannot be opened.
    if (const std::string problem = directionProblem(info.direction); !problem.empty())
        throwIoError(sourceName, problem);
    if (!info.hasOrientation && info.direction != glm::dmat3(1.0))
        throw std::invalid_argument(sourceName + ": a direction matrix without an orientation");
    const BrickLayout layout(info.dims, options.brickSize);
    if (const std::string problem = brickLayoutProblem(layout); !problem.empty())
        throwIoError(sourceName, problem);
    const int most = levelsUntilOneBrick(layout) - 1;
    if (options.coarseLevels != StoreWriteOptions::kLevelsUntilOneBrick &&
        (options.coarseLevels < 0 || options.coarseLevels > most))
        throw std::invalid_argument("--levels " + std::to_string(options.coarseLevels) + ": " +
                                    sourceName + " in bricks of " + std::to_string(options.brickSize) +
                                    " cells has at most " + std::to_string(most) +
                                    " coarser levels (the coarsest is then one brick)");
}

// A coarser level being made: its slices as they are filtered from the level below, and the
// next of its layers of bricks to encode.
struct LevelInProgress {
    BrickLevel level;
    SliceRing ring;
    int64_t nextSlice = 0;
    int64_t nextLayer = 0;
};

// The last slice layer `bk` of `layout` needs.
int64_t lastSliceOfLayer(const BrickLayout& layout, int64_t bk) {
    return std::min(layout.firstSample(bk) + layout.side() - 1, layout.dims[2] - 1);
}

}  // namespace

StoreWriteSummary writeBrickStore(SliceReader& source, const std::string& outPath,
                                  const StoreWriteOptions& options, const ProgressFn& progress) {
    const auto start = std::chrono::steady_clock::now();
    VolumeInfo info = source.info();
    validateOptions(info, options, source.name());
    info.direction = normalizedColumns(info.direction);  // the store holds unit columns
    const BrickLayout layout(info.dims, options.brickSize);
    const size_t sampleBytes = scalarSize(info.type);
    const int B = options.brickSize;
    const int levelCount = options.coarseLevels == StoreWriteOptions::kLevelsUntilOneBrick
                               ? levelsUntilOneBrick(layout)
                               : options.coarseLevels + 1;
    const std::vector<BrickLevel> levels = brickLevels(info, B, levelCount);

    AtomicOutputFile out(outPath, options.overwrite, source.files());
    uint64_t fileEnd = kStoreHeaderBytes;  // the header is written last, at offset 0

    auto mapRing = [&](SliceRing& ring, const Dims3& dims, int64_t slots) {
        ring.sliceBytes = size_t(dims[0] * dims[1]) * sampleBytes;
        ring.slots = std::min<int64_t>(slots, dims[2]);
        const uint64_t ringBytes = checkedMul(uint64_t(ring.slots), uint64_t(ring.sliceBytes));
        if (ringBytes > SIZE_MAX || !ring.map(size_t(ringBytes)))
            throwIoError(source.name(), "converting it needs " + std::to_string(ringBytes >> 20) +
                                            " MiB for " + std::to_string(ring.slots) + " slices of " +
                                            std::to_string(dims[0]) + " x " + std::to_string(dims[1]) +
                                            " samples, more memory than the process may allocate");
    };
    SliceRing ring;
    mapRing(ring, info.dims, 2 * int64_t(B) + kGhostBefore + kGhostAfter);
    std::vector<LevelInProgress> coarse(size_t(levelCount - 1));
    for (size_t l = 0; l < coarse.size(); ++l) {
        coarse[l].level = levels[l + 1];
        mapRing(coarse[l].ring, coarse[l].level.volume.dims, int64_t(B) + kGhostBefore + kGhostAfter);
    }

    const int64_t totalBricks = levels.back().firstBrick + levels.back().layout.brickCount();
    std::vector<BrickEntry> entries(static_cast<size_t>(totalBricks));
    std::vector<SubBlockCode> subBlocks(entries.size() * kSubBlocksPerBrick);
    // Bricks are encoded a few rows at a time and written in the order they are made: enough
    // work for every core, while the compressed bytes held stay a few MB whatever the layer's
    // size. Two groups: one is encoded while the other is written, so neither core waits on
    // the copy into the page cache. One write is in flight at a time.
    std::vector<StoredBrick> groups[2];
    int64_t groupIndex = 0;
    std::future<void> pendingWrite;
    tbb::enumerable_thread_specific<BrickScratch> scratch;

    // Encodes and writes layer `bk` of a level, its slices in `window`.
    auto emitLayer = [&](const SliceRing& window, const BrickLevel& level, int64_t bk) {
        const BrickLayout& lay = level.layout;
        const int64_t rowBricks = lay.brickCounts[0];
        const int64_t groupRows = std::max<int64_t>(1, 128 / rowBricks);
        for (int64_t bj = 0; bj < lay.brickCounts[1]; bj += groupRows, ++groupIndex) {
            std::vector<StoredBrick>& group = groups[groupIndex % 2];
            const int64_t firstId = lay.brickId(0, bj, bk);
            const int64_t count = std::min(groupRows, lay.brickCounts[1] - bj) * rowBricks;
            if (group.size() < size_t(count)) group.resize(size_t(count));
            const bool countSamples = level.firstBrick == 0;
            tbb::parallel_for(tbb::blocked_range<int64_t>(0, count, 2), [&](const auto& r) {
                BrickScratch& s = scratch.local();
                for (int64_t b = r.begin(); b != r.end(); ++b)
                    encodeBrick(window, lay, info.type, options, firstId + b, countSamples, s, group[size_t(b)]);
            });
            const uint64_t groupStart = fileEnd;
            for (int64_t b = 0; b < count; ++b) {
                StoredBrick& sb = group[size_t(b)];
                sb.entry.offset = fileEnd;
                fileEnd = alignUp(fileEnd + sb.bytes.size());
                const int64_t id = level.firstBrick + firstId + b;
                entries[size_t(id)] = sb.entry;
                std::copy(std::begin(sb.subBlocks), std::end(sb.subBlocks),
                          subBlocks.begin() + id * kSubBlocksPerBrick);
            }
            if (pendingWrite.valid()) pendingWrite.get();
            pendingWrite = std::async(std::launch::async, [&out, &group, count, groupStart, fileEnd] {
                for (int64_t b = 0; b < count; ++b)
                    out.writeAt(group[size_t(b)].bytes.data(), group[size_t(b)].bytes.size(),
                                group[size_t(b)].entry.offset);
                out.startWriteback(groupStart, fileEnd - groupStart);
            });
        }
    };

    // Level `l` (>= 1) makes every slice it can now that the level below holds slices up to
    // `below`; each new slice goes on to the next level, and each layer it completes is encoded.
    std::function<void(size_t, int64_t)> feed = [&](size_t l, int64_t below) {
        LevelInProgress& level = coarse[l - 1];
        const SliceRing& fineRing = l == 1 ? ring : coarse[l - 2].ring;
        const Dims3& fine = levels[l - 1].volume.dims;
        const Dims3& dims = level.level.volume.dims;
        while (level.nextSlice < dims[2] &&
               (2 * level.nextSlice + 1 <= below || below == fine[2] - 1)) {
            const int64_t z = level.nextSlice;
            auto fineSlice = [&](int64_t s) { return fineRing.slice(std::clamp<int64_t>(s, 0, fine[2] - 1)); };
            visitScalarType(info.type, [&](auto zero) {
                using T = decltype(zero);
                const T* planes[3] = {reinterpret_cast<const T*>(fineSlice(2 * z - 1)),
                                      reinterpret_cast<const T*>(fineSlice(2 * z)),
                                      reinterpret_cast<const T*>(fineSlice(2 * z + 1))};
                T* dst = reinterpret_cast<T*>(level.ring.slice(z));
                tbb::parallel_for(tbb::blocked_range<int64_t>(0, dims[1], 16), [&](const auto& r) {
                    downsampleRows<T>(planes[0], planes[1], planes[2], fine, dims, r.begin(), r.end(), dst);
                });
            });
            ++level.nextSlice;
            if (l < coarse.size()) feed(l + 1, z);
            const BrickLayout& lay = level.level.layout;
            // (Two layers can end on the volume's last slice.)
            while (level.nextLayer < lay.brickCounts[2] && lastSliceOfLayer(lay, level.nextLayer) == z)
                emitLayer(level.ring, level.level, level.nextLayer++);
        }
    };

    readSlices(source, ring, 0, lastSliceOfLayer(layout, 0) + 1);
    int64_t fedSlices = 0;  // level-0 slices handed to level 1
    for (int64_t bk = 0; bk < layout.brickCounts[2]; ++bk) {
        throwIfInterrupted(source.name());  // also without a progress callback
        std::future<void> prefetch;
        if (bk + 1 < layout.brickCounts[2])
            prefetch = std::async(std::launch::async, readSlices, std::ref(source), std::ref(ring),
                                  lastSliceOfLayer(layout, bk) + 1, lastSliceOfLayer(layout, bk + 1) + 1);
        emitLayer(ring, levels[0], bk);
        // The slices the next layer does not read again are final for level 1 now; the reader
        // fills other slots meanwhile.
        if (!coarse.empty()) {
            const int64_t last = lastSliceOfLayer(layout, bk);
            for (; fedSlices <= last; ++fedSlices) feed(1, fedSlices);
        }
        if (prefetch.valid()) prefetch.get();
        if (progress) progress(double(bk + 1) / double(layout.brickCounts[2]));
    }
    if (pendingWrite.valid()) pendingWrite.get();
    for (const LevelInProgress& level : coarse)
        if (level.nextLayer != level.level.layout.brickCounts[2])
            throw std::logic_error("store writer: a level of detail was not completed");
    source.finish();

    StoreHeader header;
    header.volume = info;
    header.brickSize = B;
    header.levelCount = levelCount;
    header.compression = options.compression;
    header.filter = filterFor(info.type, options);
    header.valueMin = std::numeric_limits<double>::max();
    header.valueMax = std::numeric_limits<double>::lowest();
    uint64_t level0Bytes = 0;
    for (size_t id = 0; id < entries.size(); ++id) {
        const BrickEntry& e = entries[id];
        header.storedBrickBytes += e.storedBytes;
        if (int64_t(id) >= layout.brickCount()) continue;  // coarse samples lie within level 0's
        level0Bytes += e.storedBytes;
        header.valueMin = std::min(header.valueMin, double(e.minValue));
        header.valueMax = std::max(header.valueMax, double(e.maxValue));
    }

    // The histogram spans the finite samples (docs/store-format.md): -inf counts in the first
    // bin, +inf in the last, NaN nowhere. Where the volume's range is infinite, the finite end
    // is the edge of the extreme finite fine bin.
    std::vector<uint64_t> fine(kFineBins, 0);
    for (const BrickScratch& s : scratch)
        for (size_t key = 0; key < size_t(kFineBins); ++key)
            fine[key] += s.histogramEven[key] + s.histogramOdd[key];
    ValueHistogram histogram;
    histogram.lo = std::isfinite(header.valueMin) ? header.valueMin : 0.0;
    histogram.hi = std::isfinite(header.valueMax) ? header.valueMax : 0.0;
    bool anyFinite = false;
    for (uint32_t key = 0; key < uint32_t(kFineBins); ++key) {
        if (!fine[key] || fineKeyKind(info.type, key) != KeyKind::Finite) continue;
        if (!std::isfinite(header.valueMin) && !anyFinite) histogram.lo = fineKeyValue(info.type, key, 0);
        if (!std::isfinite(header.valueMax)) histogram.hi = fineKeyValue(info.type, key, 2);
        anyFinite = true;
    }
    if (!anyFinite) histogram.lo = histogram.hi = 0.0;
    const double binScale =
        histogram.hi > histogram.lo ? kHistogramBins / (histogram.hi - histogram.lo) : 0.0;
    for (uint32_t key = 0; key < uint32_t(kFineBins); ++key) {
        if (!fine[key]) continue;
        int bin = 0;
        switch (fineKeyKind(info.type, key)) {
            case KeyKind::NaN: continue;  // NaN samples have no place on the value axis
            case KeyKind::NegativeInfinity: bin = 0; break;
            case KeyKind::PositiveInfinity: bin = kHistogramBins - 1; break;
            case KeyKind::Finite: {
                const double v = std::clamp(fineKeyValue(info.type, key), histogram.lo, histogram.hi);
                bin = std::min(kHistogramBins - 1, int((v - histogram.lo) * binScale));
                break;
            }
        }
        histogram.counts[size_t(bin)] += fine[key];
    }

    header.indexOffset = fileEnd;
    const std::vector<unsigned char> index = store_format::encodeIndex(entries, histogram, subBlocks);
    header.indexBytes = index.size();
    out.writeAt(index.data(), index.size(), fileEnd);
    const auto headerBytes = store_format::encodeHeader(header);
    out.writeAt(headerBytes.data(), headerBytes.size(), 0);
    out.commit();

    StoreWriteSummary summary;
    summary.bricks = totalBricks;
    summary.levels = levelCount;
    summary.level0Bytes = level0Bytes;
    summary.coarseBytes = header.storedBrickBytes - level0Bytes;
    summary.inputBytes = info.byteSize();
    summary.fileBytes = fileEnd + index.size();
    summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return summary;
}

}  // namespace vdiso
