// A meta-cell's cell corners projected once, for the view's per-cell work
// (core/kernel/brick_kernel.h, extractShownMetaCell): each cell's screen box and the pixel
// positions of its polygons' vertices come from the same projected corners.
//
// A corner's clip coordinates are computed from its global grid coordinates by one formula,
// whichever meta-cell, brick or strip asks, so a corner shared by neighbours has the same bits
// in each. A point on the edge between two corners is placed by interpolating their clip
// coordinates at the edge's crossing fraction (exact in real arithmetic: a projective map is
// linear in clip space), then dividing: a vertex shared by cells gets the same pixel position in
// every cell, and coverage ties stay exact across them. A cell's screen box is the min and max
// of its eight corners' positions: the exact box (core/view/screen_box.h), widened by a hair so
// that rounding in the division never leaves a point of the cell outside it.
//
// Sized for one meta-cell size; reused from meta-cell to meta-cell; one per thread.
#pragma once

#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include <emmintrin.h>

#include <glm/mat4x4.hpp>
#include <glm/vec2.hpp>
#include <glm/vec4.hpp>

#include "core/simd.h"
#include "core/view/pixel_rect.h"
#include "core/view/screen_box.h"

namespace vdiso {

class CornerProjection {
public:
    // A box holds its cell's points despite the division's rounding (a few ulps of a pixel
    // position): widened by this many pixels on each side.
    static constexpr double kBoxSlack = 1.0 / (1 << 20);

    // gridToClip: the camera's view-projection times the volume's grid-to-world map (OpenGL clip
    // space); the image is width x height pixels; corners of meta-cells of metaCellSize cells a
    // side. `simd` (core/simd.h): the baseline makes a corner's clip coordinates two at a time,
    // AVX2 four; both give the same bits.
    CornerProjection(const glm::dmat4& gridToClip, int width, int height, int metaCellSize,
                     SimdLevel simd = simdLevel());

    // Local corner (x, y, z) of the meta-cell being projected, each in [0, metaCellSize].
    int cornerIndex(int x, int y, int z) const { return (z * mSide + y) * mSide + x; }
    // cornerIndex's step along axis 0, 1, 2.
    int cornerStride(int axis) const { return axis == 0 ? 1 : axis == 1 ? mSide : mSide * mSide; }

    // Projects the corners at global grid coordinates first + (x, y, z) for each bit x of
    // rows[z * (metaCellSize + 1) + y], y and z in [0, metaCellSize]; the others keep whatever
    // they held.
    void project(const int64_t first[3], const uint64_t* rows);

    // The screen box of the meta-cell's local cell (x, y, z), whose eight corners were projected;
    // a box crossing the near plane when one of them is not in front of it (w > 0, z + w > 0),
    // BoxProjector::outsideBox() when all eight lie behind it (z + w < 0: so does every point
    // of the cell, z + w being linear).
    ScreenBox cellBox(int x, int y, int z) const {
        __m128d lo, hi;
        if (!cornerBounds(x, y, z, lo, hi)) return behindNearPlane(x, y, z) ? BoxProjector::outsideBox() : BoxProjector::nearPlaneBox();
        const __m128d slack = _mm_set1_pd(kBoxSlack);
        alignas(16) double l[2], h[2];
        _mm_store_pd(l, _mm_sub_pd(lo, slack));
        _mm_store_pd(h, _mm_add_pd(hi, slack));
        return {l[0], h[0], l[1], h[1], false};
    }
    // The pixel centres of cellBox(x, y, z), rounded as ViewCuller::pixelRect rounds a box and
    // clamped to the image (empty when none of them is on it, or when the cell lies behind the
    // near plane); false when the box crosses the near plane: such a cell is refined, never
    // culled. Inline: asked for every crossed cell of every visible meta-cell.
    bool cellRect(int x, int y, int z, PixelRect& r) const {
        __m128d lo, hi;
        if (!cornerBounds(x, y, z, lo, hi)) {
            r = {0, 0, -1, -1};
            return behindNearPlane(x, y, z);
        }
        const __m128d slack = _mm_set1_pd(kBoxSlack);
        r = boxCentresOnImage(_mm_sub_pd(lo, slack), _mm_add_pd(hi, slack), mImage);
        return true;
    }

