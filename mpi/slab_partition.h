// Which slices and layers of bricks each rank of `vdiso-mpi convert` reads, owns and encodes,
// at every level of detail (core/brick_levels.h): plain arithmetic, the same on every rank, so
// each rank knows every other's share without asking. Header-only, so it is tested without MPI.
//
// Level 0: its layers of bricks (z) are cut into one contiguous run per rank, the first
// (layers mod ranks) runs one longer; ranks beyond the layer count get none. Rank r owns the
// level-0 slices from its first layer's first cell slice up to the next rank's (the last rank
// with layers to the volume's end); it reads them, plus the ghosts its layers need (one slice
// before, two after), which its neighbours read too.
//
// Level l: rank r owns the slices s whose level-0 position min(2^l s, dims-1) lies in its
// level-0 range. So every slice has one owner, and the owner of level-(l+1) slice k also owns
// level-l slice 2k, the centre of the tent filter that makes it: it needs only slices 2k-1 and
// 2k+1 beside its own, at most one from each neighbour. Rank r encodes the level-l layers whose
// first cell slice it owns; a layer also needs one slice before and B+1 after (its ghosts and
// cells), which may belong to several ranks at coarse levels, where ranks own few slices or
// none. neededSlices() is the union: what a rank must hold of level l, its own slices and the
// halo the others send it.
#pragma once

#include <algorithm>
#include <cstdint>
#include <vector>

#include "core/brick_layout.h"
#include "core/brick_levels.h"

namespace vdiso::mpi {

// [begin, end); empty when begin >= end.
struct IndexRange {
    int64_t begin = 0, end = 0;
    bool empty() const { return begin >= end; }
    int64_t size() const { return std::max<int64_t>(0, end - begin); }
};

// Rank `rank`'s run of the `layers` level-0 layers among `ranks`.
inline IndexRange level0Layers(int64_t layers, int ranks, int rank) {
    const int64_t q = layers / ranks, extra = layers % ranks;
    auto first = [&](int64_t r) { return r * q + std::min(r, extra); };
    return {first(rank), first(rank + 1)};
}

// The level-`l` slices rank `rank` owns.
inline IndexRange ownedSlices(const std::vector<BrickLevel>& levels, int l, int ranks, int rank) {
    const BrickLayout& level0 = levels[0].layout;
    const int64_t n0 = level0.dims[2], n = levels[size_t(l)].volume.dims[2];
    const int64_t step = int64_t(1) << l;
    // The first level-0 slice a rank owns (n0 for a rank without layers after the last).
    auto level0Start = [&](int r) {
        if (r >= ranks) return n0;
        const int64_t layer = level0Layers(level0.brickCounts[2], ranks, r).begin;
        return layer >= level0.brickCounts[2] ? n0 : layer * level0.brickSize;
    };
    // The first level-l slice s with min(step s, n0 - 1) >= a.
    auto start = [&](int64_t a) { return a >= n0 ? n : (a + step - 1) / step; };
    return {start(level0Start(rank)), start(level0Start(rank + 1))};
}

// The level-`l` layers of bricks rank `rank` encodes: those whose first cell slice it owns.
inline IndexRange encodedLayers(const std::vector<BrickLevel>& levels, int l, int ranks, int rank) {
    const BrickLayout& layout = levels[size_t(l)].layout;
    const IndexRange owned = ownedSlices(levels, l, ranks, rank);
    const int64_t B = layout.brickSize, layers = layout.brickCounts[2];
    return {std::min(layers, (owned.begin + B - 1) / B), std::min(layers, (owned.end + B - 1) / B)};
}

// The level-`l` slices rank `rank` must hold: its own, one more on each side for the tent
// filter of the next level, and every slice of the layers it encodes (ghosts included); clamped
// to the level. Empty for a rank that owns none.
inline IndexRange neededSlices(const std::vector<BrickLevel>& levels, int l, int ranks, int rank) {
    const IndexRange owned = ownedSlices(levels, l, ranks, rank);
    if (owned.empty()) return {0, 0};
    const BrickLayout& layout = levels[size_t(l)].layout;
    const IndexRange layers = encodedLayers(levels, l, ranks, rank);
    int64_t last = owned.end;  // the slice after its own: 2k+1 of its last next-level slice
    if (!layers.empty()) last = std::max(last, layout.firstSample(layers.end - 1) + layout.side() - 1);
    return {std::max<int64_t>(0, owned.begin - kGhostBefore), std::min(layout.dims[2] - 1, last) + 1};
}

// The level-0 slices rank `rank` reads: every slice its layers need (empty without layers).
inline IndexRange level0ReadSlices(const BrickLayout& level0, int ranks, int rank) {
    const IndexRange layers = level0Layers(level0.brickCounts[2], ranks, rank);
    if (layers.empty()) return {0, 0};
    return {level0.clampSample(2, level0.firstSample(layers.begin)),
            std::min(level0.firstSample(layers.end - 1) + level0.side() - 1, level0.dims[2] - 1) + 1};
}

inline IndexRange intersect(const IndexRange& a, const IndexRange& b) {
    return {std::max(a.begin, b.begin), std::min(a.end, b.end)};
}

}  // namespace vdiso::mpi
