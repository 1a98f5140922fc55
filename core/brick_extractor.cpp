#include "core/brick_extractor.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <type_traits>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include "core/iso.h"
#include "core/mc_tables.h"

namespace vdiso {

namespace {

// Comparisons against the isovalue in the samples' own type: for integers, s > iso exactly
// when s > floor(iso), so the cell loop compares integers.
template <class T>
struct IsoThreshold {
    using Compare = std::conditional_t<std::is_integral_v<T>, int64_t, double>;
    Compare value;
    explicit IsoThreshold(double iso) {
        if constexpr (std::is_integral_v<T>)
            value = int64_t(std::clamp(std::floor(iso), -1e18, 1e18));
        else
            value = iso;
    }
    bool above(T s) const { return Compare(s) > value; }
};

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
            // NaN samples count as -inf (core/iso.h).
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

// The cell loop for one brick of sample type T.
template <class T>
struct BrickKernel {
    BrickExtractor& x;
    const T* s;          // the brick's (B+3)^3 samples
    int side;            // B + 3
    int cells[3];        // cells of this brick per axis
    int64_t corner0[3];  // global coordinates of the brick's first cell corner
    double iso;
    IsoThreshold<T> threshold;
    TriangleMesh& mesh;
    EdgeVertexMap& seams;

    BrickKernel(BrickExtractor& extractor, int64_t id, const void* samples, double isovalue,
                TriangleMesh& out, EdgeVertexMap& seamMap)
        : x(extractor), s(static_cast<const T*>(samples)), side(extractor.mLayout.side()),
          iso(isovalue), threshold(isovalue), mesh(out), seams(seamMap) {
        if (x.mBrickFirstVertex == BrickExtractor::kNoFirstVertex) {
            x.mBrickFirstVertex = out.nextVertex();
            if (x.mBrickFirstVertex < x.mVerticesMade) {  // another mesh: its numbers restart
                std::fill(x.mEdgeVertex.begin(), x.mEdgeVertex.end(), 0u);
                x.mVerticesMade = 0;
            }
        }
        const Dims3 c = x.mLayout.brickCoord(id);
        for (int a = 0; a < 3; ++a) {
            cells[a] = x.mLayout.cellsOnAxis(a, c[a]);
            corner0[a] = c[a] * x.mLayout.brickSize;
        }
    }

    // Index of local cell corner (cx, cy, cz) in the sample array (ghost offset included).
    size_t sampleIndex(int cx, int cy, int cz) const {
        return BrickLayout::cornerIndex(side, cx, cy, cz);
    }

    void metaCellBox(int m, int lo[3], int hi[3]) const {
        const int M = x.mMetaCellSize, n = x.mMetaPerAxis;
        const int mc[3] = {m % n, (m / n) % n, m / (n * n)};
        for (int a = 0; a < 3; ++a) {
            lo[a] = std::min(mc[a] * M, cells[a]);
            hi[a] = std::min(lo[a] + M, cells[a]);
        }
    }

    glm::dvec3 gradientAt(size_t i) const {
        const glm::dvec3& h = x.mVolume.spacing;
        const size_t sy = size_t(side), sz = size_t(side) * side;
        return {(double(s[i + 1]) - double(s[i - 1])) / (2 * h.x),
                (double(s[i + sy]) - double(s[i - sy])) / (2 * h.y),
                (double(s[i + sz]) - double(s[i - sz])) / (2 * h.z)};
    }

