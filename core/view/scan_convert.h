// Scan conversion of projected polygons at pixel centres (SAGE §3.2).
//
// Input: a closed polygon in pixel coordinates (core/camera.h: x right, y down, pixel (i, j)
// has its centre at (i + 0.5, j + 0.5)), any number of vertices >= 3, possibly concave or
// self-overlapping: the projection of a non-planar marching-cubes polygon (core/kernel/mc_tables.h).
// Output: sink(y, x0, x1) for each maximal run x0..x1 (inclusive) of covered pixel centres in
// row y, rows in increasing order, runs of a row in increasing order and disjoint, all inside
// [0, width) x [0, height). A polygon with a non-finite vertex (e.g. a point behind the eye,
// which Camera::project turns into NaN) covers nothing.
//
// Fill rule: NONZERO winding at the pixel centre. The outline's winding number is the sum of its
// fan triangles' windings, so a centre with nonzero winding lies inside at least one fan
// triangle: the outline never covers a pixel that its triangles (what is drawn) leave uncovered,
// which keeps occlusion culling conservative. Even-odd would also be safe but would leave holes
// where a non-planar polygon's projection folds over itself.
//
// Tie rule (top-left, in this y-down convention): an edge counts for row y when
// yTop <= y + 0.5 < yBottom (its upper end included, its lower end excluded; horizontal edges
// never count), and a crossing at exactly the centre's x counts as lying to its left. So a
// centre on a left or top edge is inside, on a right or bottom edge outside; a centre on an
// edge shared by two adjacent polygons is covered exactly once. Crossings are computed from the
// edge's upper end whichever way the polygon runs, so both polygons sharing an edge get
// bit-identical crossings and the rule holds exactly in floating point, not just on paper.
//
// Cost: per row, one pass over the edges and an insertion sort of the few crossings; no heap
// allocation up to kScanLocalVertices vertices (marching-cubes polygons have at most 7).
// Pure functions: safe to call from any thread.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <span>
#include <vector>

#include <glm/vec2.hpp>

#include "core/view/pixel_round.h"