    // The pixel position of the point at fraction t along the edge from corner `corner`
    // (cornerIndex) to the next one along `axis`; false when it has none (as Camera::project: at
    // or behind the eye, before the near plane or beyond the far one, or not finite). Placed
    // once an edge between project() calls: a vertex is shared by up to four cells.
    bool place(int corner, int axis, double t, glm::dvec2& out) {
        const size_t edge = size_t(corner) * 3 + size_t(axis);
        if (mEdgeStamp[edge] != mStamp) {
            mEdgeStamp[edge] = mStamp;
            mEdgePixel[edge] = placeNow(corner, corner + cornerStride(axis), t);
        }
        out = mEdgePixel[edge];
        return out.x == out.x;
    }

    // Whether the point placed at t along that edge (as place() makes it) lies behind the near
    // plane (clip z + w < 0): a polygon all of whose points do is clipped away whole.
    bool behindNearPlane(int corner, int axis, double t) const {
        const glm::dvec4 c = clipAt(corner, corner + cornerStride(axis), t);
        return c.z + c.w < 0.0;
    }

private:
    void projectAvx2(const int64_t first[3], const uint64_t* rows);  // project()'s AVX2 path

    // Whether all eight corners of cell (x, y, z) lie behind the near plane.
    bool behindNearPlane(int x, int y, int z) const {
        const size_t row = size_t(z * mSide + y), s = size_t(mSide);
        const uint64_t back = mBehind[row] & mBehind[row + 1] & mBehind[row + s] & mBehind[row + s + 1];
        return (back >> x & 3) == 3;
    }

    // The least and greatest (x, y) of cell (x, y, z)'s eight projected corners; false when one
    // of them is not in front of the near plane.
    bool cornerBounds(int x, int y, int z, __m128d& lo, __m128d& hi) const {
        // Rows (y, z), (y + 1, z), (y, z + 1) and (y + 1, z + 1) of the front bits.
        const size_t row = size_t(z * mSide + y), s = size_t(mSide), plane = s * s;
        const uint64_t front = mFront[row] & mFront[row + 1] & mFront[row + s] & mFront[row + s + 1];
        if ((front >> x & 3) != 3) return false;
        const double* p = &mPixel[size_t(cornerIndex(x, y, z))].x;
        lo = hi = _mm_loadu_pd(p);
        const size_t at[7] = {1, s, s + 1, plane, plane + 1, plane + s, plane + s + 1};
        for (size_t k : at) {
            const __m128d c = _mm_loadu_pd(p + 2 * k);
            lo = _mm_min_pd(lo, c);
            hi = _mm_max_pd(hi, c);
        }
        return true;
    }
    // Camera::project's pixel position of clip point c (c.w > 0).
    glm::dvec2 pixelOf(const glm::dvec4& c) const {
        const double r = 1.0 / c.w;
        return {(c.x * r * 0.5 + 0.5) * mWidth, (0.5 - c.y * r * 0.5) * mHeight};
    }
    // The clip coordinates of the point at t from corner a to corner b.
    glm::dvec4 clipAt(int a, int b, double t) const {
        const glm::dvec4& p = mClip[size_t(a)];
        return p + t * (mClip[size_t(b)] - p);
    }
    // The point at t from corner a to corner b placed, or NaN.
    glm::dvec2 placeNow(int a, int b, double t) const {
        const glm::dvec4 c = clipAt(a, b, t);
        if (!(c.w > 0.0) || !(c.z >= -c.w && c.z <= c.w)) return glm::dvec2(std::numeric_limits<double>::quiet_NaN());
        const glm::dvec2 out = pixelOf(c);
        return std::isfinite(out.x) && std::isfinite(out.y) ? out : glm::dvec2(std::numeric_limits<double>::quiet_NaN());
    }

    glm::dvec4 mRow[4];  // rows x, y, z, w of gridToClip
    SimdLevel mSimd;
    double mWidth, mHeight;
    ImageLanes mImage;
    int mSide;                         // metaCellSize + 1
    std::vector<glm::dvec4> mClip;     // by cornerIndex
    std::vector<glm::dvec2> mPixel;    // pixelOf(mClip), for corners in front
    std::vector<uint64_t> mFront;      // bit x of [z * mSide + y]: corner in front of the near plane
    std::vector<uint64_t> mBehind;     // likewise: corner behind it (z + w < 0)
    // Edge (cornerIndex * 3 + axis) placed since the last project() when its stamp is mStamp.
    std::vector<glm::dvec2> mEdgePixel;
    std::vector<uint32_t> mEdgeStamp;
    uint32_t mStamp = 0;
};

}  // namespace vdiso
