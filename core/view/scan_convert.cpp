#include "core/view/scan_convert.h"

#include "core/view/occlusion_pyramid.h"

namespace vdiso {

bool scanConvertPolygon(std::span<const glm::dvec2> vertices, OcclusionPyramid& pyramid) {
    bool changed = false;
    scanConvertPolygon(vertices, pyramid.width(), pyramid.height(),
                       [&](int y, int x0, int x1) { changed |= pyramid.coverSpan(y, x0, x1); });
    return changed;
}

}  // namespace vdiso
