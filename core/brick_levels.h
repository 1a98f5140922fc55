// Levels of detail of a bricked volume (docs/design.md, "Trees over the bricks"; core/lod/view_levels.h).
//
// Level 0 is the volume. Level l has cells 2^l times larger: its sample s stands at level-0
// position s 2^l (clamped to the volume's last sample), so it has ceil((dims-1) / 2^l) cells
// per axis, and its bricks of the same B cells cover 2^l level-0 bricks per axis: level-l brick
// (i, j, k) covers level-0 bricks [2^l i, 2^l (i+1)) on each axis, clipped to the volume.
// Its samples are the level-(l-1) samples filtered by the separable tent [1/4, 1/2, 1/4]
// around 2s (core/lod/downsample.h). The bricks of every level share one numbering, level after
// level: level l's brick i is source brick firstBrick(l) + i.
#pragma once

#include <algorithm>
#include <cstdint>
#include <vector>

#include "core/brick_layout.h"
#include "core/volume.h"

namespace vdiso {

// At most this many levels (level 0 included): 2^15 level-0 bricks per axis, well past what
// the min/max tree indexes.
constexpr int kMaxLevels = 16;

// Samples per axis at level l of a volume of `dims` samples.
inline Dims3 levelDims(const Dims3& dims, int level) {
    Dims3 d;
    for (int a = 0; a < 3; ++a) {
        const int64_t cells = dims[a] - 1, step = int64_t(1) << level;
        d[a] = (cells + step - 1) / step + 1;
    }
    return d;
}

// Levels until the coarsest is one brick (level 0 included): `--levels auto`.
inline int levelsUntilOneBrick(const BrickLayout& level0) {
    int levels = 1;
    const int64_t most = std::max({level0.brickCounts[0], level0.brickCounts[1], level0.brickCounts[2]});
    while ((int64_t(1) << (levels - 1)) < most) ++levels;
    return levels;
}

struct BrickLevel {
    VolumeInfo volume;    // the level's samples: dims and spacing of its grid, same origin
    BrickLayout layout;   // its bricks
    int64_t firstBrick;   // its first brick's number among all levels' bricks
};

// The levels [0, count) of a volume in bricks of `brickSize` cells.
inline std::vector<BrickLevel> brickLevels(const VolumeInfo& volume, int brickSize, int count) {
    std::vector<BrickLevel> levels;
    int64_t first = 0;
    for (int l = 0; l < count; ++l) {
        VolumeInfo v = volume;
        v.dims = levelDims(volume.dims, l);
        v.spacing = volume.spacing * double(int64_t(1) << l);
        const BrickLayout layout(v.dims, brickSize);
        levels.push_back({v, layout, first});
        first += layout.brickCount();
    }
    return levels;
}

// The level that brick `id` (numbered through all levels) belongs to.
inline int levelOfBrick(const std::vector<BrickLevel>& levels, int64_t id) {
    int l = 0;
    while (l + 1 < int(levels.size()) && id >= levels[size_t(l) + 1].firstBrick) ++l;
    return l;
}

}  // namespace vdiso
