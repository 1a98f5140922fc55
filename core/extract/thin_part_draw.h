// The points a view draws for the thin parts its coarse levels lose (core/lod/thin_parts.h),
// gathered while the traversal goes and drawn at the end of a brick or of the walk, where
// nothing nearer covered their pixel by then (core/extract/extract_view.cpp).
//
// At most one point waits on a pixel: only the first on a pixel could be drawn there, so take()
// refuses the others before their normals are made (a Jacobi eigenvector each, most of a distant
// CT frame's thin-part work). A point's pixel is the one its stored (float) position falls on.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "core/camera.h"
#include "core/mesh.h"
#include "core/view/occlusion_pyramid.h"

namespace vdiso {

class ThinPartDraw {
public:
    // Both outlive it: the traversal's.
    ThinPartDraw(const PixelProjector& pixels, OcclusionPyramid& pyramid) : mPixels(pixels), mPyramid(pyramid) {}

    // Whether a point at `position` (world units) should be made: on the image and its depth
    // range, on a pixel not covered now and with no point waiting; if so the pixel is taken.
    bool take(const glm::dvec3& position);
    // Where the points taken are appended (appendLostPartPoints' `out`).
    PointSet& waiting() { return mWaiting; }
    // Appends to `points` the waiting points whose pixel is still not covered, covers those
    // pixels (and propagates), forgets the rest; returns how many were drawn.
    int64_t draw(PointSet& points);

private:
    // The pixel `position` falls on; false off the image or outside the depth range.
    bool pixelOf(const glm::dvec3& position, glm::ivec2& pixel) const;
    size_t bitOf(const glm::ivec2& p) const { return size_t(p.y) * size_t(mPyramid.width()) + size_t(p.x); }

    const PixelProjector& mPixels;
    OcclusionPyramid& mPyramid;
    PointSet mWaiting;
    std::vector<uint64_t> mTaken;  // bit y * width + x: a point waits on pixel (x, y); made at the first
};

}  // namespace vdiso
