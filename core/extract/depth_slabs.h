// Sharing one view-dependent extraction among processes by parts of the volume (object-space
// partition, mpi/): slabs of level-0 bricks along the axis nearest the view direction, each
// process extracting its own (ViewExtractOptions::region) and taking in the coverage of the
// slabs in front of it as they are made (ViewExtractOptions::coverage).
//
// Why slabs: with the eye in slab e (clamped to the first or last when the eye is outside
// them), a ray from the eye crosses slabs e, e+1, ... or e, e-1, ... in that order, so only the
// slabs between a slab and the eye can hide anything in it, whatever the camera. Slab e itself
// has nothing in front. The axis nearest the view direction makes the slabs' overlap on screen,
// and so what front slabs hide in back ones, the largest.
#pragma once

#include <vector>

#include "core/brick_layout.h"
#include "core/brick_source.h"
#include "core/camera.h"

namespace vdiso {

struct DepthSlabs {
    int axis = 2;
    std::vector<int64_t> cuts;  // slabs + 1 level-0 brick coordinates along axis, 0 to the count
    int eyeSlab = 0;            // the slab holding the eye, clamped to the first or last

    int count() const { return int(cuts.size()) - 1; }
    // Slab s as a region of level-0 bricks (empty when it has no layer).
    BrickRegion region(int s, const BrickLayout& layout) const;
    // Whether slab `front` lies between the eye and slab s, so that it may hide some of it.
    bool inFront(int front, int s) const {
        if (s > eyeSlab) return front >= eyeSlab && front < s;
        if (s < eyeSlab) return front <= eyeSlab && front > s;
        return false;
    }
};

// `slabs` slabs along the axis of the largest component of the camera's view direction, cut
// between layers of bricks so that each holds about as many active bricks (range holding iso)
// as the others; with fewer layers than slabs, the last slabs are empty.
DepthSlabs depthSlabs(const BrickSource& source, const Camera& camera, double iso, int slabs);

}  // namespace vdiso
