// Points for the thin parts a coarse level of detail loses (docs/design.md, "One frame,
// view-dependent", step 5).
//
// The levels' filter (core/lod/downsample.h) averages a part thinner than a coarse cell (a plate
// one or two voxels thick: a CT's head holder or table) towards its background; where its
// averaged peak no longer reaches the isovalue, the coarse level's surface has a hole there, or
// the part is gone. Where a view takes a coarse level, its cells span at most a pixel or so, so
// what was lost is drawn as points, one per coarse sample on the lost part, without reading the
// finer bricks: a finer level's sub-block ranges (core/trees/sub_blocks.h, in the store's index)
// say where the surface is, the coarse samples where it went.
//
// Level m = l - levelsBetween is compared with level l: each of level m's sub-blocks under the
// coarse brick whose range crosses the isovalue clearly (crossesClearly) where the coarse corner
// samples of the cells meeting its box keep less than kKeptReach of its reach beyond it (none,
// or strips). In that box, the coarse samples on the lost part become points: on the lost side
// of the isovalue, at least halfway from the box's other extreme towards the part, and a ridge
// (or a valley) across it. Across is the direction in which the samples fall away fastest (the
// Hessian's eigenvector of largest curvature), which is also the point's normal, turned towards
// the eye. A thick part's edge is a slope, not a ridge: it gives no points.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <span>
#include <vector>

#include <glm/vec3.hpp>

#include "core/brick_source.h"
#include "core/mesh.h"
#include "core/trees/brick_memo.h"

namespace vdiso {

// Whether a range crosses iso by more than a graze: beyond it on each side by at least
// kClearCrossing of its reach on the other. A finer level's surface where its samples only
// graze the isovalue is a speck a cell or two across, which a coarse level may drop unseen.
constexpr double kClearCrossing = 0.15;
// A coarse box that keeps less than this of the fine samples' reach beyond the isovalue has lost
// its part, or kept it in strips.
constexpr double kKeptReach = 0.5;
inline bool crossesClearly(const BrickRange& r, double iso) {
    const double up = double(r.maxValue) - iso, down = iso - double(r.minValue);
    return up > 0 && down >= 0 && std::min(up, down) >= kClearCrossing * std::max(up, down);
}

// A box of a coarse brick's corners [lo, hi] (inclusive on each axis) where the coarse level
// lost a part: a peak (sign -1) or a trough (+1), the coarse samples there running from `least`
// to `most`. What the view does not change: found once for a brick and isovalue, with the
// corners of the box that become points (found the first time the box shows, then kept with
// it), their normals turned to the eye for each camera.
struct LostPart {
    struct Ridges {
        std::once_flag found;
        std::vector<std::array<int16_t, 3>> corners;  // z, then y, then x order
    };
    int lo[3], hi[3];
    double sign, least, most;
    std::shared_ptr<Ridges> ridges = std::make_shared<Ridges>();
};

// Lost parts kept across the frames of a camera, by brick and isovalue (core/trees/brick_memo.h).
using LostPartMemo = BrickMemo<std::vector<LostPart>>;

// The boxes of coarse brick `brick` (in `coarse`'s numbering; `samples` its samples) where the
// surface of `fine` (the level levelsBetween >= 1 finer) is lost.
std::vector<LostPart> findLostParts(const BrickSource& coarse, int64_t brick, const void* samples, const BrickSource& fine,
                                    int levelsBetween, double iso);

// Appends the points of `parts` (findLostParts' for the same brick, samples and isovalue), box
// by box in their order; `eye` in world units. `shows` (if given) is asked about each box (its
// world corners) before its corners are looked at, and `wanted` about each point's position
// before its normal is worked out. Safe from several threads on the same parts.
void appendLostPartPoints(const BrickSource& coarse, int64_t brick, const void* samples, std::span<const LostPart> parts,
                          double iso, const glm::dvec3& eye, PointSet& out,
                          const std::function<bool(const glm::dvec3&)>& wanted = nullptr,
                          const std::function<bool(const glm::dvec3&, const glm::dvec3&)>& shows = nullptr);

}  // namespace vdiso
