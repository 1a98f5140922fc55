// SAGE's scan conversion of a polygon into the occlusion pyramid (paper §3.2), and the rule
// that keeps a polygon only when it draws something: the per-polygon half of the traversal's
// cell policy (core/extract_view.cpp). Cells arrive front to back, so a polygon whose scan
// conversion covers no pixel centre left uncovered lies behind what is drawn already or
// between pixel centres, where the rasterizer makes no fragment either.
#pragma once

#include <glm/vec2.hpp>

#include "core/occlusion_pyramid.h"
#include "core/view_culler.h"

namespace vdiso {

class PolygonCoverage {
public:
    // bottomUp: mark pixel centres bottom-up (false: insert each fan triangle top-down, WISE);
    // scanPolygons: scan-convert the polygon whole (false: each fan triangle on its own).
    PolygonCoverage(OcclusionPyramid& pyramid, bool bottomUp, bool scanPolygons)
        : mPyramid(pyramid), mBottomUp(bottomUp), mScanPolygons(scanPolygons) {}

    // Marks the pixel centres the polygon (count vertices in pixel coordinates, a fan from v[0])
    // covers. With keepOnlyNew, returns whether it covered a centre not covered before, or one
    // lies within a rasterizer's rounding of it (then it is drawn); otherwise true.
    bool cover(const glm::dvec2* v, int count, bool keepOnlyNew);

    // Whether the projected polygon folds over itself: its fan triangles wind both ways.
    static bool folds(const glm::dvec2* v, int count);

private:
    bool uncoveredCentresInBox(const glm::dvec2* v, int count, PixelRect& r) const;
    bool coversSingleCentre(const glm::dvec2* v, int count, int x, int y, bool keepOnlyNew);
    bool nearUncoveredCentre(const glm::dvec2& p0, const glm::dvec2& p1, const glm::dvec2& p2) const;

    OcclusionPyramid& mPyramid;
    bool mBottomUp, mScanPolygons;
};

}  // namespace vdiso
