// Tests 1-3 of the view-dependent traversal (core/extract/extract_view.h) for one camera and one
// occlusion pyramid: range, frustum (a box covering no pixel centre counts as outside) and
// occlusion, for tree nodes, a brick's sub-blocks, meta-cells and cells. The traversal and its
// look-ahead (core/extract/brick_look_ahead.h) ask the same culler, so the look-ahead finds exactly the
// bricks the traversal would read if the pyramid stayed as it is now.
//
// Boxes are given in cell coordinates of the volume ([lo, hi) per axis, clamped to its cells)
// or as world boxes; screen boxes are SAGE's estimate (§3.4) or the exact 8-corner box.
// Reads the pyramid, never writes it; immutable otherwise, but a pyramid is per thread.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

#include <glm/vec3.hpp>

#include "core/brick_source.h"
#include "core/camera.h"
#include "core/trees/minmax_tree.h"
#include "core/view/occlusion_pyramid.h"
#include "core/view/pixel_rect.h"
#include "core/view/screen_box.h"

namespace vdiso {

enum class Cull { None, Range, Frustum, SubPixel, Occlusion };

class ViewCuller {
public:
    ViewCuller(const BrickSource& source, const Camera& camera, const OcclusionPyramid& pyramid,
               double iso, bool estimateBox);

    const Camera& camera() const { return mCamera; }
    // The eye in brick coordinates, for MinMaxTree::pushChildrenFarFirst.
    const glm::dvec3& eyeInBricks() const { return mEyeInBricks; }

    // World box of the cells [lo, hi) (clamped to the volume's cells).
    void worldBox(const int64_t lo[3], const int64_t hi[3], glm::dvec3& a, glm::dvec3& b) const;
    void nodeBox(const MinMaxNode& node, glm::dvec3& a, glm::dvec3& b) const;

    ScreenBox screenBox(const glm::dvec3& a, const glm::dvec3& b) const {
        return mEstimateBox ? mProjector.estimateBox(a, b) : mProjector.exactBox(a, b);
    }
    // The camera's view-projection times the grid-to-world map: grid coordinates to clip space.
    const glm::dmat4& gridToClip() const { return mGridToClip; }
    // The pixel centres a screen box covers; all of the image for a box crossing the near plane.
    PixelRect pixelRect(const ScreenBox& box) const;

    // Whether every pixel centre of the rectangle is covered (core/view/occlusion_pyramid.h).
    bool occluded(const PixelRect& r) const { return mPyramid.isOccluded(r.x0, r.y0, r.x1, r.y1); }

    // Tests 2-3 for a screen box (a box crossing the near plane is never culled).
    Cull cullScreenBox(const ScreenBox& box) const;
    // Tests 1-3 for the world box [a, b] whose range is `range`; its screen box in `box`
    // (unset when the range culls it).
    Cull cull(const BrickRange& range, const glm::dvec3& a, const glm::dvec3& b, ScreenBox& box) const {
        if (!rangeHoldsIso(range.minValue, range.maxValue, mIso)) return Cull::Range;
        box = screenBox(a, b);
        return cullScreenBox(box);
    }
    // Tests 1-3 for the sub-blocks of a brick (core/trees/sub_blocks.h): does any pass? Known from
    // the index, so a brick whose box passes only where it holds no surface, or only where its
    // surface is hidden, is not read. True when the source has no sub-block ranges.
    bool subBlocksShow(int64_t brick) const;

private:
    const BrickSource& mSource;
    const Camera& mCamera;
    const OcclusionPyramid& mPyramid;
    double mIso;
    bool mEstimateBox;
    BoxProjector mProjector;
    ImageLanes mImage;
    glm::dmat4 mGridToClip;
    glm::dvec3 mEyeInBricks;
};

// Inline: asked for every cell of every visible meta-cell.
inline PixelRect ViewCuller::pixelRect(const ScreenBox& box) const {
    if (box.crossesNearPlane) return {0, 0, mCamera.width - 1, mCamera.height - 1};
    // (NaN boxes never get here: cullScreenBox culls them.)
    return boxCentres(_mm_setr_pd(box.left, box.top), _mm_setr_pd(box.right, box.bottom), mImage);
}

inline Cull ViewCuller::cullScreenBox(const ScreenBox& box) const {
    if (box.crossesNearPlane) return Cull::None;  // refined, never culled
    // A camera whose numbers overflow the projection (an eye at 1e300, a fov of 1e-300
    // degrees) gives boxes of NaN: nothing of them can be drawn.
    if (!(box.left <= box.right && box.top <= box.bottom)) return Cull::Frustum;
    if (box.right < 0.5 || box.left > mCamera.width - 0.5 || box.bottom < 0.5 ||
        box.top > mCamera.height - 0.5)
        return Cull::Frustum;
    // Within the image now, so its centres there are the box's (empty exactly when it has none).
    const PixelRect r = boxCentresOnImage(_mm_setr_pd(box.left, box.top), _mm_setr_pd(box.right, box.bottom), mImage);
    if (r.empty()) return Cull::SubPixel;  // no pixel centre: nothing shows
    if (mPyramid.isOccluded(r.x0, r.y0, r.x1, r.y1)) return Cull::Occlusion;
    return Cull::None;
}

}  // namespace vdiso
