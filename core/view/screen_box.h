// Screen-space bounding boxes of axis-aligned world boxes (meta-cells, tree nodes): the exact
// box of the 8 projected corners, and SAGE's fast over-estimate (§3.4, Fig. 6), plus the
// sub-pixel point rule (§3.3, Fig. 4).
//
// Boxes are in the pixel convention of core/camera.h (x right, y down, pixel (i, j) centred at
// (i + 0.5, j + 0.5)). estimateBox() always contains exactBox() (up to rounding), which in turn
// contains the projection of every point of the world box; both may extend off the image.
// A box that reaches the camera's near plane (some corner with clip z < -w, i.e. nearer than
// zNear, or with clip w <= 0: at or behind the eye) has no meaningful extent: crossesNearPlane
// is set and the extent is the whole plane (-inf..+inf); the caller treats the node as visible
// and refines it. Unless it lies wholly outside one of the view frustum's six planes (behind
// the near plane, or beside the frustum while reaching behind the eye): nothing of it is drawn,
// and it is given as outsideBox(), empty and beyond the image, which every test culls.
//
// BoxProjector is built once per camera and frame; it is immutable, so any number of threads
// may use one.
#pragma once

#include <algorithm>
#include <limits>
#include <optional>

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>
#include <glm/vec2.hpp>

#include "core/camera.h"

namespace vdiso {

struct ScreenBox {
    double left, right, top, bottom;  // left <= right, top <= bottom, pixel units
    bool crossesNearPlane;

    double width() const { return right - left; }
    double height() const { return bottom - top; }
};

class BoxProjector {
public:
    explicit BoxProjector(const Camera& camera);
    // viewProjection as Camera::viewProjection(): OpenGL clip space, near plane at z = -w.
    BoxProjector(const glm::dmat4& viewProjection, int width, int height);

    // Projects the 8 corners of [lo, hi].
    ScreenBox exactBox(const glm::dvec3& lo, const glm::dvec3& hi) const;

    // Fig. 6: with P the centre and D the half extents, clip = P M + D M over the corners,
    // where each row of D M is bounded by D |M| (half extents are a direction: w = 0, not the
    // 1 printed in Fig. 6). Each screen extreme is that of an independent numerator range over
    // a w range [PMw - DMw, PMw + DMw], hence an over-estimate; PMw - DMw is exactly the
    // nearest corner's w, so the near-plane test is exact. Two matrix-vector products, two
    // divisions.
    ScreenBox estimateBox(const glm::dvec3& lo, const glm::dvec3& hi) const;

    int width() const { return mWidth; }
    int height() const { return mHeight; }

    static double apply(const glm::dvec4& r, const glm::dvec3& p) { return r.x * p.x + r.y * p.y + r.z * p.z + r.w; }
    static ScreenBox nearPlaneBox() {
        constexpr double inf = std::numeric_limits<double>::infinity();
        return {-inf, inf, -inf, inf, true};
    }
    // A box nothing of which is in the view frustum: beyond the image's right and bottom edges.
    static ScreenBox outsideBox() {
        constexpr double inf = std::numeric_limits<double>::infinity();
        return {inf, inf, inf, inf, false};
    }

private:
    // NDC y points up, pixel y down: the largest NDC y is the top (smallest pixel y).
    ScreenBox fromNdc(double xMin, double xMax, double yMin, double yMax) const {
        const double halfW = 0.5 * mWidth, halfH = 0.5 * mHeight;
        return {(xMin + 1.0) * halfW, (xMax + 1.0) * halfW, (1.0 - yMax) * halfH, (1.0 - yMin) * halfH, false};
    }

    // Rows of the view-projection matrix (clip x, y, w, and z + w: >= 0 in front of the near
    // plane) and their elementwise absolute values for the half extents.
    glm::dvec4 mRowX, mRowY, mRowW, mRowNear;
    glm::dvec3 mAbsX, mAbsY, mAbsW, mAbsNear;
    // The frustum's planes as rows of clip coordinates, each >= 0 inside: w + x, w - x, w + y,
    // w - y, w + z (the near plane), w - z.
    glm::dvec4 mPlane[6];
    // Whether the box of centre p and half extents d lies wholly outside one of the planes: the
    // largest value of the plane's row over its corners (linear in the corner) is below zero by
    // more than the rounding of the sums that make it.
    bool outsideFrustum(const glm::dvec3& p, const glm::dvec3& d) const;
    ScreenBox estimate(const glm::dvec3& p, const glm::dvec3& d, double dmx, double dmy, double dmw, double dmNear) const {
        const double pmw = apply(mRowW, p);
        // The smallest w and z + w over the corners, exactly: each is linear in the corner.
        if (!(pmw - dmw > 0.0) || !(apply(mRowNear, p) - dmNear > 0.0))
            return outsideFrustum(p, d) ? outsideBox() : nearPlaneBox();
        const double fNear = 1.0 / (pmw - dmw), fFar = 1.0 / (pmw + dmw);
        const double pmx = apply(mRowX, p), pmy = apply(mRowY, p);
        // Fig. 6: a positive numerator is farthest from zero over the smallest w, a negative
        // one nearest to zero over the largest, and conversely for the minimum.
        auto over = [](double t, double f1, double f2) { return t > 0.0 ? t * f1 : t * f2; };
        return fromNdc(over(pmx - dmx, fFar, fNear), over(pmx + dmx, fNear, fFar), over(pmy - dmy, fFar, fNear),
                       over(pmy + dmy, fNear, fFar));
    }
    int mWidth, mHeight;
};

// The box of `count` (>= 1) points on the image plane, in pixels (a projected polygon's).
inline ScreenBox boxOfPoints(const glm::dvec2* p, int count) {
    ScreenBox box{p[0].x, p[0].x, p[0].y, p[0].y, false};
    for (int k = 1; k < count; ++k) {
        box.left = std::min(box.left, p[k].x);
        box.right = std::max(box.right, p[k].x);
        box.top = std::min(box.top, p[k].y);
        box.bottom = std::max(box.bottom, p[k].y);
    }
    return box;
}

// Fig. 4 applies to boxes smaller than two pixels each way (never to one crossing the near
// plane).
inline bool isSubPixel(const ScreenBox& box) {
    return !box.crossesNearPlane && box.width() < 2.0 && box.height() < 2.0;
}

// SAGE §3.3, Fig. 4, per axis as printed:
//     l = trunc(left); if (left - l >= 0.5) l++;
//     if (l + 0.5 < right && right < l + 1.5) point at pixel l, else ignore
// i.e. l + 0.5 is the first pixel centre strictly right of left, and the box is a point when
// that centre lies strictly inside and the next one (l + 1.5) does not reach right. Returns
// the pixel (column, row) whose centre the box covers when that holds on both axes.
// Returns nullopt when the box is not sub-pixel, or covers no centre on an axis (the node adds
// nothing at this resolution: drop it), or covers two centres on an axis (a centre exactly at
// right counts, one exactly at left does not): such a node is not a point, and the caller must
// refine or extract it instead.
// floor replaces the paper's trunc: the two agree for left >= 0, and floor stays right for
// boxes hanging over the left or top image border (trunc(-0.7) = 0 would skip the centre at
// -0.5). The pixel may lie outside the image: the caller checks it against the image (and the
// occlusion pyramid) before emitting the point and marking the pixel. (A box more than 1e9
// pixels off the image gets nullopt: it has no int pixel index and no visible centre.)
std::optional<glm::ivec2> subPixelPoint(const ScreenBox& box);

}  // namespace vdiso
