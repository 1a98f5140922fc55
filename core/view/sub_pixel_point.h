// SAGE's point rule (paper Fig. 4): a box of the traversal under two pixels each way that
// covers exactly one pixel centre is drawn as one point instead of being refined. The point
// goes where that centre's ray first meets the surface in the box, with the field's normal
// there, so it draws on the pixel the pyramid marks, shaded as the triangles it stands for.
// A box covering two centres is refined like any other.
#pragma once

#include <algorithm>
#include <optional>
#include <utility>

#include <glm/vec3.hpp>

#include "core/kernel/brick_kernel.h"
#include "core/camera.h"
#include "core/view/first_hit.h"
#include "core/mesh.h"
#include "core/view/occlusion_pyramid.h"
#include "core/view/screen_box.h"

namespace vdiso {

enum class PointRule {
    NotAPoint,  // refine the box as any other
    Dropped,    // its centre is covered, off the image, or its ray meets no surface in the box
    Drawn,      // a point was added to `points` (and, with markPyramid, its pixel covered)
};

// The rule for a box [a, b] (world) whose screen box is `box`, the surface in it that of
// `kernel`'s brick.
template <class T>
PointRule applyPointRule(const ScreenBox& box, const glm::dvec3& a, const glm::dvec3& b,
                         const BrickKernel<T>& kernel, const PixelProjector& pixels, OcclusionPyramid& pyramid,
                         bool markPyramid, PointSet& points) {
    if (!isSubPixel(box)) return PointRule::NotAPoint;
    const std::optional<glm::ivec2> p = subPixelPoint(box);
    if (!p) return PointRule::NotAPoint;
    if (p->x < 0 || p->y < 0 || p->x >= pyramid.width() || p->y >= pyramid.height() || pyramid.isCovered(p->x, p->y))
        return PointRule::Dropped;
    // The ray through the pixel centre, clipped to the box (slabs).
    const glm::dvec3 nearPoint = pixels.unproject({p->x + 0.5, p->y + 0.5, 0.0});
    const glm::dvec3 farPoint = pixels.unproject({p->x + 0.5, p->y + 0.5, 1.0});
    const glm::dvec3 direction = farPoint - nearPoint;
    double t0 = 0.0, t1 = 1.0;
    for (int k = 0; k < 3; ++k) {
        if (direction[k] == 0.0) {
            if (nearPoint[k] < a[k] || nearPoint[k] > b[k]) return PointRule::Dropped;
            continue;
        }
        double ta = (a[k] - nearPoint[k]) / direction[k], tb = (b[k] - nearPoint[k]) / direction[k];
        if (ta > tb) std::swap(ta, tb);
        t0 = std::max(t0, ta);
        t1 = std::min(t1, tb);
    }
    glm::vec3 position, normal;
    if (t0 > t1 || !firstHit(kernel, nearPoint, direction, t0, t1, position, normal)) return PointRule::Dropped;
    points.positions.push_back(position);
    points.normals.push_back(normal);
    if (markPyramid) {
        pyramid.coverSpan(p->y, p->x, p->x);
        pyramid.propagate();
    }
    return PointRule::Drawn;
}

}  // namespace vdiso
