#include "core/screen_box.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

namespace vdiso {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

glm::dvec4 row(const glm::dmat4& m, int r) { return {m[0][r], m[1][r], m[2][r], m[3][r]}; }

double apply(const glm::dvec4& r, const glm::dvec3& p) {
    return r.x * p.x + r.y * p.y + r.z * p.z + r.w;
}

// Fig. 6: f1, f2 are 1 / w at the two ends of the w range. A positive numerator is farthest
// from zero over the smallest w, a negative one nearest to zero over the largest, and
// conversely for the minimum (the callers swap f1 and f2).
double compute(double t, double f1, double f2) { return t > 0.0 ? t * f1 : t * f2; }

ScreenBox nearPlaneBox() { return {-kInf, kInf, -kInf, kInf, true}; }

}  // namespace

BoxProjector::BoxProjector(const Camera& camera)
    : BoxProjector(camera.viewProjection(), camera.width, camera.height) {}

BoxProjector::BoxProjector(const glm::dmat4& viewProjection, int width, int height)
    : mRowX(row(viewProjection, 0)),
      mRowY(row(viewProjection, 1)),
      mRowW(row(viewProjection, 3)),
      mRowNear(row(viewProjection, 2) + row(viewProjection, 3)),
      mAbsX(glm::abs(glm::dvec3(mRowX))),
      mAbsY(glm::abs(glm::dvec3(mRowY))),
      mAbsW(glm::abs(glm::dvec3(mRowW))),
      mAbsNear(glm::abs(glm::dvec3(mRowNear))),
      mUnitX(glm::dot(mAbsX, glm::dvec3(0.5))),
      mUnitY(glm::dot(mAbsY, glm::dvec3(0.5))),
      mUnitW(glm::dot(mAbsW, glm::dvec3(0.5))),
      mUnitNear(glm::dot(mAbsNear, glm::dvec3(0.5))),
      mWidth(width),
      mHeight(height) {}

// NDC y points up, pixel y down: the largest NDC y is the top (smallest pixel y).
ScreenBox BoxProjector::fromNdc(double xMin, double xMax, double yMin, double yMax) const {
    const double halfW = 0.5 * mWidth, halfH = 0.5 * mHeight;
    return {(xMin + 1.0) * halfW, (xMax + 1.0) * halfW, (1.0 - yMax) * halfH,
            (1.0 - yMin) * halfH, false};
}

ScreenBox BoxProjector::exactBox(const glm::dvec3& lo, const glm::dvec3& hi) const {
    double xMin = kInf, xMax = -kInf, yMin = kInf, yMax = -kInf;
    for (int corner = 0; corner < 8; ++corner) {
        const glm::dvec3 p{corner & 1 ? hi.x : lo.x, corner & 2 ? hi.y : lo.y,
                           corner & 4 ? hi.z : lo.z};
        const double w = apply(mRowW, p);
        if (!(w > 0.0) || !(apply(mRowNear, p) > 0.0)) return nearPlaneBox();
        const double x = apply(mRowX, p) / w, y = apply(mRowY, p) / w;
        xMin = std::min(xMin, x);
        xMax = std::max(xMax, x);
        yMin = std::min(yMin, y);
        yMax = std::max(yMax, y);
    }
    return fromNdc(xMin, xMax, yMin, yMax);
}

ScreenBox BoxProjector::estimateBox(const glm::dvec3& lo, const glm::dvec3& hi) const {
    const glm::dvec3 d = 0.5 * (hi - lo);
    return estimate(0.5 * (lo + hi), glm::dot(mAbsX, d), glm::dot(mAbsY, d), glm::dot(mAbsW, d),
                    glm::dot(mAbsNear, d));
}

ScreenBox BoxProjector::estimateUnitBox(const glm::dvec3& lo) const {
    return estimate(lo + 0.5, mUnitX, mUnitY, mUnitW, mUnitNear);
}

ScreenBox BoxProjector::estimate(const glm::dvec3& p, double dmx, double dmy, double dmw,
                                 double dmNear) const {
    const double pmw = apply(mRowW, p);
    // The smallest w and z + w over the corners, exactly: each is linear in the corner.
    if (!(pmw - dmw > 0.0) || !(apply(mRowNear, p) - dmNear > 0.0)) return nearPlaneBox();
    const double fNear = 1.0 / (pmw - dmw), fFar = 1.0 / (pmw + dmw);
    const double pmx = apply(mRowX, p), pmy = apply(mRowY, p);
    return fromNdc(compute(pmx - dmx, fFar, fNear), compute(pmx + dmx, fNear, fFar),
                   compute(pmy - dmy, fFar, fNear), compute(pmy + dmy, fNear, fFar));
}

std::optional<glm::ivec2> subPixelPoint(const ScreenBox& box) {
    if (!isSubPixel(box)) return std::nullopt;
    // Fig. 4 on one axis: whether it holds, and the pixel index when it does.
    auto axis = [](double left, double right, int& pixel) {
        double l = std::floor(left);
        if (left - l >= 0.5) l += 1.0;
        if (!(l + 0.5 < right && right < l + 1.5)) return false;
        if (!(std::abs(l) < 1e9)) return false;  // far off the image: no int pixel index
        pixel = int(l);
        return true;
    };
    glm::ivec2 pixel;
    if (!axis(box.left, box.right, pixel.x) || !axis(box.top, box.bottom, pixel.y))
        return std::nullopt;
    return pixel;
}

}  // namespace vdiso
