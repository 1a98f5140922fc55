// Where a pixel's ray first meets the extracted surface inside one brick: the position and
// normal of a SAGE point (§3.3), which stands for the triangles of a sub-pixel box and must
// draw as they would.
//
// The ray is origin + t * direction (world units), t in [tEnter, tExit], a segment that lies
// within the kernel's brick. Its cells are walked front to back (a 3-D DDA); in each crossed
// cell the ray is intersected with the cell's own marching-cubes triangles (the fan form the
// mesh has, vertices interpolated as the kernel does), and the first hit wins. The normal is
// the hit triangle's vertex normals (the kernel's edge normals) interpolated at the hit, as a
// rasterizer interpolates them at that pixel centre: so a point shades as the triangle drawn
// there. (Marching the trilinear interpolant and taking its gradient instead shaded 3% of a
// distant view of the MRI differently from its triangles.) Returns false when no triangle of
// the segment's cells is hit.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>

#include <glm/geometric.hpp>

#include "core/kernel/brick_kernel.h"
#include "core/kernel/mc_tables.h"

namespace vdiso {

namespace detail {

// Möller-Trumbore: the ray parameter of the hit of p + t d with triangle (a, b, c) and the
// barycentric weights of b and c there, or false.
inline bool rayTriangle(const glm::dvec3& p, const glm::dvec3& d, const glm::dvec3& a, const glm::dvec3& b,
                        const glm::dvec3& c, double& t, double& u, double& v) {
    const glm::dvec3 e1 = b - a, e2 = c - a;
    const glm::dvec3 q = glm::cross(d, e2);
    const double det = glm::dot(e1, q);
    if (!(std::abs(det) > 1e-300)) return false;
    const double inv = 1.0 / det;
    const glm::dvec3 s = p - a;
    u = glm::dot(s, q) * inv;
    if (u < 0.0 || u > 1.0) return false;
    const glm::dvec3 r = glm::cross(s, e1);
    v = glm::dot(d, r) * inv;
    if (v < 0.0 || u + v > 1.0) return false;
    t = glm::dot(e2, r) * inv;
    return true;
}

}  // namespace detail

template <class T>
bool firstHit(const BrickKernel<T>& kernel, const glm::dvec3& origin, const glm::dvec3& direction,
              double tEnter, double tExit, glm::vec3& position, glm::vec3& normal) {
    const VolumeInfo& volume = kernel.volume();
    // The ray in this brick's cell coordinates (cell (i, j, k) spans [i, i + 1] on each axis).
    glm::dvec3 p, d;
    for (int a = 0; a < 3; ++a) {
        p[a] = (origin[a] - volume.origin[a]) / volume.spacing[a] - double(kernel.corner0[a]);
        d[a] = direction[a] / volume.spacing[a];
    }
    // The DDA over cells from tEnter to tExit.
    const glm::dvec3 start = p + d * tEnter;
    int cell[3], step[3];
    double tNext[3], tDelta[3];
    for (int a = 0; a < 3; ++a) {
        cell[a] = std::clamp(int(std::floor(start[a])), 0, kernel.cells[a] - 1);
        step[a] = d[a] > 0 ? 1 : -1;
        if (d[a] == 0.0) {
            tNext[a] = tDelta[a] = std::numeric_limits<double>::infinity();
        } else {
            const double boundary = double(cell[a] + (d[a] > 0 ? 1 : 0));
            tNext[a] = (boundary - p[a]) / d[a];
            tDelta[a] = std::abs(1.0 / d[a]);
        }
    }
    const int side = kernel.side;
    const size_t strides[3] = {1, size_t(side), size_t(side) * side};
    // Edge e of the current cell: its crossing (cell coordinates) and its vertex normal, as
    // the kernel makes them.
    auto edgeStart = [&](int e) {
        const int8_t* o = kCornerOffset[kEdgeCorners[e][0]];
        return kernel.sampleIndex(cell[0] + o[0], cell[1] + o[1], cell[2] + o[2]);
    };
    auto edgePoint = [&](int e) {
        const int8_t* o = kCornerOffset[kEdgeCorners[e][0]];
        const int axis = mcEdgeAxis(e);
        const size_t i0 = edgeStart(e);
        glm::dvec3 q(cell[0] + o[0], cell[1] + o[1], cell[2] + o[2]);
        q[axis] += crossingFraction(double(kernel.s[i0]), double(kernel.s[i0 + strides[axis]]), kernel.iso);
        return q;
    };
    auto edgeNormalOf = [&](int e) {
        const int axis = mcEdgeAxis(e);
        return glm::dvec3(kernel.edgeNormal(edgeStart(e), strides[axis], axis));
    };
    for (int guard = 0; guard < 3 * (kernel.cells[0] + kernel.cells[1] + kernel.cells[2]) + 3; ++guard) {
        const size_t base = kernel.sampleIndex(cell[0], cell[1], cell[2]);
        int caseIndex = 0;
        for (int c = 0; c < 8; ++c) {
            const int8_t* o = kCornerOffset[c];
            caseIndex |= int(kernel.threshold.above(kernel.s[base + o[0] * strides[0] + o[1] * strides[1] + o[2] * strides[2]])) << c;
        }
        if (caseIndex != 0 && caseIndex != 255) {
            const McPolygonCase& pc = mcPolygonCase(caseIndex);
            double best = std::numeric_limits<double>::infinity(), bestU = 0, bestV = 0;
            int bestEdges[3] = {0, 0, 0};
            glm::dvec3 at[kMcMaxPolygonVertices];
            for (int poly = 0, first = 0; poly < pc.polygonCount; first += pc.vertexCount[poly++]) {
                const int count = pc.vertexCount[poly];
                for (int k = 0; k < count; ++k) at[k] = edgePoint(pc.edges[first + k]);
                for (int k = 2; k < count; ++k) {
                    double t, u, v;
                    if (detail::rayTriangle(p, d, at[0], at[k - 1], at[k], t, u, v) && t >= tEnter && t <= tExit &&
                        t < best) {
                        best = t;
                        bestU = u;
                        bestV = v;
                        bestEdges[0] = pc.edges[first];
                        bestEdges[1] = pc.edges[first + k - 1];
                        bestEdges[2] = pc.edges[first + k];
                    }
                }
            }
            if (best < std::numeric_limits<double>::infinity()) {
                // Normals only for the triangle hit: they are most of a vertex's cost.
                const glm::dvec3 n = (1.0 - bestU - bestV) * edgeNormalOf(bestEdges[0]) +
                                     bestU * edgeNormalOf(bestEdges[1]) + bestV * edgeNormalOf(bestEdges[2]);
                const double length = glm::length(n);
                position = glm::vec3(origin + direction * best);
                normal = length > 0 ? glm::vec3(n / length) : glm::vec3(0.0f);
                return true;
            }
        }
        // The next cell along the ray, unless the segment ends in this one.
        int axis = 0;
        if (tNext[1] < tNext[axis]) axis = 1;
        if (tNext[2] < tNext[axis]) axis = 2;
        if (tNext[axis] > tExit) return false;
        cell[axis] += step[axis];
        if (cell[axis] < 0 || cell[axis] >= kernel.cells[axis]) return false;
        tNext[axis] += tDelta[axis];
    }
    return false;
}

}  // namespace vdiso
