#include "core/kernel/brick_extractor.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <type_traits>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include "core/kernel/brick_kernel.h"
#include "core/kernel/iso.h"

namespace vdiso {

namespace {

// Ranges of all meta-cells of one brick ((B+3)^3 samples, `cells` cells per axis) at once,
// separably, whole rows at a time: first, for each z-slab of meta-cells, the elementwise
// min/max over the slab's planes (rows contiguous in x, so these loops vectorise); then over
// each y-run of those rows; last over the x-runs of what is left, a small array. Each sample
// is read about once. Meta-cells beyond the brick's cells (n per axis in all) get an empty
// range.
template <class T>
void computeMetaCellRanges(const T* s, int side, const int cells[3], int M, int n,
                           std::vector<BrickRange>& out) {
    thread_local std::vector<T> lo, hi;
    const int rowX = cells[0] + 1, rowsY = cells[1] + 1;
    const size_t slab = size_t(rowsY) * rowX;  // pass 1: n slabs of rowsY rows
    const size_t plane = size_t(n) * rowX;     // pass 2: n x n rows, after the slabs
    lo.resize(size_t(n) * slab + size_t(n) * plane);
    hi.resize(lo.size());
    T* lo2 = lo.data() + size_t(n) * slab;
    T* hi2 = hi.data() + size_t(n) * slab;
    const int slabs = (cells[2] + M - 1) / M, runsY = (cells[1] + M - 1) / M;
    for (int mz = 0; mz < slabs; ++mz) {
        const int z0 = mz * M, z1 = std::min(z0 + M, cells[2]);
        for (int y = 0; y < rowsY; ++y) {
            T* l = lo.data() + size_t(mz) * slab + size_t(y) * rowX;
            T* h = hi.data() + size_t(mz) * slab + size_t(y) * rowX;
            const T* first = s + BrickLayout::cornerIndex(side, 0, y, z0);
            // NaN samples count as -inf (core/kernel/iso.h).
            for (int i = 0; i < rowX; ++i) l[i] = h[i] = rangeValue(first[i]);
            for (int z = z0 + 1; z <= z1; ++z) {
                const T* row = s + BrickLayout::cornerIndex(side, 0, y, z);
                for (int i = 0; i < rowX; ++i) {
                    const T v = rangeValue(row[i]);
                    l[i] = v < l[i] ? v : l[i];
                    h[i] = v > h[i] ? v : h[i];
                }
            }
        }
        for (int my = 0; my < runsY; ++my) {
            const int y0 = my * M, y1 = std::min(y0 + M, cells[1]);
            T* l = lo2 + (size_t(mz) * n + my) * rowX;
            T* h = hi2 + (size_t(mz) * n + my) * rowX;
            const T* firstLo = lo.data() + size_t(mz) * slab + size_t(y0) * rowX;
            const T* firstHi = hi.data() + size_t(mz) * slab + size_t(y0) * rowX;
            std::copy(firstLo, firstLo + rowX, l);
            std::copy(firstHi, firstHi + rowX, h);
            for (int y = y0 + 1; y <= y1; ++y) {
                const T* rowLo = lo.data() + size_t(mz) * slab + size_t(y) * rowX;
                const T* rowHi = hi.data() + size_t(mz) * slab + size_t(y) * rowX;
                for (int i = 0; i < rowX; ++i) {
                    l[i] = rowLo[i] < l[i] ? rowLo[i] : l[i];
                    h[i] = rowHi[i] > h[i] ? rowHi[i] : h[i];
                }
            }
        }
    }
    out.resize(size_t(n) * n * n);
    for (int mz = 0; mz < n; ++mz)
        for (int my = 0; my < n; ++my)
            for (int mx = 0; mx < n; ++mx) {
                BrickRange& r = out[(size_t(mz) * n + my) * n + mx];
                const int x0 = mx * M;
                if (x0 >= cells[0] || my >= runsY || mz >= slabs) {
                    r = {std::numeric_limits<float>::max(), std::numeric_limits<float>::lowest()};
                    continue;
                }
                const int x1 = std::min(x0 + M, cells[0]);
                const T* l = lo2 + (size_t(mz) * n + my) * rowX;
                const T* h = hi2 + (size_t(mz) * n + my) * rowX;
                T a = l[x0], b = h[x0];
                for (int i = x0 + 1; i <= x1; ++i) {
                    a = l[i] < a ? l[i] : a;
                    b = h[i] > b ? h[i] : b;
                }
                r = {float(a), float(b)};
            }
}

}  // namespace

BrickExtractor::BrickExtractor(const VolumeInfo& volume, const BrickLayout& layout,
                               int metaCellSize)
    : mVolume(volume), mLayout(layout), mMetaCellSize(std::clamp(metaCellSize, 1, kMaxMetaCellSize)) {
    mMetaPerAxis = (layout.brickSize + mMetaCellSize - 1) / mMetaCellSize;
    const size_t corners = size_t(layout.brickSize + 1);
    mEdgeVertex.resize(corners * corners * corners * 3);
}

void BrickExtractor::metaCellRanges(int64_t id, const void* samples, std::vector<BrickRange>& out) {
    const Dims3 c = mLayout.brickCoord(id);
    const int cells[3] = {mLayout.cellsOnAxis(0, c[0]), mLayout.cellsOnAxis(1, c[1]),
                          mLayout.cellsOnAxis(2, c[2])};
    visitScalarType(mVolume.type, [&](auto zero) {
        using T = decltype(zero);
        computeMetaCellRanges(static_cast<const T*>(samples), mLayout.side(), cells,
                              mMetaCellSize, mMetaPerAxis, out);
    });
}

void BrickExtractor::forgetBrickVertices() { mBrickFirstVertex = kNoFirstVertex; }

void BrickExtractor::beginBrick(int64_t id, const void* samples) {
    mCurrentBrick = id;
    mCurrentSamples = samples;
    forgetBrickVertices();
    mRangesCurrent = false;
}

const std::vector<BrickRange>& BrickExtractor::currentRanges() {
    if (!mRangesCurrent) metaCellRanges(mCurrentBrick, mCurrentSamples, mRanges);
    mRangesCurrent = true;
    return mRanges;
}

void BrickExtractor::extractBrick(int64_t id, const void* samples, double iso, TriangleMesh& mesh,
                                  EdgeVertexMap& seams) {
    forgetBrickVertices();
    mRangesCurrent = false;
    metaCellRanges(id, samples, mRanges);
    visitScalarType(mVolume.type, [&](auto zero) {
        using T = decltype(zero);
        BrickKernel<T> k(*this, id, samples, iso, mesh, seams);
        AllCells all;
        for (int m = 0; m < metaCellsPerBrick(); ++m) {
            const BrickRange r = mRanges[size_t(m)];
            ++mCounters.metaCellsTested;
            if (!rangeHoldsIso(r.minValue, r.maxValue, iso)) continue;
            k.extractMetaCell(m, all);
        }
    });
}

void BrickExtractor::extractMetaCells(int64_t id, const void* samples, double iso,
                                      std::span<const uint32_t> metaCells, TriangleMesh& mesh,
                                      EdgeVertexMap& seams) {
    forgetBrickVertices();
    visitScalarType(mVolume.type, [&](auto zero) {
        using T = decltype(zero);
        BrickKernel<T> k(*this, id, samples, iso, mesh, seams);
        AllCells all;
        for (uint32_t m : metaCells) {
            k.extractMetaCell(int(m), all);
        }
    });
}

}  // namespace vdiso