namespace vdiso {

class OcclusionPyramid;

namespace detail {

constexpr int kScanLocalVertices = 16;

// A non-horizontal edge, stored from its upper end (smaller y).
struct ScanEdge {
    double xTop, yTop, yBottom;
    double dx, dy;  // bottom minus top; dy > 0
    int winding;    // +1 when the polygon runs downwards along it, -1 upwards
};

struct ScanCrossing {
    double x;
    int winding;
};

// Smallest i with i + 0.5 >= v, for v clamped to [-1, limit + 1] so that far off-image
// coordinates cannot overflow the int.
inline int firstCentreAtOrAfter(double v, int limit) {
    return ceilToInt(std::clamp(v, -1.0, double(limit) + 1.0) - 0.5);
}

// Fills edges[] (room for n) with the polygon's non-horizontal edges and returns how many; 0
// when a vertex is not finite. yMin/yMax receive the polygon's vertical extent.
inline int buildScanEdges(const glm::dvec2* v, size_t n, ScanEdge* edges, double& yMin,
                          double& yMax) {
    yMin = v[0].y;
    yMax = v[0].y;
    int count = 0;
    for (size_t i = 0; i < n; ++i) {
        const glm::dvec2 a = v[i];
        const glm::dvec2 b = v[i + 1 == n ? 0 : i + 1];
        if (!std::isfinite(a.x) || !std::isfinite(a.y)) return 0;
        yMin = std::min(yMin, a.y);
        yMax = std::max(yMax, a.y);
        if (a.y == b.y) continue;
        const bool down = a.y < b.y;
        const glm::dvec2 top = down ? a : b;
        const glm::dvec2 bottom = down ? b : a;
        edges[count++] = {top.x, top.y, bottom.y, bottom.x - top.x, bottom.y - top.y,
                          down ? 1 : -1};
    }
    return count;
}

// The covered runs of one row (see the header comment for the rules); scratch needs room for
// edgeCount crossings. Runs are merged so that sink sees maximal runs only.
template <class SpanSink>
inline void scanRow(const ScanEdge* edges, int edgeCount, ScanCrossing* scratch, int row,
                    int width, SpanSink& sink) {
    const double yc = row + 0.5;
    int count = 0;
    for (int i = 0; i < edgeCount; ++i) {
        const ScanEdge& e = edges[i];
        if (e.yTop <= yc && yc < e.yBottom) {
            // Product before division: exact whenever the crossing is representable, so a
            // centre lying exactly on an edge is judged exactly.
            const double x = e.xTop + (yc - e.yTop) * e.dx / e.dy;
            ScanCrossing c{x, e.winding};
            int k = count++;
            for (; k > 0 && scratch[k - 1].x > x; --k) scratch[k] = scratch[k - 1];
            scratch[k] = c;
        }
    }
    int winding = 0;
    double runStartX = 0.0;
    int pendingBegin = 0, pendingEnd = -2;  // pending run, not yet emitted (empty: end < begin)
    for (int k = 0; k < count; ++k) {
        const int before = winding;
        winding += scratch[k].winding;
        if (before == 0 && winding != 0) {
            runStartX = scratch[k].x;
        } else if (before != 0 && winding == 0) {
            const int x0 = std::max(firstCentreAtOrAfter(runStartX, width), 0);
            const int x1 = std::min(firstCentreAtOrAfter(scratch[k].x, width) - 1, width - 1);
            if (x0 > x1) continue;
            // Runs of equal-x crossings can close and reopen at the same place: join them.
            if (pendingEnd >= pendingBegin && x0 <= pendingEnd + 1) {
                pendingEnd = std::max(pendingEnd, x1);
            } else {
                if (pendingEnd >= pendingBegin) sink(row, pendingBegin, pendingEnd);
                pendingBegin = x0;
                pendingEnd = x1;
            }
        }
    }
    if (pendingEnd >= pendingBegin) sink(row, pendingBegin, pendingEnd);
}

template <class SpanSink>
inline void scanConvertEdges(const ScanEdge* edges, int edgeCount, ScanCrossing* scratch,
                             double yMin, double yMax, int width, int height, SpanSink& sink) {
    if (edgeCount < 2) return;
    const int rowBegin = std::max(firstCentreAtOrAfter(yMin, height), 0);
    const int rowEnd = std::min(firstCentreAtOrAfter(yMax, height), height);
    for (int row = rowBegin; row < rowEnd; ++row)
        scanRow(edges, edgeCount, scratch, row, width, sink);
}

}  // namespace detail

// Calls sink(y, x0, x1) for the covered pixel centres of the polygon, as described above.
template <class SpanSink>
void scanConvertPolygon(std::span<const glm::dvec2> vertices, int width, int height,
                        SpanSink&& sink) {
    const size_t n = vertices.size();
    if (n < 3 || width <= 0 || height <= 0) return;
    double yMin, yMax;
    if (n <= size_t(detail::kScanLocalVertices)) {
        detail::ScanEdge edges[detail::kScanLocalVertices];
        detail::ScanCrossing scratch[detail::kScanLocalVertices];
        const int count = detail::buildScanEdges(vertices.data(), n, edges, yMin, yMax);
        detail::scanConvertEdges(edges, count, scratch, yMin, yMax, width, height, sink);
    } else {
        std::vector<detail::ScanEdge> edges(n);
        std::vector<detail::ScanCrossing> scratch(n);
        const int count = detail::buildScanEdges(vertices.data(), n, edges.data(), yMin, yMax);
        detail::scanConvertEdges(edges.data(), count, scratch.data(), yMin, yMax, width, height,
                                 sink);
    }
}

// Whether the polygon covers the pixel centre (x + 0.5, y + 0.5): by the rules above (the
// winding of the crossings of row y at or left of the centre, each computed as scanRow
// computes it), so it agrees with scanConvertPolygon exactly. For polygons whose box holds a
// single pixel centre, the common case where cells are about a pixel, this is all the scan
// conversion there is to do.
inline bool coversCentre(const glm::dvec2* v, size_t n, int x, int y) {
    const double yc = y + 0.5, xc = x + 0.5;
    int winding = 0;
    for (size_t i = 0; i < n; ++i) {
        const glm::dvec2 a = v[i];
        const glm::dvec2 b = v[i + 1 == n ? 0 : i + 1];
        if (!std::isfinite(a.x) || !std::isfinite(a.y)) return false;
        if (a.y == b.y) continue;
        const bool down = a.y < b.y;
        const glm::dvec2 top = down ? a : b;
        const glm::dvec2 bottom = down ? b : a;
        if (!(top.y <= yc && yc < bottom.y)) continue;
        const double crossing = top.x + (yc - top.y) * (bottom.x - top.x) / (bottom.y - top.y);
        if (crossing <= xc) winding += down ? 1 : -1;
    }
    return winding != 0;
}

// Convenience: covers the polygon's pixels in the pyramid's bottom level (coverSpan); the
// caller runs pyramid.propagate() before the next query. Returns whether the polygon covered
// a pixel centre that was not covered before.
bool scanConvertPolygon(std::span<const glm::dvec2> vertices, OcclusionPyramid& pyramid);

}  // namespace vdiso
