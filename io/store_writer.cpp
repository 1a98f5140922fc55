#include "io/store_writer.h"

#include <algorithm>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>

#include <tbb/blocked_range2d.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <zstd.h>

#include "io/atomic_output.h"
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
inline uint32_t fineKey(float v) {
    const uint32_t u = std::bit_cast<uint32_t>(v);
    return ((u & 0x80000000u) ? ~u : (u | 0x80000000u)) >> 16;
}

double fineKeyValue(ScalarType type, uint32_t key) {
    switch (type) {
        case ScalarType::U8:
        case ScalarType::U16: return double(key);
        case ScalarType::I16: return double(int32_t(key) - 32768);
        case ScalarType::F32: break;
    }
    const uint32_t k = (key << 16) | 0x8000u;  // the middle of the bin
    const uint32_t u = (k & 0x80000000u) ? (k & 0x7fffffffu) : ~k;
    return double(std::bit_cast<float>(u));
}

// The samples of the current layer of bricks: slot s holds global slice zFirst + s.
struct SlabWindow {
    std::vector<unsigned char> bytes;
    int64_t zFirst = 0;
    size_t sliceBytes = 0;
    const unsigned char* slice(int64_t z) const { return bytes.data() + size_t(z - zFirst) * sliceBytes; }
    unsigned char* slice(int64_t z) { return bytes.data() + size_t(z - zFirst) * sliceBytes; }
};

// Copies brick (bi, bj) of the window's layer into dst, (B+3)^3 samples, clamping at borders.
template <class T>
void gatherBrick(const SlabWindow& window, const BrickLayout& layout, int64_t bi, int64_t bj,
                 int64_t bk, T* dst) {
    const int side = layout.side();
    const int64_t nx = layout.dims[0];
    const int64_t x0 = layout.firstSample(bi);
    const bool rowInside = x0 >= 0 && x0 + side <= nx;
    for (int lz = 0; lz < side; ++lz) {
        const int64_t z = layout.clampSample(2, layout.firstSample(bk) + lz);
        const T* slice = reinterpret_cast<const T*>(window.slice(z));
        for (int ly = 0; ly < side; ++ly) {
            const int64_t y = layout.clampSample(1, layout.firstSample(bj) + ly);
            const T* row = slice + y * nx;
            if (rowInside) {
                std::memcpy(dst, row + x0, side * sizeof(T));
            } else {
                for (int lx = 0; lx < side; ++lx) dst[lx] = row[layout.clampSample(0, x0 + lx)];
            }
            dst += side;
        }
    }
}

// Min and max over the samples of the brick's cells, and the histogram of the samples the
// brick owns (each volume sample is owned by exactly one brick).
template <class T>
void measureBrick(const T* brick, const BrickLayout& layout, const Dims3& coord, float& minValue,
                  float& maxValue, uint64_t* fineHistogram) {
    const int side = layout.side();
    int cells[3], owned[3];
    for (int a = 0; a < 3; ++a) {
        cells[a] = layout.cellsOnAxis(a, coord[a]);
        owned[a] = layout.ownedSamplesOnAxis(a, coord[a]);
    }
    T lo = std::numeric_limits<T>::max(), hi = std::numeric_limits<T>::lowest();
    for (int lz = kGhostBefore; lz <= kGhostBefore + cells[2]; ++lz) {
        for (int ly = kGhostBefore; ly <= kGhostBefore + cells[1]; ++ly) {
            const T* row = brick + (size_t(lz) * side + ly) * side;
            const bool ownedRow = lz < kGhostBefore + owned[2] && ly < kGhostBefore + owned[1];
            const int ownedEnd = ownedRow ? kGhostBefore + owned[0] : kGhostBefore;
            for (int lx = kGhostBefore; lx < ownedEnd; ++lx) {
                lo = std::min(lo, row[lx]);
                hi = std::max(hi, row[lx]);
                ++fineHistogram[fineKey(row[lx])];
            }
            for (int lx = ownedEnd; lx <= kGhostBefore + cells[0]; ++lx) {
                lo = std::min(lo, row[lx]);
                hi = std::max(hi, row[lx]);
            }
        }
    }
    minValue = float(lo);
    maxValue = float(hi);
}

struct BrickScratch {
    std::vector<unsigned char> raw;
    std::vector<uint64_t> fineHistogram = std::vector<uint64_t>(kFineBins, 0);
    ZSTD_CCtx* cctx = nullptr;
    BrickScratch() = default;
    BrickScratch(const BrickScratch&) = delete;
    ~BrickScratch() { ZSTD_freeCCtx(cctx); }
};

struct StoredBrick {
    std::vector<unsigned char> bytes;
    BrickEntry entry;
};

void encodeBrick(const SlabWindow& window, const BrickLayout& layout, ScalarType type,
                 const StoreWriteOptions& options, int64_t id, BrickScratch& scratch,
                 StoredBrick& out) {
    const Dims3 coord = layout.brickCoord(id);
    const size_t rawBytes = size_t(layout.samplesPerBrick()) * scalarSize(type);
    scratch.raw.resize(rawBytes);
    visitScalarType(type, [&](auto zero) {
        using T = decltype(zero);
        T* brick = reinterpret_cast<T*>(scratch.raw.data());
        gatherBrick<T>(window, layout, coord[0], coord[1], coord[2], brick);
        measureBrick<T>(brick, layout, coord, out.entry.minValue, out.entry.maxValue,
                        scratch.fineHistogram.data());
    });
    out.entry.compressed = false;
    if (options.compression == Compression::Zstd) {
        if (!scratch.cctx) scratch.cctx = ZSTD_createCCtx();
        out.bytes.resize(ZSTD_compressBound(rawBytes));
        const size_t n = ZSTD_compressCCtx(scratch.cctx, out.bytes.data(), out.bytes.size(),
                                           scratch.raw.data(), rawBytes, options.compressionLevel);
        if (ZSTD_isError(n)) throw std::runtime_error(std::string("zstd: ") + ZSTD_getErrorName(n));
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
}

}  // namespace

