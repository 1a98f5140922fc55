#include "core/view/polygon_coverage.h"

#include <algorithm>
#include <cmath>
#include <span>

#include "core/view/edge_function.h"
#include "core/view/pixel_round.h"
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

// What the scan conversion of the polygon (or of its fan triangles, as in cover) marks when
// its box holds the one centre (x, y), not yet covered.
bool PolygonCoverage::coversSingleCentre(const glm::dvec2* v, int count, int x, int y, bool keepOnlyNew) {
    bool covered = mScanPolygons && coversCentre(v, size_t(count), x, y);
    const bool askFans = !mScanPolygons || (keepOnlyNew && !covered && folds(v, count));
    for (int k = 2; k < count && !covered && askFans; ++k) {
        const glm::dvec2 triangle[3] = {v[0], v[k - 1], v[k]};
        covered = coversCentre(triangle, 3, x, y);
    }
    return covered && mPyramid.coverSpan(y, x, x);
}

// Whether an uncovered pixel centre lies inside the triangle or within kRasterSlack pixels of
// each of its edges' lines. Degenerate triangles draw nothing.
bool PolygonCoverage::nearUncoveredCentre(const glm::dvec2& p0, const glm::dvec2& p1, const glm::dvec2& p2) const {
    constexpr double kRasterSlack = 1.0 / 64;  // GL's sub-pixel snapping is 1/256 or finer
    const double xMin = std::min({p0.x, p1.x, p2.x}) - kRasterSlack;
    const double xMax = std::max({p0.x, p1.x, p2.x}) + kRasterSlack;
    const double yMin = std::min({p0.y, p1.y, p2.y}) - kRasterSlack;
    const double yMax = std::max({p0.y, p1.y, p2.y}) + kRasterSlack;
    // Clamped to the image before the conversion (a vertex far off it holds no int).
    const double w = mPyramid.width(), h = mPyramid.height();
    const int x0 = ceilToInt(std::clamp(xMin - 0.5, 0.0, w));
    const int x1 = floorToInt(std::clamp(xMax - 0.5, -1.0, w - 1));
    const int y0 = ceilToInt(std::clamp(yMin - 0.5, 0.0, h));
    const int y1 = floorToInt(std::clamp(yMax - 0.5, -1.0, h - 1));
    if (x0 > x1 || y0 > y1 || mPyramid.isOccluded(x0, y0, x1, y1)) return false;
    const TriangleEdgeFunctions f = TriangleEdgeFunctions::of(p0, p1, p2);
    if (f.degenerate) return false;
    for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) {
            if (mPyramid.isCovered(x, y)) continue;
            bool inside = true;
            for (int e = 0; e < 3 && inside; ++e) inside = f.distance(e, x + 0.5, y + 0.5) >= -kRasterSlack;
            if (inside) return true;
        }
    return false;
}

}  // namespace vdiso
