// The view's meta-cell (core/extract/extract_view.cpp): the cells of one meta-cell tested front
// to back and their polygons scan-converted before any vertex is made. What the view decides
// per cell and polygon is a policy type, so that its tests inline into the loop (a call through
// a pointer per cell and per polygon cost 10% of a view):
//   void projectCorners(const int64_t first[3], const uint64_t* rows);
//       the corners of the meta-cell's crossed cells, before any test: global grid
//       coordinates first + (x, y, z) for each bit x of rows[z * (M + 1) + y] (M the meta-cell
//       size); a corner is named below by (z * (M + 1) + y) * (M + 1) + x
//   bool keepCell(int x, int y, int z);   // the meta-cell's local cell; false skips it
//   bool keepPolygon(const EdgePoint* outline, int count);
//   bool keepsTriangles();  // false when only keepPolygon's effects count
// keepPolygon gets each polygon's outline as points on cell edges; a cell's vertices (with their
// normals) and triangles are made when any of its polygons is wanted (the polygons of one cell
// come in no front-to-back order, so one may hide another) and the policy keeps triangles (a
// traversal marking its coverage with a brick whose surface the consumer holds wants the scan
// conversion, not the triangles). The view drops about half the polygons it tests: their
// vertices are never made.
#pragma once

#include <algorithm>
#include <cstdint>

#include <glm/vec3.hpp>

#include "core/kernel/brick_kernel.h"

