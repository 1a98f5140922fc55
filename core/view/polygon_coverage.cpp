#include "core/view/polygon_coverage.h"

#include <algorithm>
#include <cmath>
#include <span>

#include "core/view/edge_function.h"
#include "core/view/scan_convert.h"

namespace vdiso {

// If the polygon does not fold, its winding number is nonzero wherever one of its fan
// triangles covers, and asking them after the polygon would find nothing more.
bool PolygonCoverage::folds(const glm::dvec2* v, int count) {
    bool positive = false, negative = false;
    for (int k = 2; k < count; ++k) {
        const glm::dvec2 a = v[k - 1] - v[0], b = v[k] - v[0];
        const double area2 = a.x * b.y - a.y * b.x;
        positive |= area2 > 0.0;
        negative |= area2 < 0.0;
    }
    return positive && negative;
}

// Whether an uncovered pixel centre lies inside the triangle or within kRasterSlack pixels of
// each of its edges' lines. Degenerate triangles draw nothing.
bool PolygonCoverage::nearUncoveredCentre(const glm::dvec2& p0, const glm::dvec2& p1, const glm::dvec2& p2) const {
    const glm::dvec2 corners[3] = {p0, p1, p2};
    PixelRect r, centres;
    polygonRects(corners, 3, mImage, r, centres);
    if (!uncoveredCentreIn(r)) return false;
    const TriangleEdgeFunctions f = TriangleEdgeFunctions::of(p0, p1, p2);
    if (f.degenerate) return false;
    return mPyramid.findUncovered(r.x0, r.y0, r.x1, r.y1, [&](int x, int y) {
        bool inside = true;
        for (int e = 0; e < 3 && inside; ++e) inside = f.distance(e, x + 0.5, y + 0.5) >= -kRasterSlack;
        return inside;
    });
}

}  // namespace vdiso
