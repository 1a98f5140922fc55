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
// separably: first, for each z-slab of meta-cells, the elementwise min/max over the slab's
// planes, each plane whole (ghost samples too: one long loop that vectorises, where a loop per
// row of 33 samples spent more on its set-up than on the samples); then over each y-run of that
// plane's corner rows; last over the x-runs of what is left, a small array. Each sample is read
// about once. Meta-cells beyond the brick's cells (n per axis in all) get an empty range.
template <class T>
void computeMetaCellRanges(const T* s, int side, const int cells[3], int M, int n,
                           std::vector<BrickRange>& out) {
    thread_local std::vector<T> slabLo, slabHi, lo, hi;
    const int rowX = cells[0] + 1;
    const size_t plane = size_t(side) * size_t(side);
    const size_t rows = size_t(n) * rowX;  // pass 2: n x n rows of rowX
    slabLo.resize(plane);
    slabHi.resize(plane);
    lo.resize(size_t(n) * rows);
    hi.resize(lo.size());
    T* lo2 = lo.data();
    T* hi2 = hi.data();
    const int slabs = (cells[2] + M - 1) / M, runsY = (cells[1] + M - 1) / M;
    for (int mz = 0; mz < slabs; ++mz) {
        const int z0 = mz * M, z1 = std::min(z0 + M, cells[2]);
        {
            T* __restrict l = slabLo.data();
            T* __restrict h = slabHi.data();
            const T* __restrict first = s + size_t(z0 + kGhostBefore) * plane;  // corner plane z0, whole
            // NaN samples count as -inf (core/kernel/iso.h).
            for (size_t i = 0; i < plane; ++i) l[i] = h[i] = rangeValue(first[i]);
            for (int z = z0 + 1; z <= z1; ++z) {
                const T* __restrict p = first + size_t(z - z0) * plane;
                for (size_t i = 0; i < plane; ++i) {
                    const T v = rangeValue(p[i]);
                    l[i] = v < l[i] ? v : l[i];
                    h[i] = v > h[i] ? v : h[i];
                }
            }
        }
        // Corner row y of the slab, in slabLo/slabHi (laid out as a plane of samples).
        auto rowAt = [&](const std::vector<T>& v, int y) {
            return v.data() + size_t(y + kGhostBefore) * size_t(side) + size_t(kGhostBefore);
        };
        for (int my = 0; my < runsY; ++my) {
            const int y0 = my * M, y1 = std::min(y0 + M, cells[1]);
            T* l = lo2 + (size_t(mz) * n + my) * rowX;
            T* h = hi2 + (size_t(mz) * n + my) * rowX;
            std::copy(rowAt(slabLo, y0), rowAt(slabLo, y0) + rowX, l);
            std::copy(rowAt(slabHi, y0), rowAt(slabHi, y0) + rowX, h);
            for (int y = y0 + 1; y <= y1; ++y) {
                const T* rowLo = rowAt(slabLo, y);
                const T* rowHi = rowAt(slabHi, y);
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
                               int metaCellSize, bool trilinear)
    : mVolume(volume), mGradientScale(0.5 / volume.spacing), mLayout(layout), mMetaCellSize(std::clamp(metaCellSize, 1, kMaxMetaCellSize)),
      mTrilinear(trilinear) {
    mMetaPerAxis = (layout.brickSize + mMetaCellSize - 1) / mMetaCellSize;
    const size_t corners = size_t(layout.brickSize + 1);
    mEdgeVertex.resize(corners * corners * corners * 3);
    mEdgeSeen.resize((mEdgeVertex.size() + 63) / 64);
    if (wholeBricks()) mLayerVertex.resize(BrickKernel<uint8_t>::layerSlots(layout.brickSize));
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

// The meta-cells of the current brick that a full extraction visits: the listed ones, or
// with none listed every one whose range holds iso (mRanges, computed here).
template <class F>
void BrickExtractor::forEachActiveMetaCell(int64_t id, const void* samples, double iso,
                                           std::span<const uint32_t> metaCells, F&& f) {
    if (!metaCells.empty()) {
        for (uint32_t m : metaCells) f(int(m));
        return;
    }
    mRangesCurrent = false;
    metaCellRanges(id, samples, mRanges);
    for (int m = 0; m < metaCellsPerBrick(); ++m) {
        const BrickRange r = mRanges[size_t(m)];
        ++mCounters.metaCellsTested;
        if (rangeHoldsIso(r.minValue, r.maxValue, iso)) f(m);
    }
}

template <class Mesh>
void BrickExtractor::extractInto(int64_t id, const void* samples, double iso,
                                 std::span<const uint32_t> metaCells, Mesh& mesh, EdgeVertexMap& seams) {
    forgetBrickVertices();
    visitScalarType(mVolume.type, [&](auto zero) {
        using T = decltype(zero);
        BrickKernel<T, Mesh> k(*this, id, samples, iso, mesh, seams);
        if (metaCells.empty() && wholeBricks()) {
            mEdgeSeen.resize(std::max(mEdgeSeen.size(), size_t(k.cells[1] + 1) * size_t(k.cells[2] + 1)));
            k.emitBrick(mEdgeSeen.data(), mLayerVertex.data());
            return;
        }
        forEachActiveMetaCell(id, samples, iso, metaCells, [&](int m) { k.extractMetaCell(m); });
    });
}

BrickCount BrickExtractor::countInPlace(int64_t id, const void* samples, double iso,
                                        std::span<const uint32_t> metaCells, const EdgeOwnership& ownership,
                                        std::vector<uint32_t>* activeMetaCells) {
    // Listed already, or not needed: a whole brick is emitted at once (extractInto).
    if (!metaCells.empty() || wholeBricks()) activeMetaCells = nullptr;
    BrickCount count;
    const KernelCounters counters = mCounters;  // the emission counts what it visits
    // The kernel's output, which the count does not touch; a first vertex already set, so that
    // making the kernel leaves the vertex slots alone.
    thread_local TriangleMesh none;
    thread_local EdgeVertexMap noSeams;
    mBrickFirstVertex = 0;
    visitScalarType(mVolume.type, [&](auto zero) {
        using T = decltype(zero);
        const BrickKernel<T> k(*this, id, samples, iso, none, noSeams);
        if (wholeBricks()) {  // the whole brick at once, a word per corner row
            mEdgeSeen.resize(std::max(mEdgeSeen.size(), size_t(k.cells[1] + 1) * size_t(k.cells[2] + 1)));
            count = k.countBrick(mEdgeSeen.data(), ownership);
            return;
        }
        std::fill(mEdgeSeen.begin(), mEdgeSeen.end(), uint64_t(0));
        forEachActiveMetaCell(id, samples, iso, metaCells, [&](int m) {
            k.countMetaCell(m, mEdgeSeen.data(), ownership, count);
            if (activeMetaCells) activeMetaCells->push_back(uint32_t(m));
        });
    });
    forgetBrickVertices();
    mCounters = counters;
    return count;
}

void BrickExtractor::extractBrick(int64_t id, const void* samples, double iso, TriangleMesh& mesh,
                                  EdgeVertexMap& seams) {
    extractInto(id, samples, iso, {}, mesh, seams);
}

void BrickExtractor::extractMetaCells(int64_t id, const void* samples, double iso,
                                      std::span<const uint32_t> metaCells, TriangleMesh& mesh,
                                      EdgeVertexMap& seams) {
    if (!metaCells.empty()) extractInto(id, samples, iso, metaCells, mesh, seams);
}

void BrickExtractor::extractInPlace(int64_t id, const void* samples, double iso,
                                    std::span<const uint32_t> metaCells, PlacedMesh& mesh,
                                    EdgeVertexMap& seams) {
    extractInto(id, samples, iso, metaCells, mesh, seams);
}

}  // namespace vdiso
