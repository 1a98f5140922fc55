// A pinhole camera: where it looks from, the image it makes, and how world points map to pixels.
//
// Pixel convention (the renderer, the PNG writer and the occlusion pyramid all share it):
//   x grows to the right and y DOWN, from the top-left corner of the image, in pixel units, as
//   images are stored (top row first). Pixel (i, j) is column i, row j and covers
//   [i, i+1) x [j, j+1); its centre is (i + 0.5, j + 0.5). The whole image is [0,w] x [0,h].
//   Depth is OpenGL window depth: 0 at the near plane, 1 at the far plane (non-linear in
//   distance), exactly what the renderer reads back from its depth buffer.
//
// Matrices are OpenGL-style (GLM, right-handed eye space looking down -z, clip z in [-w, w]).
// A camera whose zNear <= 0 or zFar <= zNear has no clip planes yet: fitClipPlanes() derives
// them from the bounds of what is drawn; until then projectionMatrix() uses a fallback of
// [d/1000, d*1000] around the eye-to-target distance d.
// Everything here is pure: safe to call from any thread.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <glm/mat4x4.hpp>
#include <glm/mat3x3.hpp>
#include <glm/vec3.hpp>

#include "core/volume.h"

namespace vdiso {

struct Camera {
    glm::dvec3 eye{0.0, 1.0, 0.0};
    glm::dvec3 target{0.0, 0.0, 0.0};
    glm::dvec3 up{0.0, 0.0, 1.0};  // need not be orthogonal to the view direction, not parallel
    double fovYDegrees = 30.0;     // full vertical field of view
    int width = 800;               // image size in pixels
    int height = 600;
    double zNear = 0.0;  // distances from the eye along the view direction; <= 0: not set
    double zFar = 0.0;

    double aspect() const { return double(width) / double(height); }
    bool hasClipPlanes() const { return zNear > 0.0 && zFar > zNear; }
    // Unit vector from the eye towards the target.
    glm::dvec3 forward() const;

    glm::dmat4 viewMatrix() const;
    glm::dmat4 projectionMatrix() const;
    glm::dmat4 viewProjection() const { return projectionMatrix() * viewMatrix(); }

    // (x, y, depth) in the pixel convention above. Points on or behind the eye plane have no
    // image: all three components are NaN (comparisons with them are false, so they are never
    // "inside the image"). Points outside the view volume get coordinates outside [0,w]x[0,h]
    // or a depth outside [0,1].
    glm::dvec3 project(const glm::dvec3& world) const;
    // The inverse: the world point at pixel position (x, y) and window depth.
    glm::dvec3 unproject(const glm::dvec3& pixelAndDepth) const;
};

// A camera's projection with its matrices computed once: for the hot loops that project every
// vertex (Camera::project rebuilds them on each call). Same conventions as Camera::project.
class PixelProjector {
public:
    explicit PixelProjector(const Camera& camera);
    glm::dvec3 project(const glm::dvec3& world) const;
    glm::dvec3 unproject(const glm::dvec3& pixelAndDepth) const;

private:
    glm::dmat4 mViewProjection, mInverse;
    double mWidth, mHeight;
};

// Every picture a camera makes is kMinImageSide to kMaxImageSide pixels each way: the command
// line's --size, camera files, the viewer's VIEW and Python take this one range.
constexpr int kMinImageSide = 16, kMaxImageSide = 8192;
// World units between eye and target at most (farther, the projection's arithmetic overflows).
constexpr double kMaxEyeDistance = 1e15;

// What keeps `camera` from making a picture, in words that name its fields (eye, target, up,
// fov, width, height), or "" when it can: eye, target and up finite; fov in (0, 180) degrees;
// each image side in [kMinImageSide, kMaxImageSide]; eye and target apart, by at most
// kMaxEyeDistance; up neither zero nor parallel to target - eye; clip planes, when either is
// set (not 0), 0 < near < far. The one check of a camera that comes from outside (a camera
// file, a VIEW message, Python); a camera may have no clip planes yet.
std::string cameraProblem(const Camera& camera);

// Sets zNear and zFar so that the box [boundsMin, boundsMax] lies between them with a 1% margin.
// When the eye is inside the box or close to it, zNear is clamped to zFar / 1000 to keep depth
// precision (24-bit buffers); geometry nearer than that is clipped.
void fitClipPlanes(Camera& camera, const glm::dvec3& boundsMin, const glm::dvec3& boundsMax);

}  // namespace vdiso
