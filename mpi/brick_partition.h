// Sharing a full extraction's bricks among ranks: every rank computes the same partition from
// the store's index alone (no sample is read), and takes its part.
//
// The active bricks, in increasing id order as extractOctree visits them, are cut into
// contiguous runs, one per rank, balanced by a weight per brick: its sub-blocks whose range
// holds the isovalue (core/trees/sub_blocks.h; at least 1, and 1 for a store without sub-block
// ranges), which follows the surface's area in the brick better than a count of bricks.
// A contiguous run of ids (x fastest, then y, then z) is a slab of brick layers with ragged
// ends, so parts are spatially compact and meet at few brick faces. Contiguous runs in id order also keep the
// single process's vertex numbering: rank r's vertices follow rank r-1's (mpi/rank_weld.h).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "core/brick_source.h"

namespace vdiso::mpi {

struct BrickPartition {
    std::vector<int64_t> bricks;    // the active bricks, increasing ids
    std::vector<size_t> firsts;     // parts + 1 entries: part r is bricks[firsts[r], firsts[r+1])
    std::vector<uint64_t> weights;  // per active brick
    std::vector<int32_t> partOfBrick;  // per brick of the volume: its part, -1 when inactive

    int parts() const { return int(firsts.size()) - 1; }
    std::span<const int64_t> part(int r) const {
        return std::span<const int64_t>(bricks).subspan(firsts[size_t(r)], firsts[size_t(r) + 1] - firsts[size_t(r)]);
    }
    uint64_t weightOf(int r) const;
};

// The weight of each of `bricks` at `iso` (see above).
std::vector<uint64_t> activeSubBlockWeights(const BrickSource& source, std::span<const int64_t> bricks,
                                            double iso);

// Cuts `bricks` (increasing ids among brickCount) into `parts` contiguous runs of about equal
// weight: run r ends at the first brick where the running weight reaches r + 1 parts' share.
// Every run holds at least one brick when there are as many bricks as parts. parts >= 1.
BrickPartition partitionBricks(std::vector<int64_t> bricks, std::vector<uint64_t> weights, int parts,
                               int64_t brickCount);

}  // namespace vdiso::mpi
