// The visible-surface oracle: the least a view-dependent extraction must produce and read.
//
// From the depth buffer of the full surface rendered from a camera, every covered pixel is
// mapped back to the world point it shows and so to the cell and the brick holding it. Those
// cells' triangles are the least any view-dependent method must extract for the picture to be
// complete, and those bricks the least it must read (docs/design.md, "Testing and measuring").
// Depth precision can move a point into a neighbouring cell, which only lowers the bound.
#pragma once

#include <cstdint>
#include <span>

#include "core/brick_source.h"
#include "core/camera.h"

namespace vdiso {

struct VisibleSurfaceOracle {
    uint64_t pixels = 0;     // covered pixels
    uint64_t cells = 0;      // distinct cells they show (active or not, after depth rounding)
    uint64_t triangles = 0;  // triangles of those cells (the fan form)
    uint64_t bricks = 0;     // distinct bricks holding them
};

// `depth`: camera.width * camera.height window depths, top row first, 1 = nothing drawn (as
// io/renderer returns them). Acquires the bricks of the visible cells to count triangles.
VisibleSurfaceOracle visibleSurfaceOracle(BrickSource& source, const Camera& camera,
                                          std::span<const float> depth, double iso);

}  // namespace vdiso
