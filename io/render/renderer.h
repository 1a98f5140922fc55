// Headless rendering of extracted surfaces (OSMesa, Mesa's software rasteriser).
//
// Draws triangles and points (SAGE §3.3: sub-pixel parts of the surface drawn as single points)
// with their normals, lit by a headlight at the eye plus a little ambient light. Lighting is
// two-sided: a surface seen from behind (its normal pointing away from the eye) shades like its
// front, so the inside of a cut-open skull reads as well as the outside. Triangles use GL's
// two-sided light model, which needs the mesh contract of core/mesh.h (counter-clockwise seen
// from the side the normal points to); points have no winding, so their normals are turned
// towards the eye before drawing. No face culling, depth test on.
//
// Images follow core/camera.h's pixel convention (top row first); depth is window depth in
// [0,1], the same number Camera::project() returns for the surface point seen in a pixel's
// centre, and exactly 1 where nothing was drawn. A camera without clip planes gets planes fitted
// to the bounds of the geometry (fitClipPlanes); the output is then exactly that of rendering
// with the fitted camera.
//
// Thread-safety: one GL context serves the process; concurrent calls are serialised by an
// internal lock. Throws std::invalid_argument for an image side outside 1..kMaxRenderSide or
// mismatched array sizes, std::runtime_error if OSMesa cannot make a context or runs out of
// memory.
#pragma once

#include <vector>

#include <glm/vec3.hpp>

#include "core/camera.h"
#include "core/mesh.h"
#include "io/render/png_image.h"

namespace vdiso {

constexpr int kMaxRenderSide = 4096;

struct RenderStyle {
    glm::vec3 surfaceColor{0.89f, 0.85f, 0.76f};  // bone / skin, in [0,1]
    glm::vec3 background{0.08f, 0.08f, 0.09f};
    float pointSize = 1.0f;  // pixels; each point covers a square this wide
    float ambient = 0.15f;   // fraction of surfaceColor seen without any direct light
};

struct RenderResult {
    RgbaImage image;           // camera.width x camera.height, alpha 255 everywhere
    std::vector<float> depth;  // one per pixel, top row first; 1 = nothing drawn
    double drawSeconds = 0.0;  // the draw calls (with the vertex transfers they imply)
                               // through glFinish(); excludes context setup and read-back
    Camera camera;             // the camera used, with its clip planes filled in
};

RenderResult renderSurface(const TriangleMesh& mesh, const PointSet& points, const Camera& camera,
                           const RenderStyle& style = {});

}  // namespace vdiso
