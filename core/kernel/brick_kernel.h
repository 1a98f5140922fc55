// The marching-cubes cell loop over one brick of sample type T (core/kernel/brick_extractor.h tells
// what it computes). A kernel is made once per brick, after BrickExtractor::beginBrick or by
// the extractor's own loops; it borrows the extractor's scratch, so one kernel per extractor
// at a time. extractMetaCell makes every crossed cell of a meta-cell (the full extractions);
// the view takes a meta-cell through core/kernel/shown_meta_cell.h, which tests its cells and
// polygons before it makes their vertices.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <type_traits>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include "core/kernel/brick_extractor.h"
#include "core/kernel/edge_vertex_map.h"
#include "core/kernel/iso.h"
#include "core/kernel/mc_tables.h"
#include "core/kernel/placed_mesh.h"
#include "core/kernel/row_classify.h"
#include "core/kernel/trilinear_cell.h"

namespace vdiso {

// A row of cells between four corner rows of above bits (rows (y, z), (y + 1, z), (y, z + 1),
// (y + 1, z + 1); bit i: corner x = i): the cells with corners on both sides (bit i: cell x = i,
// of `cellBits`), and cell rx's marching-cubes case (corner k is (k & 1, k >> 1 & 1, k >> 2)).
struct CellRow {
    uint64_t r00, r10, r01, r11;
    uint64_t crossed(uint64_t cellBits) const {
        const uint64_t any = r00 | r10 | r01 | r11, all = r00 & r10 & r01 & r11;
        return (any | any >> 1) & ~(all & all >> 1) & cellBits;
    }
    int caseOf(int rx) const {
        return int(r00 >> rx & 3) | int(r10 >> rx & 3) << 2 | int(r01 >> rx & 3) << 4 | int(r11 >> rx & 3) << 6;
    }
};

// `Mesh`: a TriangleMesh appended to, or a PlacedMesh (core/kernel/placed_mesh.h) written in
// place, where a brick makes only the vertices it owns.
template <class T, class Mesh>
struct BrickKernel {
    static constexpr bool kPlaced = std::is_same_v<Mesh, PlacedMesh>;
    BrickExtractor& x;
    const T* s;          // the brick's (B+3)^3 samples
    int side;            // B + 3
    int cells[3];        // cells of this brick per axis
    int64_t corner0[3];  // global coordinates of the brick's first cell corner
    double iso;
    IsoThreshold<T> threshold;
    Mesh& mesh;
    EdgeVertexMap& seams;
    int64_t brick;