StoreWriteSummary writeBrickStore(SliceReader& source, const std::string& outPath,
                                  const StoreWriteOptions& options, const ProgressFn& progress) {
    const auto start = std::chrono::steady_clock::now();
    const VolumeInfo info = source.info();
    validateOptions(info, options, source.name());
    const BrickLayout layout(info.dims, options.brickSize);
    const size_t sampleBytes = scalarSize(info.type);
    const int B = options.brickSize;

    AtomicOutputFile out(outPath, options.overwrite);
    uint64_t fileEnd = kStoreHeaderBytes;  // the header is written last, at offset 0

    SlabWindow window;
    window.sliceBytes = size_t(info.sliceSamples()) * sampleBytes;
    window.bytes.resize(size_t(layout.side()) * window.sliceBytes);
    window.zFirst = -kGhostBefore;
    int64_t slicesRead = 0;

    std::vector<BrickEntry> entries(size_t(layout.brickCount()));
    const int64_t layerBricks = layout.brickCounts[0] * layout.brickCounts[1];
    std::vector<StoredBrick> layer(static_cast<size_t>(layerBricks));
    tbb::enumerable_thread_specific<BrickScratch> scratch;

    for (int64_t bk = 0; bk < layout.brickCounts[2]; ++bk) {
        // Slide the window: the last kGhostBefore + kGhostAfter slices of the previous layer
        // are the first ones of this layer.
        const int64_t zFirst = layout.firstSample(bk);
        if (bk > 0) {
            const size_t keep = size_t(kGhostBefore + kGhostAfter) * window.sliceBytes;
            std::memmove(window.bytes.data(), window.bytes.data() + size_t(B) * window.sliceBytes, keep);
            window.zFirst = zFirst;
        }
        const int64_t zNeed = std::min(zFirst + layout.side() - 1, info.dims[2] - 1);
        if (zNeed >= slicesRead) {
            source.read(window.slice(slicesRead), zNeed - slicesRead + 1);
            slicesRead = zNeed + 1;
        }

        const int64_t firstId = bk * layerBricks;
        tbb::parallel_for(tbb::blocked_range<int64_t>(0, layerBricks, 4), [&](const auto& r) {
            BrickScratch& s = scratch.local();
            for (int64_t b = r.begin(); b != r.end(); ++b)
                encodeBrick(window, layout, info.type, options, firstId + b, s, layer[size_t(b)]);
        });
        for (int64_t b = 0; b < layerBricks; ++b) {
            StoredBrick& sb = layer[size_t(b)];
            sb.entry.offset = fileEnd;
            out.writeAt(sb.bytes.data(), sb.bytes.size(), fileEnd);
            fileEnd = alignUp(fileEnd + sb.bytes.size());
            entries[size_t(firstId + b)] = sb.entry;
        }
        if (progress) progress(double(bk + 1) / double(layout.brickCounts[2]));
    }
    source.finish();

    StoreHeader header;
    header.volume = info;
    header.brickSize = B;
    header.compression = options.compression;
    header.valueMin = std::numeric_limits<double>::max();
    header.valueMax = std::numeric_limits<double>::lowest();
    for (const BrickEntry& e : entries) {
        header.valueMin = std::min(header.valueMin, double(e.minValue));
        header.valueMax = std::max(header.valueMax, double(e.maxValue));
        header.storedBrickBytes += e.storedBytes;
    }

    ValueHistogram histogram;
    histogram.lo = header.valueMin;
    histogram.hi = header.valueMax;
    const double binScale = header.valueMax > header.valueMin
                                ? kHistogramBins / (header.valueMax - header.valueMin)
                                : 0.0;
    for (const BrickScratch& s : scratch)
        for (int key = 0; key < kFineBins; ++key) {
            if (!s.fineHistogram[size_t(key)]) continue;
            const double value = fineKeyValue(info.type, uint32_t(key));
            if (std::isnan(value)) continue;  // NaN samples have no place on the value axis
            const double v = std::clamp(value, header.valueMin, header.valueMax);
            const int bin = std::min(kHistogramBins - 1, int((v - header.valueMin) * binScale));
            histogram.counts[size_t(bin)] += s.fineHistogram[size_t(key)];
        }

    header.indexOffset = fileEnd;
    const std::vector<unsigned char> index = store_format::encodeIndex(entries, histogram);
    header.indexBytes = index.size();
    out.writeAt(index.data(), index.size(), fileEnd);
    const auto headerBytes = store_format::encodeHeader(header);
    out.writeAt(headerBytes.data(), headerBytes.size(), 0);
    out.commit();

    StoreWriteSummary summary;
    summary.bricks = layout.brickCount();
    summary.inputBytes = info.byteSize();
    summary.fileBytes = fileEnd + index.size();
    summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return summary;
}

}  // namespace vdiso
