// How a volume is cut into bricks, and which samples each brick carries.
//
// Brick (i,j,k) owns the cells [iB, (i+1)B) on each axis (fewer in the last brick of an axis).
// It stores B+3 samples per axis, from iB-1 to iB+B+1: the B+1 corners of its cells plus one
// ghost before and one after, so central-difference normals at every corner, and so every cell,
// can be computed without touching a neighbour. Indices outside the volume are clamped to the
// border, which makes the gradient one-sided there. Every brick has the same (B+3)^3 shape.
#pragma once

#include <algorithm>
#include <cstdint>
#include <string>

#include "core/volume.h"

namespace vdiso {

constexpr int kGhostBefore = 1;
constexpr int kGhostAfter = 2;

// What the min/max tree (core/trees/minmax_tree.h: 16-bit brick coordinates, 32-bit node numbers)
// can index: at most 65,535 bricks along an axis and 2^31 in all.
constexpr int64_t kMaxBricksPerAxis = 65535;
constexpr int64_t kMaxBricks = int64_t(1) << 31;

struct BrickLayout;
// "" when the layout is within the limits above, else what is wrong and what to do, in words.
// `dims` must be within core/volume.h's limits.
inline std::string brickLayoutProblem(const BrickLayout& layout);

struct BrickLayout {
    Dims3 dims{0, 0, 0};        // samples per axis
    int brickSize = 32;         // B: cells per brick side
    Dims3 brickCounts{0, 0, 0}; // bricks per axis

    BrickLayout() = default;
    BrickLayout(const Dims3& sampleDims, int cellsPerBrick) : dims(sampleDims), brickSize(cellsPerBrick) {
        for (int a = 0; a < 3; ++a) brickCounts[a] = (dims[a] - 1 + brickSize - 1) / brickSize;
    }

    // Throws std::overflow_error rather than wrap (dims beyond core/volume.h's limits).
    int64_t brickCount() const {
        return checkedMul(checkedMul(brickCounts[0], brickCounts[1]), brickCounts[2]);
    }
    int side() const { return brickSize + kGhostBefore + kGhostAfter; }
    int64_t samplesPerBrick() const { return int64_t(side()) * side() * side(); }
    // Index in a brick's sample array (side^3, x fastest) of its cell corner (cx, cy, cz),
    // local to the brick, the ghost samples before it accounted for.
    static size_t cornerIndex(int side, int cx, int cy, int cz) {
        return (size_t(cz + kGhostBefore) * size_t(side) + size_t(cy + kGhostBefore)) * size_t(side) +
               size_t(cx + kGhostBefore);
    }

    // Bricks are numbered x fastest, then y, then z, which is also their order in the file.
    int64_t brickId(int64_t i, int64_t j, int64_t k) const {
        return i + brickCounts[0] * (j + brickCounts[1] * k);
    }
    Dims3 brickCoord(int64_t id) const {
        return {id % brickCounts[0], (id / brickCounts[0]) % brickCounts[1],
                id / (brickCounts[0] * brickCounts[1])};
    }

    // Global sample index of a brick's first stored sample on any axis, given its brick
    // coordinate on that axis (may be -1: clamped to the border).
    int64_t firstSample(int64_t coord) const { return coord * brickSize - kGhostBefore; }

    // Cells the brick owns on `axis`: B, or fewer in the last brick.
    int cellsOnAxis(int axis, int64_t coord) const {
        return int(std::min<int64_t>(brickSize, dims[axis] - 1 - coord * brickSize));
    }

    // Samples the brick owns on `axis` when each sample is counted once across the volume:
    // B, except the last brick which also owns the volume's last sample.
    int ownedSamplesOnAxis(int axis, int64_t coord) const {
        return coord == brickCounts[axis] - 1 ? cellsOnAxis(axis, coord) + 1 : brickSize;
    }

    int64_t clampSample(int axis, int64_t s) const { return std::clamp<int64_t>(s, 0, dims[axis] - 1); }
};

inline std::string brickLayoutProblem(const BrickLayout& layout) {
    static const char* kAxis[3] = {"x", "y", "z"};
    const std::string size = std::to_string(layout.dims[0]) + " x " + std::to_string(layout.dims[1]) +
                             " x " + std::to_string(layout.dims[2]) + " samples in bricks of " +
                             std::to_string(layout.brickSize) + " cells";
    for (int a = 0; a < 3; ++a)
        if (layout.brickCounts[a] > kMaxBricksPerAxis)
            return size + " make " + std::to_string(layout.brickCounts[a]) + " bricks along " +
                   kAxis[a] + "; vdiso indexes at most 65535 bricks per axis (use larger bricks)";
    if (layout.brickCount() > kMaxBricks)
        return size + " make " + std::to_string(layout.brickCount()) +
               " bricks; vdiso indexes at most 2^31 (use larger bricks)";
    return "";
}

// A box of bricks, [lo, hi) on each axis of their coordinates: the part of the volume one
// extraction covers when the volume is shared among processes (object-space partition, mpi/).
struct BrickRegion {
    int64_t lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
    // Whether the box of bricks [boxLo, boxHi) shares a brick with this one.
    template <class Coord>
    bool meets(const Coord (&boxLo)[3], const Coord (&boxHi)[3]) const {
        for (int a = 0; a < 3; ++a)
            if (int64_t(boxHi[a]) <= lo[a] || int64_t(boxLo[a]) >= hi[a]) return false;
        return true;
    }
};

}  // namespace vdiso