    // The vertex on edge `e` of cell (cx, cy, cz), computed the first time it is asked for.
    // Without `withNormal` its normal is left zero, for ensureNormal() to fill once the cell
    // is known to be kept: the view-dependent traversal drops about half the vertices it
    // makes, and the normal is most of a vertex's cost.
    uint32_t edgeVertex(int cx, int cy, int cz, int e, bool withNormal) {
        const int8_t* o = kCornerOffset[kEdgeCorners[e][0]];
        const int px = cx + o[0], py = cy + o[1], pz = cz + o[2], axis = mcEdgeAxis(e);
        const int n = x.mLayout.brickSize + 1;
        const size_t local = ((size_t(pz) * n + py) * n + px) * 3 + axis;
        uint32_t& slot = x.mEdgeVertex[local];
        if (slot > x.mBrickFirstVertex) return slot - 1;

        // Edges on the brick's faces are shared with a neighbour brick: weld through the map.
        const int p[3] = {px, py, pz};
        bool onFace = false;
        for (int a = 0; a < 3; ++a)
            if (a != axis && (p[a] == 0 || p[a] == cells[a])) onFace = true;
        uint64_t key = 0;
        if (onFace) {
            const Dims3& d = x.mVolume.dims;
            key = ((uint64_t(corner0[2] + pz) * uint64_t(d[1]) + uint64_t(corner0[1] + py)) *
                       uint64_t(d[0]) + uint64_t(corner0[0] + px)) * 3 + uint64_t(axis);
            const uint32_t v = seams.find(key);
            if (v != UINT32_MAX) return v;
        }

        const size_t i0 = sampleIndex(px, py, pz);
        const size_t step = axis == 0 ? 1 : axis == 1 ? size_t(side) : size_t(side) * side;
        const double s0 = double(s[i0]), s1 = double(s[i0 + step]);
        const double t = crossingFraction(s0, s1, iso);
        glm::dvec3 local3(px, py, pz);
        local3[axis] += t;
        const glm::dvec3 position =
            x.mVolume.origin + (glm::dvec3(corner0[0], corner0[1], corner0[2]) + local3) *
                                   x.mVolume.spacing;
        const uint32_t v = mesh.nextVertex();
        mesh.positions.push_back(glm::vec3(position));
        mesh.normals.push_back(withNormal ? edgeNormal(i0, step, axis) : glm::vec3(0.0f));
        slot = v + 1;
        x.mVerticesMade = v + 1;
        if (onFace) seams.insert(key, v);
        return v;
    }

    // Minus the gradient at the crossing of the edge from sample i0 to i0 + step (along
    // `axis`), interpolated between central differences at its ends, normalized. Never zero:
    // a flat gradient (clamped border, plateau) takes the edge's own direction, so a zero
    // normal means "not computed yet". Any brick holding the edge gives the same normal (the
    // ghost samples cover the differences), so a welded vertex may get it from either.
    glm::vec3 edgeNormal(size_t i0, size_t step, int axis) const {
        const double s0 = double(s[i0]), s1 = double(s[i0 + step]);
        const double t = crossingFraction(s0, s1, iso);
        const glm::dvec3 gradient = glm::mix(gradientAt(i0), gradientAt(i0 + step), t);
        const double length = glm::length(gradient);
        glm::dvec3 normal(0.0);
        // A gradient through a non-finite sample is inf or NaN: the edge's direction then.
        if (length > 0 && std::isfinite(length))
            normal = -gradient / length;
        else
            normal[axis] = s1 > s0 ? -1.0 : 1.0;
        return glm::vec3(normal);
    }

    void ensureNormal(uint32_t v, int cx, int cy, int cz, int e) {
        glm::vec3& normal = mesh.normals[v - mesh.firstVertex];
        if (normal != glm::vec3(0.0f)) return;
        const int8_t* o = kCornerOffset[kEdgeCorners[e][0]];
        const int axis = mcEdgeAxis(e);
        const size_t step = axis == 0 ? 1 : axis == 1 ? size_t(side) : size_t(side) * side;
        normal = edgeNormal(sampleIndex(cx + o[0], cy + o[1], cz + o[2]), step, axis);
    }

