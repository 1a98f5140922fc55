// The walk of the min/max tree that a view-dependent extraction takes (docs/design.md, "One frame, view-dependent"): one
// step pops the nearest node still to visit and decides it: outside the extraction's region,
// culled by tests 1-3 (range, frustum, sub-pixel, occlusion: core/view/view_culler.h, against the
// pyramid as it is now), descended (its children pushed far first, so the nearest pops next),
// or shown as a brick at the level ViewLevels picks for it, unless that brick's sub-blocks all
// fail. The traversal (core/extract/extract_view.cpp) and its look-ahead (core/extract/brick_look_ahead.h) each
// walk with a cursor of their own, so the look-ahead finds bricks in the order the traversal
// visits them by construction; only when they run does the pyramid differ, and coverage only
// grows.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

#include "core/trees/minmax_tree.h"
#include "core/view/view_culler.h"
#include "core/lod/view_levels.h"

namespace vdiso {

class TraversalCursor {
public:
    enum class Outcome {
        OutsideRegion,  // outside ViewLevels' region
        Culled,         // by the test in `cull`
        Descended,      // its children are pushed
        NotShown,       // a brick whose sub-blocks all fail tests 1-3
        Brick,          // a brick to extract: `at`
    };
    struct Step {
        uint32_t node = 0;  // the tree node decided
        Outcome outcome = Outcome::Culled;
        Cull cull = Cull::None;
        glm::dvec3 a{0.0}, b{0.0};  // its world box
        ScreenBox box{};            // its screen box (when tests 1-3 ran)
        ViewLevels::Brick at{};     // Brick, NotShown: the brick
    };

    // `culler`: level 0's (ViewLevels::culler(0)), whose grid is the tree's.
    TraversalCursor(const MinMaxTree& tree, const ViewLevels& levels, const ViewCuller& culler);

    // Whether no node is left to visit.
    bool ended() const { return mStack.empty(); }
    // Decides the nearest node still to visit; false when none is left.
    bool step(Step& s);
    // Moves on to the next brick to extract; false at the end of the walk.
    bool nextBrick(Step& s) {
        while (step(s))
            if (s.outcome == Outcome::Brick) return true;
        return false;
    }
    // Tests 1-3 again for a node a step showed, and its brick's sub-blocks: whether it shows
    // with the pyramid as it is now (its screen box into `box` when given).
    bool stillShows(uint32_t node, const ViewLevels::Brick& at, ScreenBox* box = nullptr) const;

    const ViewCuller& culler() const { return mCuller; }

private:
    const MinMaxTree& mTree;
    const ViewLevels& mLevels;
    const ViewCuller& mCuller;
    std::vector<uint32_t> mStack;  // nodes still to visit, nearest on top
};

}  // namespace vdiso
