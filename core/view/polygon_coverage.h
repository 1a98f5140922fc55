// SAGE's scan conversion of a polygon into the occlusion pyramid (paper §3.2), and the rule
// that keeps a polygon only when it draws something: the per-polygon half of the traversal's
// cell policy (core/extract/extract_view.cpp). Cells arrive front to back, so a polygon whose scan
// conversion covers no pixel centre left uncovered lies behind what is drawn already or
// between pixel centres, where the rasterizer makes no fragment either.
#pragma once

#include <algorithm>
#include <span>

#include <glm/vec2.hpp>

#include "core/view/occlusion_pyramid.h"
#include "core/view/pixel_rect.h"
#include "core/view/scan_convert.h"
#include "core/view/screen_box.h"
#include "core/view/tile_coverage.h"
#include "core/view/view_culler.h"

namespace vdiso {

// The pixel centres a polygon whose box is `box` can cover (scan_convert.h's rules: columns
// [first at or after left, first at or after right), rows likewise), clamped to the image: the
// rule polygonRects (core/view/pixel_rect.h) rounds two coordinates at a time, written one at
// a time.
inline PixelRect centresOfBox(const ScreenBox& box, int width, int height) {
    return {std::max(detail::firstCentreAtOrAfter(box.left, width), 0),
            std::max(detail::firstCentreAtOrAfter(box.top, height), 0),
            std::min(detail::firstCentreAtOrAfter(box.right, width) - 1, width - 1),
            std::min(detail::firstCentreAtOrAfter(box.bottom, height) - 1, height - 1)};
}

class PolygonCoverage {
public:
    // bottomUp: mark pixel centres bottom-up (false: insert each fan triangle top-down, WISE);
    // scanPolygons: scan-convert the polygon whole (false: each fan triangle on its own).
    PolygonCoverage(OcclusionPyramid& pyramid, bool bottomUp, bool scanPolygons)
        : mPyramid(pyramid), mBottomUp(bottomUp), mScanPolygons(scanPolygons), mSimd(simdLevel()),
          mImage(pyramid.width(), pyramid.height()) {}

    // Marks the pixel centres the polygon (count vertices in pixel coordinates, a fan from v[0])
    // covers. With keepOnlyNew, returns whether it covered a centre not covered before, or one
    // lies within a rasterizer's rounding of it (then it is drawn); otherwise true.
    bool cover(const glm::dvec2* v, int count, bool keepOnlyNew);
    // Marks what cover(v, count, true) marks, without asking whether the polygon is kept (a
    // polygon of a brick the consumer holds: only its coverage counts). Skips the slack query
    // and the rounding check of a polygon that covers nothing new.
    void mark(const glm::dvec2* v, int count);

    // Whether the projected polygon folds over itself: its fan triangles wind both ways.
    static bool folds(const glm::dvec2* v, int count);

private:
    bool coverCentres(const glm::dvec2* v, int count, const PixelRect& r, bool keepOnlyNew);
    // Covers the outline's centres (within r, its box's or a larger one's) tile by tile
    // (core/view/tile_coverage.h), or by rows beyond kTileCoverageEdges vertices; whether one was new.
    bool coverOutline(const glm::dvec2* v, int count, const PixelRect& r) {
        bool fresh = false;
        if (!coverPolygonTiles(v, count, r, mPyramid, fresh, mSimd))
            fresh = scanConvertPolygon(std::span<const glm::dvec2>(v, size_t(count)), mPyramid);
        return fresh;
    }
    bool nearUncoveredCentre(const glm::dvec2& p0, const glm::dvec2& p1, const glm::dvec2& p2) const;
    [[gnu::always_inline]] bool uncoveredCentreIn(const PixelRect& r) const {
        return !r.empty() && !mPyramid.isOccluded(r.x0, r.y0, r.x1, r.y1);
    }

    OcclusionPyramid& mPyramid;
    bool mBottomUp, mScanPolygons;
    SimdLevel mSimd;  // chosen once (core/simd.h)
    ImageLanes mImage;
};

// Inline: called for every polygon, and most are answered by the box test. With keepOnlyNew
// the rectangle of centres within the rounding slack of the box, which holds the box's own, is
// asked first: a polygon with no uncovered centre there covers nothing new and lies near none
// (most hidden polygons: one query), and where the two rectangles are the same (most
// polygons) the box's needs no query of its own. A polygon that then covers nothing new left
// the pyramid as it was, so the slack still holds an uncovered centre. Both rectangles are
// rounded at once (core/view/pixel_rect.h).
inline bool PolygonCoverage::cover(const glm::dvec2* v, int count, bool keepOnlyNew) {
    bool coversNew = false;
    PixelRect slack, r;
    polygonRects(v, count, mImage, slack, r);
    if (!mBottomUp) {
        for (int k = 2; k < count; ++k) {
            const glm::dvec2 triangle[3] = {v[0], v[k - 1], v[k]};
            coversNew |= mPyramid.insertTriangleTopDown(triangle);
        }
        if (!keepOnlyNew) return true;
        if (coversNew || !uncoveredCentreIn(slack)) return coversNew;
    } else if (!keepOnlyNew) {
        if (uncoveredCentreIn(r)) coverCentres(v, count, r, false);
        return true;
    } else {
        if (!uncoveredCentreIn(slack)) return false;
        const bool sameRect = r.x0 == slack.x0 && r.y0 == slack.y0 && r.x1 == slack.x1 && r.y1 == slack.y1;
        if (sameRect || uncoveredCentreIn(r)) coversNew = coverCentres(v, count, r, true);
        if (coversNew) return true;
    }
    // The rasterizer works in float on snapped coordinates, so a centre within a hair of an
    // edge may fall the other way there: such a polygon is kept as well (it marks nothing; only
    // coverage this side of the rounding is ever marked).
    for (int k = 2; k < count && !coversNew; ++k) coversNew = nearUncoveredCentre(v[0], v[k - 1], v[k]);
    return coversNew;
}

// The same marks as cover(v, count, true): where it marks anything, the box's centres hold an
// uncovered one and it covers them as here; the fans it asks of a folded polygon are asked here.
inline void PolygonCoverage::mark(const glm::dvec2* v, int count) {
    if (!mBottomUp) {
        cover(v, count, false);
        return;
    }
    PixelRect slack, r;
    polygonRects(v, count, mImage, slack, r);
    if (uncoveredCentreIn(r)) coverCentres(v, count, r, true);
}

// Covers the centres of r (the polygon's box's, with one uncovered) that the polygon covers;
// whether one was new.
inline bool PolygonCoverage::coverCentres(const glm::dvec2* v, int count, const PixelRect& r, bool keepOnlyNew) {
    bool coversNew = false;
    if (mScanPolygons) {
        coversNew = coverOutline(v, count, r);
        // Where a non-planar polygon's projection folds over itself its winding cancels,
        // yet its fan triangles, which are what gets drawn, cover those centres: before
        // dropping it, ask them (they mark only what they draw).
        const bool askFans = keepOnlyNew && !coversNew && folds(v, count);
        for (int k = 2; k < count && !coversNew && askFans; ++k) {
            const glm::dvec2 triangle[3] = {v[0], v[k - 1], v[k]};
            coversNew |= coverOutline(triangle, 3, r);
        }
    } else {
        for (int k = 2; k < count; ++k) {
            const glm::dvec2 triangle[3] = {v[0], v[k - 1], v[k]};
            coversNew |= coverOutline(triangle, 3, r);
        }
    }
    return coversNew;
}

}  // namespace vdiso