    void extractMetaCell(int m, PolygonCallback onPolygon = nullptr, void* context = nullptr,
                         CellFilter keepCell = nullptr, const glm::dvec3* eyeCell = nullptr) {
        int lo[3], hi[3];
        metaCellBox(m, lo, hi);
        // Cell order per axis: ascending, or with an eye (in this brick's cell coordinates)
        // nearest the eye first. Nested z, y, x, each ordered so, is a front-to-back order
        // for a grid: a cell hiding another is no farther from the eye on any axis.
        int order[3][kMaxMetaCellSize];
        for (int a = 0; a < 3; ++a) {
            const int n = hi[a] - lo[a];
            for (int k = 0; k < n; ++k) order[a][k] = lo[a] + k;
            if (eyeCell)
                std::sort(order[a], order[a] + n, [&](int i, int j) {
                    return std::abs(i + 0.5 - (*eyeCell)[a]) < std::abs(j + 0.5 - (*eyeCell)[a]);
                });
        }
        // Above bits of the meta-cell's corner samples, one word per corner row (bit i: corner
        // lo[0] + i). A cell's case is then four 2-bit fields, and a row of cells that the
        // surface misses is passed over with a few word operations instead of 8 comparisons
        // per cell: most cells of an active meta-cell are empty.
        const int nx = hi[0] - lo[0], ny = hi[1] - lo[1], nz = hi[2] - lo[2];
        uint64_t above[kMaxMetaCellSize + 1][kMaxMetaCellSize + 1];
        for (int z = 0; z <= nz; ++z)
            for (int y = 0; y <= ny; ++y) {
                const T* row = s + sampleIndex(lo[0], lo[1] + y, lo[2] + z);
                uint64_t bits = 0;
                for (int i = 0; i <= nx; ++i) bits |= uint64_t(threshold.above(row[i])) << i;
                above[z][y] = bits;
            }
        const uint64_t cellBits = (uint64_t(1) << nx) - 1;
        KernelCounters& counters = x.mCounters;
        counters.cellsVisited += int64_t(nx) * ny * nz;
        for (int iz = 0; iz < nz; ++iz)
            for (int iy = 0; iy < ny; ++iy) {
                const int cz = order[2][iz], cy = order[1][iy];
                const int rz = cz - lo[2], ry = cy - lo[1];
                const uint64_t r00 = above[rz][ry], r10 = above[rz][ry + 1];
                const uint64_t r01 = above[rz + 1][ry], r11 = above[rz + 1][ry + 1];
                const uint64_t any = r00 | r10 | r01 | r11, all = r00 & r10 & r01 & r11;
                const uint64_t mixed = (any | any >> 1) & ~(all & all >> 1) & cellBits;
                if (mixed == 0) continue;
                for (int ix = 0; ix < nx; ++ix) {
                    const int cx = order[0][ix], rx = cx - lo[0];
                    if (!(mixed >> rx & 1)) continue;
                    // Corner k is (k & 1, k >> 1 & 1, k >> 2): rows (y, z) = 00, 10, 01, 11.
                    const int caseIndex = int(r00 >> rx & 3) | int(r10 >> rx & 3) << 2 |
                                          int(r01 >> rx & 3) << 4 | int(r11 >> rx & 3) << 6;
                    if (keepCell && !keepCell(context, corner0[0] + cx, corner0[1] + cy, corner0[2] + cz))
                        continue;
                    ++counters.cellsActive;
                    const McPolygonCase& pc = mcPolygonCase(caseIndex);
                    uint32_t outline[kMcEdgeCount];  // every polygon's, one after another
                    bool wanted = onPolygon == nullptr;
                    int outlineLength = 0;
                    for (int p = 0, at = 0; p < pc.polygonCount; at += pc.vertexCount[p++]) {
                        for (int k = 0; k < pc.vertexCount[p]; ++k)
                            outline[at + k] = edgeVertex(cx, cy, cz, pc.edges[at + k], !onPolygon);
                        if (onPolygon) wanted |= onPolygon(context, outline + at, pc.vertexCount[p]);
                        outlineLength = at + pc.vertexCount[p];
                    }
                    if (!wanted) continue;
                    if (onPolygon)
                        for (int k = 0; k < outlineLength; ++k) ensureNormal(outline[k], cx, cy, cz, pc.edges[k]);
                    for (int p = 0, at = 0; p < pc.polygonCount; at += pc.vertexCount[p++])
                        for (int k = 2; k < pc.vertexCount[p]; ++k)
                            mesh.indices.insert(mesh.indices.end(),
                                                {outline[at], outline[at + k - 1], outline[at + k]});
                }
            }
    }
};

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
    metaCellRanges(id, samples, mRanges);
}

bool BrickExtractor::firstHit(const glm::dvec3& origin, const glm::dvec3& direction,
                              double tEnter, double tExit, double iso, glm::vec3& position,
                              glm::vec3& normal) const {
    bool hit = false;
    visitScalarType(mVolume.type, [&](auto zero) {
        using T = decltype(zero);
        const T* s = static_cast<const T*>(mCurrentSamples);
        const int side = mLayout.side();
        const Dims3 c = mLayout.brickCoord(mCurrentBrick);
        // Sample-array coordinates of a world point (ghost offset included).
        auto toLocal = [&](const glm::dvec3& w) {
            glm::dvec3 l;
            for (int a = 0; a < 3; ++a)
                l[a] = (w[a] - mVolume.origin[a]) / mVolume.spacing[a] -
                       double(c[a] * mLayout.brickSize) + kGhostBefore;
            return l;
        };
        auto field = [&](const glm::dvec3& l) {
            int i[3];
            double f[3];
            for (int a = 0; a < 3; ++a) {
                const double x = std::clamp(l[a], 0.0, double(side - 1) - 1e-9);
                i[a] = std::min(int(x), side - 2);
                f[a] = x - i[a];
            }
            const size_t base = (size_t(i[2]) * side + size_t(i[1])) * side + size_t(i[0]);
            const size_t dy = size_t(side), dz = size_t(side) * side;
            auto at = [&](size_t o) { return double(s[base + o]); };
            const double x00 = at(0) + f[0] * (at(1) - at(0));
            const double x10 = at(dy) + f[0] * (at(dy + 1) - at(dy));
            const double x01 = at(dz) + f[0] * (at(dz + 1) - at(dz));
            const double x11 = at(dz + dy) + f[0] * (at(dz + dy + 1) - at(dz + dy));
            const double y0 = x00 + f[1] * (x10 - x00), y1 = x01 + f[1] * (x11 - x01);
            return y0 + f[2] * (y1 - y0);
        };
        const double samples = glm::length(toLocal(origin + direction * tExit) -
                                           toLocal(origin + direction * tEnter));
        const int steps = std::max(2, int(std::ceil(samples * 4)));
        double tPrevious = tEnter;
        double previous = field(toLocal(origin + direction * tEnter));
        for (int k = 1; k <= steps && !hit; ++k) {
            const double t = tEnter + (tExit - tEnter) * k / steps;
            const double value = field(toLocal(origin + direction * t));
            if (isAbove(previous, iso) != isAbove(value, iso)) {
                const double u = crossingFraction(previous, value, iso);
                const glm::dvec3 w = origin + direction * (tPrevious + u * (t - tPrevious));
                const glm::dvec3 l = toLocal(w);
                // Central-difference gradients at the cell's corners, interpolated: the
                // estimator of the triangles' vertex normals, so the point shades as they do.
                int i[3];
                double f[3];
                for (int a = 0; a < 3; ++a) {
                    const double x = std::clamp(l[a], 1.0, double(side - 2) - 1e-9);
                    i[a] = std::min(int(x), side - 3);
                    f[a] = x - i[a];
                }
                glm::dvec3 gradient(0.0);
                for (int corner = 0; corner < 8; ++corner) {
                    const int o[3] = {corner & 1, (corner >> 1) & 1, (corner >> 2) & 1};
                    const size_t at = (size_t(i[2] + o[2]) * side + size_t(i[1] + o[1])) * side +
                                      size_t(i[0] + o[0]);
                    const size_t dy = size_t(side), dz = size_t(side) * side;
                    const glm::dvec3 g((double(s[at + 1]) - double(s[at - 1])) / mVolume.spacing.x,
                                       (double(s[at + dy]) - double(s[at - dy])) / mVolume.spacing.y,
                                       (double(s[at + dz]) - double(s[at - dz])) / mVolume.spacing.z);
                    const double weight = (o[0] ? f[0] : 1 - f[0]) * (o[1] ? f[1] : 1 - f[1]) *
                                          (o[2] ? f[2] : 1 - f[2]);
                    gradient += weight * g;
                }
                const double length = glm::length(gradient);
                position = glm::vec3(w);
                normal = length > 0 ? glm::vec3(-gradient / length) : glm::vec3(0.0f);
                hit = true;
            }
            previous = value;
            tPrevious = t;
        }
    });
    return hit;
}

void BrickExtractor::extractMetaCell(uint32_t metaCell, double iso, TriangleMesh& mesh,
                                     EdgeVertexMap& seams, PolygonCallback onPolygon,
                                     void* context, CellFilter keepCell,
                                     const glm::dvec3* eyeWorld) {
    visitScalarType(mVolume.type, [&](auto zero) {
        using T = decltype(zero);
        BrickKernel<T> k(*this, mCurrentBrick, mCurrentSamples, iso, mesh, seams);
        ++mCounters.metaCellsActive;
        glm::dvec3 eyeCell;
        if (eyeWorld)
            for (int a = 0; a < 3; ++a)
                eyeCell[a] = ((*eyeWorld)[a] - mVolume.origin[a]) / mVolume.spacing[a] -
                             double(k.corner0[a]);
        k.extractMetaCell(int(metaCell), onPolygon, context, keepCell, eyeWorld ? &eyeCell : nullptr);
    });
}

void BrickExtractor::extractBrick(int64_t id, const void* samples, double iso, TriangleMesh& mesh,
                                  EdgeVertexMap& seams) {
    forgetBrickVertices();
    metaCellRanges(id, samples, mRanges);
    visitScalarType(mVolume.type, [&](auto zero) {
        using T = decltype(zero);
        BrickKernel<T> k(*this, id, samples, iso, mesh, seams);
        for (int m = 0; m < metaCellsPerBrick(); ++m) {
            const BrickRange r = mRanges[size_t(m)];
            ++mCounters.metaCellsTested;
            if (!rangeHoldsIso(r.minValue, r.maxValue, iso)) continue;
            ++mCounters.metaCellsActive;
            k.extractMetaCell(m);
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
        for (uint32_t m : metaCells) {
            ++mCounters.metaCellsActive;
            k.extractMetaCell(int(m));
        }
    });
}

}  // namespace vdiso
