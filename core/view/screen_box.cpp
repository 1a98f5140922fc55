#include "core/view/screen_box.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

namespace vdiso {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

glm::dvec4 row(const glm::dmat4& m, int r) { return {m[0][r], m[1][r], m[2][r], m[3][r]}; }


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
      mPlane{mRowW + mRowX, mRowW - mRowX, mRowW + mRowY, mRowW - mRowY, mRowNear, mRowW - row(viewProjection, 2)},
      mWidth(width),
      mHeight(height) {}

bool BoxProjector::outsideFrustum(const glm::dvec3& p, const glm::dvec3& d) const {
    for (const glm::dvec4& plane : mPlane) {
        const glm::dvec3 a = glm::abs(glm::dvec3(plane));
        const double most = apply(plane, p) + glm::dot(a, d);
        const double magnitude = glm::dot(a, glm::abs(p)) + std::abs(plane.w) + glm::dot(a, d);
        if (most < -1e-12 * magnitude) return true;
    }
    return false;
}

ScreenBox BoxProjector::exactBox(const glm::dvec3& lo, const glm::dvec3& hi) const {
    double xMin = kInf, xMax = -kInf, yMin = kInf, yMax = -kInf;
    for (int corner = 0; corner < 8; ++corner) {
        const glm::dvec3 p{corner & 1 ? hi.x : lo.x, corner & 2 ? hi.y : lo.y,
                           corner & 4 ? hi.z : lo.z};
        const double w = apply(mRowW, p);
        if (!(w > 0.0) || !(apply(mRowNear, p) > 0.0))
            return outsideFrustum(0.5 * (lo + hi), 0.5 * (hi - lo)) ? outsideBox() : nearPlaneBox();
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
    return estimate(0.5 * (lo + hi), d, glm::dot(mAbsX, d), glm::dot(mAbsY, d), glm::dot(mAbsW, d),
                    glm::dot(mAbsNear, d));
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