    BrickKernel(BrickExtractor& extractor, int64_t id, const void* samples, double isovalue,
                Mesh& out, EdgeVertexMap& seamMap)
        : x(extractor), s(static_cast<const T*>(samples)), side(extractor.mLayout.side()),
          iso(isovalue), threshold(isovalue), mesh(out), seams(seamMap), brick(id) {
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

    const VolumeInfo& volume() const { return x.mVolume; }
    KernelCounters& counters() { return x.mCounters; }

    // The eye (world) in this brick's cell coordinates, for extractMetaCell's cell order.
    glm::dvec3 eyeInCells(const glm::dvec3& eyeWorld) const {
        glm::dvec3 e;
        for (int a = 0; a < 3; ++a)
            e[a] = (eyeWorld[a] - x.mVolume.origin[a]) / x.mVolume.spacing[a] - double(corner0[a]);
        return e;
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

    // The central-difference gradient at sample i (multiplied by 1 / (2 h): a division each
    // was a third of a vertex's arithmetic).
    glm::dvec3 gradientAt(size_t i) const {
        const glm::dvec3& g = x.mGradientScale;
        const size_t sy = size_t(side), sz = size_t(side) * side;
        return {(double(s[i + 1]) - double(s[i - 1])) * g.x, (double(s[i + sy]) - double(s[i - sy])) * g.y,
                (double(s[i + sz]) - double(s[i - sz])) * g.z};
    }

    // The vertex on edge `e` of cell (cx, cy, cz), with its normal, made the first time it is
    // asked for. `local`: the edge's slot in x.mEdgeVertex, cornerSlot(cx, cy, cz) + the
    // edgeSlots() offset of e.
    uint32_t edgeVertex(size_t local, int cx, int cy, int cz, int e) {
        uint32_t& slot = x.mEdgeVertex[local];
        if (slot > x.mBrickFirstVertex) return slot - 1;
        const int8_t* o = kCornerOffset[kEdgeCorners[e][0]];
        return makeEdgeVertex(cx + o[0], cy + o[1], cz + o[2], mcEdgeAxis(e), &slot);
    }
    // The first of the three vertex slots (x, y and z edges) of local corner (cx, cy, cz).
    size_t cornerSlot(int cx, int cy, int cz) const {
        const size_t n = size_t(x.mLayout.brickSize) + 1;
        return ((size_t(cz) * n + size_t(cy)) * n + size_t(cx)) * 3;
    }
    // Edge e of a cell has its slot at cornerSlot(the cell) + slots[e]: the index arithmetic
    // once a meta-cell instead of once an edge (kept out of the kernel's members: a larger
    // kernel changed what GCC inlines into emitBrick, 11 M instructions on a full extraction).
    void edgeSlots(uint32_t (&slots)[kMcEdgeCount]) const {
        for (int e = 0; e < kMcEdgeCount; ++e) {
            const int8_t* o = kCornerOffset[kEdgeCorners[e][0]];
            slots[e] = uint32_t(cornerSlot(o[0], o[1], o[2])) + uint32_t(mcEdgeAxis(e));
        }
    }

    // Cell (cx, cy, cz)'s corner samples minus the isovalue, in corner order.
    void cornerValues(int cx, int cy, int cz, double (&f)[8]) const {
        const T* c = s + sampleIndex(cx, cy, cz);
        for (int k = 0; k < 8; ++k)
            f[k] = double(c[sampleIndex(kCornerOffset[k][0], kCornerOffset[k][1], kCornerOffset[k][2]) - sampleIndex(0, 0, 0)]) - iso;
    }
    // Cell (cx, cy, cz) of case `caseIndex` cut as its trilinear interpolant (core/kernel/
    // trilinear_cell.h) into `out`, when the extractor asks for that and the case can be cut
    // otherwise than the tables cut it; else false.
    bool trilinearCut(int caseIndex, int cx, int cy, int cz, TrilinearCell& out) const {
        if (!x.mTrilinear || !trilinearCases()[size_t(caseIndex)]) return false;
        double f[8];
        cornerValues(cx, cy, cz, f);
        trilinearCell(f, out);
        return true;
    }
    static const std::array<bool, kMcCaseCount>& trilinearCases() {
        static const std::array<bool, kMcCaseCount> cases = [] {
            std::array<bool, kMcCaseCount> c{};
            for (int k = 0; k < kMcCaseCount; ++k) c[size_t(k)] = trilinearMayDiffer(k);
            return c;
        }();
        return cases;
    }
    // What cell (cx, cy, cz) of case `caseIndex` adds: its triangles to count.triangles and the
    // vertices a trilinear cut makes inside it to count.vertices.
    void countCell(int caseIndex, int cx, int cy, int cz, BrickCount& count) const {
        TrilinearCell cut;
        if (!trilinearCut(caseIndex, cx, cy, cz, cut)) {
            count.triangles += mcTriangleCase(caseIndex).triangleCount;
            return;
        }
        count.triangles += cut.triangleCount;
        count.vertices += cut.centreCount;
    }
    // The vertices a trilinear cut of cell (cx, cy, cz) makes inside it, made now (position and
    // the interpolant's normal there, as the edges' normals point); ids[k]: centre k's number.
    void makeCentres(const TrilinearCell& cut, int cx, int cy, int cz, uint32_t* ids) {
        double f[8];
        cornerValues(cx, cy, cz, f);
        const glm::dvec3& h = x.mVolume.spacing;
        for (int k = 0; k < cut.centreCount; ++k) {
            const double* p = cut.centres[k];
            double g[3];
            trilinearGradient(f, p, g);
            const glm::dvec3 gradient(g[0] / h.x, g[1] / h.y, g[2] / h.z);
            const double length = glm::length(gradient);
            const glm::dvec3 normal = length > 0 && std::isfinite(length) ? -gradient / length : glm::dvec3(0, 0, 1);
            const glm::dvec3 local(double(corner0[0] + cx) + p[0], double(corner0[1] + cy) + p[1], double(corner0[2] + cz) + p[2]);
            ids[k] = mesh.nextVertex();
            mesh.addVertex(glm::vec3(x.mVolume.origin + local * h), glm::vec3(normal));
        }
    }

    // The vertex on the edge from local corner (px, py, pz) along `axis`, asked for once per brick: an
    // edge on a face the brick shares with a neighbour is welded through the seam map (and, in
    // a PlacedMesh, gets a placeholder when a brick in another chunk owns it); else it is made
    // now, and its number + 1 kept in `slot` when one is given.
    uint32_t makeEdgeVertex(int px, int py, int pz, int axis, uint32_t* slot) {
        const int p[3] = {px, py, pz};
        bool onFace = false;
        for (int a = 0; a < 3; ++a)
            if (a != axis && (p[a] == 0 || p[a] == cells[a])) onFace = true;
        uint64_t key = 0;
        if (onFace) {
            const Dims3& d = x.mVolume.dims;
            key = edgeKey(d, corner0[0] + p[0], corner0[1] + p[1], corner0[2] + p[2], axis);
            const uint32_t v = seams.find(key);
            if (v != UINT32_MAX) return v;
        }
        bool owned = true;
        if constexpr (kPlaced) owned = !onFace || mesh.ownership->owns(brick, corner0, p, axis);

        const size_t i0 = sampleIndex(p[0], p[1], p[2]);
        const size_t step = axis == 0 ? 1 : axis == 1 ? size_t(side) : size_t(side) * side;
        const double s0 = double(s[i0]), s1 = double(s[i0 + step]);
        const double t = crossingFraction(s0, s1, iso);
        glm::dvec3 local3(p[0], p[1], p[2]);
        local3[axis] += t;
        const glm::dvec3 position =
            x.mVolume.origin + (glm::dvec3(corner0[0], corner0[1], corner0[2]) + local3) *
                                   x.mVolume.spacing;
        const glm::vec3 normal = edgeNormal(i0, step, axis, t);
        if constexpr (kPlaced)
            if (!owned) {  // its owner, in another chunk, makes it: a placeholder until then
                const uint32_t placeholder = mesh.addPlaceholder(key, glm::vec3(position), normal);
                seams.insert(key, placeholder);
                return placeholder;
            }
        const uint32_t v = mesh.nextVertex();
        mesh.addVertex(glm::vec3(position), normal);
        if (slot) *slot = v + 1;
        x.mVerticesMade = v + 1;
        if (onFace) seams.insert(key, v);
        return v;
    }

    // Minus the gradient at the crossing of the edge from sample i0 to i0 + step (along
    // `axis`), interpolated between central differences at its ends, normalized. Never zero:
    // a flat gradient (clamped border, plateau) takes the edge's own direction. Any brick
    // holding the edge gives the same normal (the
    // ghost samples cover the differences), so a welded vertex may get it from either.
    glm::vec3 edgeNormal(size_t i0, size_t step, int axis) const {
        return edgeNormal(i0, step, axis, crossingFraction(double(s[i0]), double(s[i0 + step]), iso));
    }
    // The same, with the edge's crossing fraction t already known.
    glm::vec3 edgeNormal(size_t i0, size_t step, int axis, double t) const {
        const double s0 = double(s[i0]), s1 = double(s[i0 + step]);
        const glm::dvec3 gradient = glm::mix(gradientAt(i0), gradientAt(i0 + step), t);
        const double length = glm::length(gradient);
        glm::dvec3 normal(0.0);
        // A gradient through a non-finite sample is inf or NaN: the edge's direction then.
        if (length > 0 && std::isfinite(length))
            normal = gradient * (-1.0 / length);
        else
            normal[axis] = s1 > s0 ? -1.0 : 1.0;
        return glm::vec3(normal);
    }

    // Above bits of the corner samples of the cells lo..hi, one word per corner row (bit i:
    // corner lo[0] + i). A cell's case is then four 2-bit fields, and a row of cells that the
    // surface misses is passed over with a few word operations instead of 8 comparisons per
    // cell: most cells of an active meta-cell are empty.
    void classifyCorners(const int lo[3], const int hi[3], uint64_t (&above)[kMaxMetaCellSize + 1][kMaxMetaCellSize + 1]) const {
        const int nx = hi[0] - lo[0];
        for (int z = 0; z <= hi[2] - lo[2]; ++z)
            for (int y = 0; y <= hi[1] - lo[1]; ++y)
                above[z][y] = aboveBits(s + sampleIndex(lo[0], lo[1] + y, lo[2] + z), nx + 1, threshold);
    }

    // Above bits of every corner row of the brick, a word per row (bit i: corner x = i), row (y, z)
    // at rows[z * (cells[1] + 1) + y]. Rows of at most 64 corners: cells[0] < 64.
    void classifyBrick(uint64_t* rows) const {
        for (int z = 0; z <= cells[2]; ++z)
            for (int y = 0; y <= cells[1]; ++y)
                rows[size_t(z) * size_t(cells[1] + 1) + size_t(y)] = aboveBits(s + sampleIndex(0, y, z), cells[0] + 1, threshold);
    }

    // Every crossed cell of the brick, for a full extraction: what extractMetaCell(m)
    // makes over every meta-cell whose range holds iso, in another order, Flying Edges' way. The
    // brick is classified a word per corner row (classifyBrick, into `rows`); then layer by layer
    // of cells, the vertices of the crossed edges of its corner rows are made in row order (x
    // edges, y edges, then z edges between layers) into a small table of slots, `layerVertex`:
    // (kLayerSlots, two corner layers of x and y edges and one of z edges), and each crossed
    // cell's polygons are fanned from the slots of its edges. No vertex is looked for but on the
    // brick's faces (the seam map); nothing is touched but the samples, a few KB and the mesh.
    static constexpr size_t layerSlots(int brickSize) { return size_t(brickSize + 1) * size_t(brickSize + 1) * 5; }
    void emitBrick(uint64_t* rows, uint32_t* layerVertex) {
        const int nx = cells[0], ny = cells[1], nz = cells[2];
        const int M = x.mMetaCellSize, n = x.mMetaPerAxis;
        classifyBrick(rows);
        auto row = [&](int y, int z) { return rows[size_t(z) * size_t(ny + 1) + size_t(y)]; };
        const uint64_t cellBits = (uint64_t(1) << nx) - 1, cornerBits = cellBits | (uint64_t(1) << nx);
        // Slots: the x edge from corner (i, y) of a corner layer at xy[layer & 1][2 y w + i], its y
        // edge at xy[..][(2 y + 1) w + i]; the z edge from corner (i, y) of the current layer at
        // zv[y w + i].
        const size_t w = size_t(nx + 1), layer = 2 * w * size_t(ny + 1);
        uint32_t* const xy[2] = {layerVertex, layerVertex + layer};
        uint32_t* const zv = layerVertex + 2 * layer;
        auto makeRow = [&](uint64_t mask, int y, int z, int axis, uint32_t* slots) {
            for (; mask; mask &= mask - 1) {
                const int px = __builtin_ctzll(mask);
                slots[px] = makeEdgeVertex(px, y, z, axis, nullptr);
            }
        };
        // The seam map's slots of a row's edges on the brick's faces, asked for a layer ahead of
        // their lookups: the map outgrows the caches, and a lookup was a fifth of a vertex.
        const Dims3& dims = x.mVolume.dims;
        const uint64_t ends = 1 | uint64_t(1) << nx;
        auto prefetchRow = [&](uint64_t mask, int y, int z, int axis) {
            const bool faceRow = (axis != 1 && (y == 0 || y == ny)) || (axis != 2 && (z == 0 || z == nz));
            for (mask &= faceRow ? ~uint64_t(0) : axis == 0 ? 0 : ends; mask; mask &= mask - 1)
                seams.prefetch(edgeKey(dims, corner0[0] + __builtin_ctzll(mask), corner0[1] + y, corner0[2] + z, axis));
        };
        auto forLayer = [&](int z, auto&& f) {  // f(mask, y, axis, row offset) for corner layer z's x and y edges
            for (int y = 0; y <= ny; ++y) {
                const uint64_t r = row(y, z);
                f((r ^ r >> 1) & cellBits, y, 0, 2 * size_t(y) * w);
                if (y < ny) f((r ^ row(y + 1, z)) & cornerBits, y, 1, (2 * size_t(y) + 1) * w);
            }
        };
        auto makeLayer = [&](int z) {  // the x and y edges of corner layer z
            uint32_t* to = xy[z & 1];
            forLayer(z, [&](uint64_t mask, int y, int axis, size_t at) { makeRow(mask, y, z, axis, to + at); });
        };
        auto prefetchLayer = [&](int z) {  // what cell layer z makes: z edges, then corner layer z + 1's
            for (int y = 0; y <= ny; ++y) prefetchRow((row(y, z) ^ row(y, z + 1)) & cornerBits, y, z, 2);
            forLayer(z + 1, [&](uint64_t mask, int y, int axis, size_t) { prefetchRow(mask, y, z + 1, axis); });
        };
        uint64_t metaMask[64];  // the cells of meta-cell mx of a row
        for (int mx = 0; mx < n; ++mx) metaMask[mx] = ((uint64_t(1) << M) - 1) << (mx * M) & cellBits;
        KernelCounters& counters = x.mCounters;
        counters.metaCellsTested += int64_t(n) * n * n;
        counters.cellsVisited += int64_t(nx) * ny * nz;
        uint64_t metaRows[64 * 64];  // [mz * n + my]: bit mx set when that meta-cell is crossed
        std::fill_n(metaRows, size_t(n) * size_t(n), uint64_t(0));
        forLayer(0, [&](uint64_t mask, int y, int axis, size_t) { prefetchRow(mask, y, 0, axis); });
        prefetchLayer(0);
        makeLayer(0);
        for (int z = 0; z < nz; ++z) {
            if (z + 1 < nz) prefetchLayer(z + 1);  // a layer ahead
            for (int y = 0; y <= ny; ++y) makeRow((row(y, z) ^ row(y, z + 1)) & cornerBits, y, z, 2, zv + size_t(y) * w);
            makeLayer(z + 1);
            const uint32_t* lo = xy[z & 1];
            const uint32_t* hi = xy[(z + 1) & 1];
            for (int y = 0; y < ny; ++y) {
                const CellRow cellRow{row(y, z), row(y + 1, z), row(y, z + 1), row(y + 1, z + 1)};
                uint64_t mixed = cellRow.crossed(cellBits);
                if (mixed == 0) continue;
                const size_t xRow = 2 * size_t(y) * w, yRow = xRow + w, zRow = size_t(y) * w;
                // Edge e of cell i has its vertex at edgeSlot[e][i] (kEdgeCorners: its first corner).
                const uint32_t* const edgeSlot[kMcEdgeCount] = {
                    lo + xRow, lo + xRow + 2 * w, hi + xRow, hi + xRow + 2 * w,
                    lo + yRow, lo + yRow + 1, hi + yRow, hi + yRow + 1,
                    zv + zRow, zv + zRow + 1, zv + zRow + w, zv + zRow + w + 1};
                uint64_t meta = 0;
                for (int mx = 0; mx < n; ++mx) meta |= uint64_t((mixed & metaMask[mx]) != 0) << mx;
                for (; mixed; mixed &= mixed - 1) {
                    const int rx = __builtin_ctzll(mixed);
                    const int caseIndex = cellRow.caseOf(rx);
                    ++counters.cellsActive;
                    if (TrilinearCell cut; trilinearCut(caseIndex, rx, y, z, cut)) {
                        uint32_t centre[kTrilinearMaxCentres];
                        makeCentres(cut, rx, y, z, centre);
                        auto vertex = [&](int e) { return e < kMcEdgeCount ? edgeSlot[e][rx] : centre[e - kTrilinearCentre]; };
                        for (int t = 0; t < cut.triangleCount; ++t)
                            mesh.addTriangle(vertex(cut.edges[3 * t]), vertex(cut.edges[3 * t + 1]), vertex(cut.edges[3 * t + 2]));
                        continue;
                    }
                    const McPolygonCase& pc = mcPolygonCase(caseIndex);
                    for (int p = 0, at = 0; p < pc.polygonCount; at += pc.vertexCount[p++]) {
                        const uint32_t first = edgeSlot[pc.edges[at]][rx];
                        uint32_t last = edgeSlot[pc.edges[at + 1]][rx];
                        for (int k = 2; k < pc.vertexCount[p]; ++k) {
                            const uint32_t next = edgeSlot[pc.edges[at + k]][rx];
                            mesh.addTriangle(first, last, next);
                            last = next;
                        }
                    }
                }
                metaRows[size_t(z / M) * size_t(n) + size_t(y / M)] |= meta;
            }
        }
        for (int m = 0; m < n * n; ++m) counters.metaCellsActive += bitCount(metaRows[m]);
    }

    // What a full extraction of this brick writes into a PlacedMesh, from the classification
    // of the whole brick (the meta-cells whose ranges hold iso, or NOISE's exact list of them,
    // hold every cell the surface crosses, so they make the same): a word per corner row
    // (`rows`: (cells[1] + 1) * (cells[2] + 1) words), crossed edges counted by popcount, those
    // on a face shared with a lower brick asked one by one whether this brick owns them, and
    // each crossed cell's triangles from its case. Rows of at most 64 corners: cells[0] < 64:
    // the bricks emitBrick takes whole.
    BrickCount countBrick(uint64_t* rows, const EdgeOwnership& ownership) const {
        const int nx = cells[0], ny = cells[1], nz = cells[2];
        classifyBrick(rows);
        BrickCount count;
        const uint64_t cellBits = (uint64_t(1) << nx) - 1, cornerBits = cellBits | (uint64_t(1) << nx);
        const bool lower[3] = {corner0[0] > 0, corner0[1] > 0, corner0[2] > 0};
        // Crossed edges in `mask` (bit i: the edge from corner x = i) along `axis` from corner
        // row (y, z): owned unless on a lower face, where the owner is asked.
        auto addEdges = [&](uint64_t mask, int y, int z, int axis) {
            const bool faceRow = (axis != 1 && y == 0 && lower[1]) || (axis != 2 && z == 0 && lower[2]);
            if (!faceRow && !(axis != 0 && lower[0] && (mask & 1))) {
                count.vertices += bitCount(mask);
                return;
            }
            for (; mask; mask &= mask - 1) {
                const int p[3] = {__builtin_ctzll(mask), y, z};
                count.vertices += ownership.owns(brick, corner0, p, axis);
            }
        };
        auto row = [&](int y, int z) { return rows[size_t(z) * size_t(ny + 1) + size_t(y)]; };
        for (int z = 0; z <= nz; ++z)
            for (int y = 0; y <= ny; ++y) {
                const uint64_t r = row(y, z);
                addEdges((r ^ r >> 1) & cellBits, y, z, 0);
                if (y < ny) addEdges((r ^ row(y + 1, z)) & cornerBits, y, z, 1);
                if (z < nz) addEdges((r ^ row(y, z + 1)) & cornerBits, y, z, 2);
                if (y == ny || z == nz) continue;
                const CellRow cellRow{r, row(y + 1, z), row(y, z + 1), row(y + 1, z + 1)};
                for (uint64_t mixed = cellRow.crossed(cellBits); mixed; mixed &= mixed - 1)
                    countCell(cellRow.caseOf(__builtin_ctzll(mixed)), __builtin_ctzll(mixed), y, z, count);
            }
        return count;
    }

    // What extractMetaCell(m) writes into a PlacedMesh, by classification alone: adds
    // the triangles to count.triangles and, once per edge (`seen`: a bit per local edge of the
    // brick, cleared for each brick), the vertices this brick owns to count.vertices.
    void countMetaCell(int m, uint64_t* seen, const EdgeOwnership& ownership, BrickCount& count) const {
        int lo[3], hi[3];
        metaCellBox(m, lo, hi);
        const int nx = hi[0] - lo[0], ny = hi[1] - lo[1], nz = hi[2] - lo[2];
        uint64_t above[kMaxMetaCellSize + 1][kMaxMetaCellSize + 1];
        classifyCorners(lo, hi, above);
        const uint64_t cellBits = (uint64_t(1) << nx) - 1;
        const size_t edgeRow = size_t(x.mLayout.brickSize + 1);
        for (int rz = 0; rz < nz; ++rz)
            for (int ry = 0; ry < ny; ++ry) {
                const CellRow cellRow{above[rz][ry], above[rz][ry + 1], above[rz + 1][ry], above[rz + 1][ry + 1]};
                for (uint64_t mixed = cellRow.crossed(cellBits); mixed; mixed &= mixed - 1) {
                    const int rx = __builtin_ctzll(mixed);
                    const int caseIndex = cellRow.caseOf(rx);
                    countCell(caseIndex, lo[0] + rx, lo[1] + ry, lo[2] + rz, count);
                    for (unsigned crossed = mcCrossedEdges(caseIndex); crossed; crossed &= crossed - 1) {
                        const int e = __builtin_ctz(crossed);
                        const int8_t* o = kCornerOffset[kEdgeCorners[e][0]];
                        const int p[3] = {lo[0] + rx + o[0], lo[1] + ry + o[1], lo[2] + rz + o[2]};
                        const int axis = mcEdgeAxis(e);
                        const size_t local = ((size_t(p[2]) * edgeRow + size_t(p[1])) * edgeRow + size_t(p[0])) * 3 + size_t(axis);
                        uint64_t& word = seen[local >> 6];
                        const uint64_t bit = uint64_t(1) << (local & 63);
                        if (word & bit) continue;
                        word |= bit;
                        count.vertices += ownership.owns(brick, corner0, p, axis);
                    }
                }
            }
    }

    // Cell coordinates lo..hi per axis in front-to-back order from `eyeCell` (this brick's cell
    // coordinates: eyeInCells), nearest the eye first. Nested z, y, x, each ordered so, is a
    // front-to-back order for a grid: a cell hiding another is no farther from the eye on any axis.
    static void frontToBack(const int lo[3], const int hi[3], const glm::dvec3& eyeCell, int (&order)[3][kMaxMetaCellSize]) {
        for (int a = 0; a < 3; ++a) {
            const int n = hi[a] - lo[a];
            // The eye beside the cells on this axis (most meta-cells): ascending or descending.
            const bool descending = eyeCell[a] >= double(hi[a]);
            for (int k = 0; k < n; ++k) order[a][k] = descending ? hi[a] - 1 - k : lo[a] + k;
            if (descending || eyeCell[a] <= double(lo[a])) continue;
            std::sort(order[a], order[a] + n, [&](int i, int j) {
                return std::abs(i + 0.5 - eyeCell[a]) < std::abs(j + 0.5 - eyeCell[a]);
            });
        }
    }

    // The vertex slots of the meta-cell's corner rows, asked for below: requested now, all rows
    // at once, their misses overlap instead of stalling one by one (a view visits a brick's
    // meta-cells scattered, so the slots are rarely cached).
    void prefetchSlots(const int lo[3], const int hi[3]) const {
        const int edgeRow = x.mLayout.brickSize + 1, nx = hi[0] - lo[0];
        for (int z = lo[2]; z <= hi[2]; ++z)
            for (int y = lo[1]; y <= hi[1]; ++y) {
                const uint32_t* slots = x.mEdgeVertex.data() + ((size_t(z) * edgeRow + size_t(y)) * edgeRow + size_t(lo[0])) * 3;
                __builtin_prefetch(slots);
                __builtin_prefetch(slots + 3 * nx + 2);
            }
    }

    // Appends the surface of every crossed cell of meta-cell m, in memory order.
    void extractMetaCell(int m) {
        int lo[3], hi[3];
        metaCellBox(m, lo, hi);
        const int nx = hi[0] - lo[0], ny = hi[1] - lo[1], nz = hi[2] - lo[2];
        uint64_t above[kMaxMetaCellSize + 1][kMaxMetaCellSize + 1];
        prefetchSlots(lo, hi);
        classifyCorners(lo, hi, above);
        const uint64_t cellBits = (uint64_t(1) << nx) - 1;
        uint32_t slotOffset[kMcEdgeCount];
        edgeSlots(slotOffset);
        KernelCounters& counters = x.mCounters;
        ++counters.metaCellsActive;
        counters.cellsVisited += int64_t(nx) * ny * nz;
        for (int rz = 0; rz < nz; ++rz)
            for (int ry = 0; ry < ny; ++ry) {
                const CellRow cellRow{above[rz][ry], above[rz][ry + 1], above[rz + 1][ry], above[rz + 1][ry + 1]};
                for (uint64_t mixed = cellRow.crossed(cellBits); mixed; mixed &= mixed - 1) {
                    const int rx = __builtin_ctzll(mixed);
                    const int cx = lo[0] + rx, cy = lo[1] + ry, cz = lo[2] + rz;
                    ++counters.cellsActive;
                    const int caseIndex = cellRow.caseOf(rx);
                    const size_t cellSlot = cornerSlot(cx, cy, cz);
                    if (TrilinearCell cut; trilinearCut(caseIndex, cx, cy, cz, cut)) {
                        uint32_t centre[kTrilinearMaxCentres], v[3];
                        makeCentres(cut, cx, cy, cz, centre);
                        for (int t = 0; t < cut.triangleCount; ++t) {
                            for (int k = 0; k < 3; ++k) {
                                const int e = cut.edges[3 * t + k];
                                v[k] = e < kMcEdgeCount ? edgeVertex(cellSlot + slotOffset[e], cx, cy, cz, e)
                                                        : centre[e - kTrilinearCentre];
                            }
                            mesh.addTriangle(v[0], v[1], v[2]);
                        }
                        continue;
                    }
                    const McPolygonCase& pc = mcPolygonCase(caseIndex);
                    for (int p = 0, at = 0; p < pc.polygonCount; at += pc.vertexCount[p++]) {
                        const uint32_t first = edgeVertex(cellSlot + slotOffset[pc.edges[at]], cx, cy, cz, pc.edges[at]);
                        uint32_t last = edgeVertex(cellSlot + slotOffset[pc.edges[at + 1]], cx, cy, cz, pc.edges[at + 1]);
                        for (int k = 2; k < pc.vertexCount[p]; ++k) {
                            const uint32_t next = edgeVertex(cellSlot + slotOffset[pc.edges[at + k]], cx, cy, cz, pc.edges[at + k]);
                            mesh.addTriangle(first, last, next);
                            last = next;
                        }
                    }
                }
            }
    }
};

}  // namespace vdiso
