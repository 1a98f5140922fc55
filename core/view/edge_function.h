// The edge functions of a screen triangle: for each edge e, a[e] * x + b[e] * y + c[e] is the
// signed distance in pixels of (x, y) from the edge's line, positive on the triangle's side
// whichever way it winds. Used where coverage is decided by distances rather than by scan
// rows: WISE's top-down classification of pyramid nodes (core/view/occlusion_pyramid.cpp) and the
// traversal's test for centres within rasterizer rounding of a triangle (core/extract/extract_view.cpp).
#pragma once

#include <cmath>

#include <glm/vec2.hpp>

namespace vdiso {

struct TriangleEdgeFunctions {
    double a[3], b[3], c[3];  // edge e runs from corner e to corner (e + 1) % 3
    // Zero or non-finite area, or a repeated corner: nothing lies inside. An edge of zero
    // length then gets a = b = 0, c = 1: its distance never excludes a point.
    bool degenerate = false;

    double distance(int e, double x, double y) const { return a[e] * x + b[e] * y + c[e]; }

    static TriangleEdgeFunctions of(const glm::dvec2& p0, const glm::dvec2& p1, const glm::dvec2& p2) {
        TriangleEdgeFunctions f;
        const double area2 = (p1.x - p0.x) * (p2.y - p0.y) - (p1.y - p0.y) * (p2.x - p0.x);
        f.degenerate = !(area2 != 0.0);
        const double sign = area2 < 0.0 ? -1.0 : 1.0;
        const glm::dvec2 corner[3] = {p0, p1, p2};
        for (int e = 0; e < 3; ++e) {
            const glm::dvec2 p = corner[e], q = corner[e == 2 ? 0 : e + 1];
            const double ex = q.x - p.x, ey = q.y - p.y;
            const double length = std::sqrt(ex * ex + ey * ey);
            if (length == 0.0) {
                f.a[e] = f.b[e] = 0.0;
                f.c[e] = 1.0;
                f.degenerate = true;
                continue;
            }
            f.a[e] = -ey * sign / length;
            f.b[e] = ex * sign / length;
            f.c[e] = -(f.a[e] * p.x + f.b[e] * p.y);
        }
        return f;
    }
};

}  // namespace vdiso
