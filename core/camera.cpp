#include "core/camera.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/matrix.hpp>
#include <glm/trigonometric.hpp>

namespace vdiso {

namespace {

constexpr double kClipMargin = 0.01;
constexpr double kMaxFarOverNear = 1000.0;

}  // namespace

glm::dvec3 Camera::forward() const { return glm::normalize(target - eye); }

glm::dmat4 Camera::viewMatrix() const { return glm::lookAt(eye, target, up); }

glm::dmat4 Camera::projectionMatrix() const {
    double n = zNear, f = zFar;
    if (!hasClipPlanes()) {
        const double d = glm::length(target - eye);
        n = d / kMaxFarOverNear;
        f = d * kMaxFarOverNear;
    }
    return glm::perspective(glm::radians(fovYDegrees), aspect(), n, f);
}

glm::dvec3 Camera::project(const glm::dvec3& world) const { return PixelProjector(*this).project(world); }

glm::dvec3 Camera::unproject(const glm::dvec3& pixelAndDepth) const {
    return PixelProjector(*this).unproject(pixelAndDepth);
}

PixelProjector::PixelProjector(const Camera& camera)
    : mViewProjection(camera.viewProjection()), mInverse(glm::inverse(mViewProjection)),
      mWidth(camera.width), mHeight(camera.height) {}

glm::dvec3 PixelProjector::project(const glm::dvec3& world) const {
    const glm::dvec4 clip = mViewProjection * glm::dvec4(world, 1.0);
    if (!(clip.w > 0.0)) return glm::dvec3(std::numeric_limits<double>::quiet_NaN());
    const glm::dvec3 ndc = glm::dvec3(clip) / clip.w;
    // The y flip turns OpenGL's bottom-up window coordinates into top-down image rows.
    return {(ndc.x * 0.5 + 0.5) * mWidth, (0.5 - ndc.y * 0.5) * mHeight, ndc.z * 0.5 + 0.5};
}

glm::dvec3 PixelProjector::unproject(const glm::dvec3& pixelAndDepth) const {
    const glm::dvec4 ndc{pixelAndDepth.x / mWidth * 2.0 - 1.0, 1.0 - pixelAndDepth.y / mHeight * 2.0,
                         pixelAndDepth.z * 2.0 - 1.0, 1.0};
    const glm::dvec4 world = mInverse * ndc;
    return glm::dvec3(world) / world.w;
}

std::string cameraProblem(const Camera& camera) {
    auto finite = [](const glm::dvec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); };
    if (!finite(camera.eye) || !finite(camera.target) || !finite(camera.up))
        return "eye, target and up must be finite numbers";
    if (!(camera.fovYDegrees > 0.0 && camera.fovYDegrees < 180.0)) return "fov must be in (0, 180) degrees";
    for (const int side : {camera.width, camera.height})
        if (side < kMinImageSide || side > kMaxImageSide)
            return "width and height must be " + std::to_string(kMinImageSide) + " to " +
                   std::to_string(kMaxImageSide) + " pixels, not " + std::to_string(camera.width) + " x " +
                   std::to_string(camera.height);
    const glm::dvec3 view = camera.target - camera.eye;
    const double distance = glm::length(view);
    if (!(distance > 0.0)) return "eye and target must differ";
    if (!(distance <= kMaxEyeDistance)) {
        char text[96];
        std::snprintf(text, sizeof text, "eye is too far from target (%.17g; at most %g)", distance, kMaxEyeDistance);
        return text;
    }
    const double upLength = glm::length(camera.up);
    if (!(upLength > 0.0) || !(glm::length(glm::cross(view / distance, camera.up / upLength)) >= 1e-9))
        return "up must not be zero nor parallel to the view direction (target - eye)";
    if ((camera.zNear != 0.0 || camera.zFar != 0.0) &&
        !(camera.zNear > 0.0 && camera.zFar > camera.zNear && std::isfinite(camera.zFar)))
        return "near and far must satisfy 0 < near < far";
    return "";
}

void fitClipPlanes(Camera& camera, const glm::dvec3& boundsMin, const glm::dvec3& boundsMax) {
    const glm::dvec3 f = camera.forward();
    double nearest = std::numeric_limits<double>::infinity();
    double farthest = -std::numeric_limits<double>::infinity();
    for (int corner = 0; corner < 8; ++corner) {
        const glm::dvec3 p{corner & 1 ? boundsMax.x : boundsMin.x,
                           corner & 2 ? boundsMax.y : boundsMin.y,
                           corner & 4 ? boundsMax.z : boundsMin.z};
        const double depth = glm::dot(p - camera.eye, f);
        nearest = std::min(nearest, depth);
        farthest = std::max(farthest, depth);
    }
    // A box wholly behind the eye (or a degenerate one at it) still gets valid planes.
    const double scale = std::max(glm::length(boundsMax - boundsMin),
                                  glm::length(camera.target - camera.eye));
    camera.zFar = std::max(farthest * (1.0 + kClipMargin), scale * kClipMargin);
    camera.zNear = std::max(nearest * (1.0 - kClipMargin), camera.zFar / kMaxFarOverNear);
}

}  // namespace vdiso