namespace vdiso {

// A polygon's vertex before it is made: the point at fraction t along the cell edge from corner
// `corner` of the meta-cell (numbered as for projectCorners) to the next corner along `axis`;
// t is the crossing fraction makeEdgeVertex places the vertex at.
struct EdgePoint {
    int corner, axis;
    double t;
};

// Appends the surface of meta-cell m of `kernel`'s brick that `view` keeps (the policy above),
// its cells front to back from `eyeCell` (kernel.eyeInCells). The corners of its crossed cells go to
// the view at once; each crossed cell is asked, then each of its polygons as points on its
// edges; only a kept cell's vertices are made.
template <class T, class Mesh, class View>
void extractShownMetaCell(BrickKernel<T, Mesh>& kernel, int m, View& view, const glm::dvec3& eyeCell) {
    int lo[3], hi[3];
    kernel.metaCellBox(m, lo, hi);
    int order[3][kMaxMetaCellSize];
    kernel.frontToBack(lo, hi, eyeCell, order);
    const int nx = hi[0] - lo[0], ny = hi[1] - lo[1], nz = hi[2] - lo[2];
    const int cornerSide = kernel.x.metaCellSize() + 1;
    uint64_t above[kMaxMetaCellSize + 1][kMaxMetaCellSize + 1];
    kernel.prefetchSlots(lo, hi);
    kernel.classifyCorners(lo, hi, above);
    const uint64_t cellBits = (uint64_t(1) << nx) - 1;
    // The crossed cells by row, and their corners (bit x of corners[z * (M + 1) + y]).
    uint64_t crossed[kMaxMetaCellSize][kMaxMetaCellSize];
    uint64_t corners[(kMaxMetaCellSize + 1) * (kMaxMetaCellSize + 1)];
    std::fill_n(corners, size_t(cornerSide) * size_t(cornerSide), uint64_t(0));
    for (int rz = 0; rz < nz; ++rz)
        for (int ry = 0; ry < ny; ++ry) {
            const uint64_t c = CellRow{above[rz][ry], above[rz][ry + 1], above[rz + 1][ry], above[rz + 1][ry + 1]}.crossed(cellBits);
            crossed[rz][ry] = c;
            const uint64_t both = c | c << 1;
            uint64_t* row = corners + rz * cornerSide + ry;
            row[0] |= both;
            row[1] |= both;
            row[cornerSide] |= both;
            row[cornerSide + 1] |= both;
        }
    const int64_t first[3] = {kernel.corner0[0] + lo[0], kernel.corner0[1] + lo[1], kernel.corner0[2] + lo[2]};
    view.projectCorners(first, corners);
    uint32_t slotOffset[kMcEdgeCount];
    kernel.edgeSlots(slotOffset);
    // Edge e of a cell: its first corner's offset in the corner numbering and in the samples,
    // and the step to its other corner in the samples.
    int cornerAt[kMcEdgeCount];
    size_t sampleAt[kMcEdgeCount], sampleStep[kMcEdgeCount];
    for (int e = 0; e < kMcEdgeCount; ++e) {
        const int8_t* o = kCornerOffset[kEdgeCorners[e][0]];
        const int axis = mcEdgeAxis(e);
        cornerAt[e] = (o[2] * cornerSide + o[1]) * cornerSide + o[0];
        sampleAt[e] = kernel.sampleIndex(o[0], o[1], o[2]) - kernel.sampleIndex(0, 0, 0);
        sampleStep[e] = axis == 0 ? 1 : axis == 1 ? size_t(kernel.side) : size_t(kernel.side) * kernel.side;
    }
    // rank[a][r]: the place of local coordinate r on axis a (x, y) in the front-to-back order.
    // A row's crossed cells, and a layer's rows that hold any, are taken by their bits in that
    // order, not by testing every place (whose branch on the bit mispredicted, and which was
    // 3 % of a view's instructions).
    int rank[2][kMaxMetaCellSize];
    for (int a = 0; a < 2; ++a)
        for (int k = 0; k < hi[a] - lo[a]; ++k) rank[a][order[a][k] - lo[a]] = k;
    uint64_t rowsHeld[kMaxMetaCellSize];  // bit rank[1][ry] of [rz]: row (ry, rz) holds a crossed cell
    for (int rz = 0; rz < nz; ++rz) {
        rowsHeld[rz] = 0;
        for (int ry = 0; ry < ny; ++ry) rowsHeld[rz] |= uint64_t(crossed[rz][ry] != 0) << rank[1][ry];
    }
    KernelCounters& counters = kernel.counters();
    ++counters.metaCellsActive;
    counters.cellsVisited += int64_t(nx) * ny * nz;
    for (int iz = 0; iz < nz; ++iz)
        for (uint64_t rows = rowsHeld[order[2][iz] - lo[2]]; rows != 0; rows &= rows - 1) {
            const int cz = order[2][iz], cy = order[1][__builtin_ctzll(rows)];
            const int rz = cz - lo[2], ry = cy - lo[1];
            const uint64_t mixed = crossed[rz][ry];
            const CellRow cellRow{above[rz][ry], above[rz][ry + 1], above[rz + 1][ry], above[rz + 1][ry + 1]};
            uint64_t ranked = 0;
            for (uint64_t left = mixed; left != 0; left &= left - 1) ranked |= uint64_t(1) << rank[0][__builtin_ctzll(left)];
            for (; ranked != 0; ranked &= ranked - 1) {
                const int cx = order[0][__builtin_ctzll(ranked)], rx = cx - lo[0];
                if (!view.keepCell(rx, ry, rz)) continue;
                ++counters.cellsActive;
                const McPolygonCase& pc = mcPolygonCase(cellRow.caseOf(rx));
                const int corner = (rz * cornerSide + ry) * cornerSide + rx;
                const T* cellSamples = kernel.s + kernel.sampleIndex(cx, cy, cz);
                EdgePoint outline[kMcEdgeCount];  // every polygon's, one after another
                bool wanted = false;
                int outlineLength = 0;
                for (int p = 0, at = 0; p < pc.polygonCount; at += pc.vertexCount[p++]) {
                    for (int k = 0; k < pc.vertexCount[p]; ++k) {
                        const int e = pc.edges[at + k];
                        const T* s0 = cellSamples + sampleAt[e];
                        outline[at + k] = {corner + cornerAt[e], mcEdgeAxis(e),
                                           crossingFraction(double(s0[0]), double(s0[sampleStep[e]]), kernel.iso)};
                    }
                    wanted |= view.keepPolygon(outline + at, pc.vertexCount[p]);
                    outlineLength = at + pc.vertexCount[p];
                }
                if (!wanted || !view.keepsTriangles()) continue;
                const size_t cellSlot = kernel.cornerSlot(cx, cy, cz);
                uint32_t vertex[kMcEdgeCount];
                for (int k = 0; k < outlineLength; ++k)
                    vertex[k] = kernel.edgeVertex(cellSlot + slotOffset[pc.edges[k]], cx, cy, cz, pc.edges[k]);
                for (int p = 0, at = 0; p < pc.polygonCount; at += pc.vertexCount[p++])
                    for (int k = 2; k < pc.vertexCount[p]; ++k)
                        kernel.mesh.addTriangle(vertex[at], vertex[at + k - 1], vertex[at + k]);
            }
        }
}

}  // namespace vdiso
