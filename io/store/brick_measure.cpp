#include "io/store/brick_measure.h"

#include <algorithm>
#include <limits>

#include "core/kernel/iso.h"

namespace vdiso {

namespace {

// The sub-blocks along an axis of `cells` cells (C each) whose corners include corner t: the
// one it starts or lies in, and the one before when t is the border they share.
inline int blocksOfCorner(int t, int cells, int C, int out[2]) {
    int n = 0;
    const int b = t / C;
    if (t > 0 && t % C == 0) out[n++] = b - 1;
    if (b * C < cells) out[n++] = b;
    return n;
}

constexpr int kRowsAhead = 4;

template <class T>
void measure(const SliceWindow& window, const BrickLayout& layout, const Dims3& coord, BrickEntry& entry,
             SubBlockCode codes[kSubBlocksPerBrick], uint64_t* histogramEven, uint64_t* histogramOdd) {
    constexpr int N = kSubBlocksPerAxis;
    const int B = layout.brickSize, C = subBlockCells(B);
    int cells[3], owned[3], blocks[3];
    for (int a = 0; a < 3; ++a) {
        cells[a] = layout.cellsOnAxis(a, coord[a]);
        owned[a] = layout.ownedSamplesOnAxis(a, coord[a]);
        blocks[a] = (cells[a] + C - 1) / C;
    }
    using Limits = std::numeric_limits<T>;
    constexpr T kHighest = Limits::has_infinity ? Limits::infinity() : Limits::max();
    constexpr T kLowest = Limits::has_infinity ? -Limits::infinity() : Limits::lowest();
    T lo[N][N][N], hi[N][N][N];  // [c][b][a]
    std::fill_n(&lo[0][0][0], N * N * N, kHighest);
    std::fill_n(&hi[0][0][0], N * N * N, kLowest);
    const int64_t nx = layout.dims[0], ny = layout.dims[1];
    const int64_t x0 = coord[0] * B, y0 = coord[1] * B, z0 = coord[2] * B;
    for (int lz = 0; lz <= cells[2]; ++lz) {
        const T* slice = reinterpret_cast<const T*>(window.slice(z0 + lz));
        int zb[2];
        const int zn = blocksOfCorner(lz, cells[2], C, zb);
        const T* nextSlice = lz < cells[2] ? reinterpret_cast<const T*>(window.slice(z0 + lz + 1)) : slice;
        for (int ly = 0; ly <= cells[1]; ++ly) {
            const T* row = slice + (y0 + ly) * nx + x0;
            // Rows lie a slice's width apart: each is a cache miss the hardware does not see
            // coming. The one a few rows on (or at the next slice's start) is asked for now.
            const T* ahead = ly + kRowsAhead <= cells[1]
                                 ? row + kRowsAhead * nx
                                 : nextSlice + std::min(y0 + ly + kRowsAhead - cells[1] - 1, ny - 1) * nx + x0;
            __builtin_prefetch(ahead);
            __builtin_prefetch(ahead + cells[0]);
            T segmentLo[N], segmentHi[N];
            for (int a = 0; a < blocks[0]; ++a) {
                const int first = a * C, last = std::min(first + C, cells[0]);
                T l = rangeValue(row[first]), h = l;
                for (int i = first + 1; i <= last; ++i) {
                    const T v = rangeValue(row[i]);
                    l = v < l ? v : l;
                    h = v > h ? v : h;
                }
                segmentLo[a] = l;
                segmentHi[a] = h;
            }
            int yb[2];
            const int yn = blocksOfCorner(ly, cells[1], C, yb);
            for (int k = 0; k < zn; ++k)
                for (int j = 0; j < yn; ++j)
                    for (int a = 0; a < blocks[0]; ++a) {
                        T& l = lo[zb[k]][yb[j]][a];
                        T& h = hi[zb[k]][yb[j]][a];
                        l = segmentLo[a] < l ? segmentLo[a] : l;
                        h = segmentHi[a] > h ? segmentHi[a] : h;
                    }
            if (!histogramEven || lz >= owned[2] || ly >= owned[1]) continue;
            int i = 0;
            for (; i + 1 < owned[0]; i += 2) {
                ++histogramEven[fineKey(row[i])];
                ++histogramOdd[fineKey(row[i + 1])];
            }
            if (i < owned[0]) ++histogramEven[fineKey(row[i])];
        }
    }
    T l = kHighest, h = kLowest;
    for (int c = 0; c < blocks[2]; ++c)
        for (int b = 0; b < blocks[1]; ++b)
            for (int a = 0; a < blocks[0]; ++a) {
                l = std::min(l, lo[c][b][a]);
                h = std::max(h, hi[c][b][a]);
            }
    entry.minValue = float(l);
    entry.maxValue = float(h);
    const BrickRange range{entry.minValue, entry.maxValue};
    for (int c = 0; c < N; ++c)
        for (int b = 0; b < N; ++b)
            for (int a = 0; a < N; ++a)
                codes[(c * N + b) * N + a] = a < blocks[0] && b < blocks[1] && c < blocks[2]
                                                 ? encodeSubBlockRange(double(lo[c][b][a]), double(hi[c][b][a]), range)
                                                 : SubBlockCode{};
}

}  // namespace

void measureBrickInSlices(ScalarType type, const SliceWindow& window, const BrickLayout& layout, const Dims3& coord,
                          BrickEntry& entry, SubBlockCode codes[kSubBlocksPerBrick], uint64_t* histogramEven,
                          uint64_t* histogramOdd) {
    visitScalarType(type, [&](auto zero) {
        measure<decltype(zero)>(window, layout, coord, entry, codes, histogramEven, histogramOdd);
    });
}

}  // namespace vdiso
