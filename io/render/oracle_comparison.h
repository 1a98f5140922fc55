// A view-dependent extraction against the visible-surface oracle (core/extract/visible_oracle.h): the
// full surface is extracted (octree) and rendered from the same camera, its depth buffer
// mapped back to the cells and bricks it shows. What `vdiso extract --oracle` reports and
// bench/views.sh tabulates.
#pragma once

#include <cstdint>

#include "core/brick_source.h"
#include "core/camera.h"
#include "core/extract/visible_oracle.h"

namespace vdiso {

struct OracleComparison {
    VisibleSurfaceOracle oracle;
    uint64_t fullTriangles = 0;  // of the whole surface
};

OracleComparison compareWithOracle(BrickSource& source, const Camera& camera, double iso,
                                   int metaCellSize, int threads);

}  // namespace vdiso
