#include "mpi/brick_partition.h"

#include <algorithm>
#include <stdexcept>

#include "core/kernel/iso.h"
#include "core/trees/sub_blocks.h"

namespace vdiso::mpi {

uint64_t BrickPartition::weightOf(int r) const {
    uint64_t w = 0;
    for (size_t i = firsts[size_t(r)]; i < firsts[size_t(r) + 1]; ++i) w += weights[i];
    return w;
}

std::vector<uint64_t> activeSubBlockWeights(const BrickSource& source, std::span<const int64_t> bricks,
                                            double iso) {
    const std::span<const BrickRange> ranges = source.brickRanges();
    std::vector<uint64_t> weights(bricks.size(), 1);
    for (size_t i = 0; i < bricks.size(); ++i) {
        const size_t id = size_t(bricks[i]);
        const std::span<const SubBlockCode> codes = source.subBlockCodesOf(bricks[i]);
        if (codes.empty()) continue;
        uint64_t active = 0;
        for (int s = 0; s < kSubBlocksPerBrick; ++s) {
            const BrickRange r = decodeSubBlockRange(codes[size_t(s)], ranges[id]);
            active += rangeHoldsIso(r.minValue, r.maxValue, iso);
        }
        weights[i] = std::max<uint64_t>(1, active);
    }
    return weights;
}

BrickPartition partitionBricks(std::vector<int64_t> bricks, std::vector<uint64_t> weights, int parts,
                               int64_t brickCount) {
    if (parts < 1 || weights.size() != bricks.size())
        throw std::invalid_argument("partitionBricks: one weight per brick and at least one part");
    BrickPartition p;
    p.bricks = std::move(bricks);
    p.weights = std::move(weights);
    const size_t n = p.bricks.size();
    uint64_t total = 0;
    for (uint64_t w : p.weights) total += w;
    p.firsts.assign(size_t(parts) + 1, n);
    p.firsts[0] = 0;
    uint64_t running = 0;
    size_t i = 0;
    for (int r = 1; r < parts; ++r) {
        // Ends part r-1 where the running weight reaches r shares, leaving a brick for each
        // part still to come (when there are enough).
        const unsigned __int128 share = (unsigned __int128)total * unsigned(r) / unsigned(parts);
        while (i < n && running < share) running += p.weights[i++];
        size_t end = i;
        if (n >= size_t(parts)) end = std::clamp(end, p.firsts[size_t(r) - 1] + 1, n - size_t(parts - r));
        for (; i < end; ++i) running += p.weights[i];
        for (; i > end; --i) running -= p.weights[i - 1];
        p.firsts[size_t(r)] = end;
    }
    p.partOfBrick.assign(size_t(brickCount), -1);
    for (int r = 0; r < parts; ++r)
        for (int64_t id : p.part(r)) p.partOfBrick[size_t(id)] = int32_t(r);
    return p;
}

}  // namespace vdiso::mpi
