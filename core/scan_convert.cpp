#include "core/scan_convert.h"

#include "core/occlusion_pyramid.h"

namespace vdiso {

void scanConvertPolygon(std::span<const glm::dvec2> vertices, OcclusionPyramid& pyramid) {
    scanConvertPolygon(vertices, pyramid.width(), pyramid.height(),
                       [&pyramid](int y, int x0, int x1) { pyramid.coverSpan(y, x0, x1); });
}

}  // namespace vdiso
