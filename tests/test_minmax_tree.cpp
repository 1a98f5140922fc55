// The min/max tree's layout and ranges (core/trees/minmax_tree.h): depth first with the first
// child next, every level-0 brick one leaf, each node's box split in two and its range exactly
// its bricks' (level 0 below it and the levels it is a brick of), on grids whose top splits are
// far from even, built on one thread and on several.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <functional>
#include <limits>
#include <random>
#include <vector>

#include "core/brick_levels.h"
#include "core/trees/minmax_tree.h"

namespace vdiso {
namespace {

TEST(MinMaxTree, EveryNodeHoldsItsBoxAndItsBricksRangesOnUnevenGrids) {
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> value(-100.0f, 100.0f);
    const Dims3 grids[] = {{80 * 8 + 1, 37 * 8 + 1, 5 * 8 + 1}, {3 * 8 + 1, 65 * 8 + 1, 33 * 8 + 1}, {9, 9, 9}};
    for (const Dims3& dims : grids) {
        VolumeInfo volume;
        volume.dims = dims;
        const BrickLayout level0(dims, 8);
        const std::vector<BrickLevel> levels = brickLevels(volume, 8, levelsUntilOneBrick(level0));
        const BrickLevel& last = levels.back();
        std::vector<BrickRange> ranges(size_t(last.firstBrick + last.layout.brickCount()));
        for (BrickRange& r : ranges) {
            const float a = value(rng), b = value(rng);
            r = {std::min(a, b), std::max(a, b)};
        }
        // Built on three threads (subtrees of MinMaxTree::kParallelBricks bricks apart): the
        // same nodes, byte for byte, as on one.
        const MinMaxTree tree(levels, ranges, 3), alone(levels, ranges, 1);
        const std::span<const MinMaxNode> nodes = tree.nodes();
        ASSERT_EQ(nodes.size(), alone.nodes().size());
        EXPECT_EQ(std::memcmp(nodes.data(), alone.nodes().data(), nodes.size_bytes()), 0);
        std::vector<int> leaves(size_t(level0.brickCount()), 0);
        // Walks the subtree at `index`; returns the index past it.
        std::function<uint32_t(uint32_t)> check = [&](uint32_t index) -> uint32_t {
            const MinMaxNode& n = nodes[index];
            float least = std::numeric_limits<float>::max(), most = std::numeric_limits<float>::lowest();
            for (int l = 0; l < int(levels.size()); ++l)
                if (n.isBrickOfLevel(l)) {
                    const BrickRange& r = ranges[size_t(tree.brickOf(n, l))];
                    least = std::min(least, r.minValue);
                    most = std::max(most, r.maxValue);
                }
            if (n.isLeaf()) {
                EXPECT_EQ(n.hi[0] - n.lo[0], 1);
                EXPECT_EQ(n.hi[1] - n.lo[1], 1);
                EXPECT_EQ(n.hi[2] - n.lo[2], 1);
                EXPECT_TRUE(n.isBrickOfLevel(0));
                ++leaves[size_t(tree.brickOf(n))];
                EXPECT_EQ(n.minValue, least);
                EXPECT_EQ(n.maxValue, most);
                return index + 1;
            }
            EXPECT_GT(n.secondChild, index + 1);
            const uint32_t end = check(index + 1);
            EXPECT_EQ(end, n.secondChild) << "the second child follows the first's subtree";
            const MinMaxNode &a = nodes[index + 1], &b = nodes[n.secondChild];
            const int axis = n.splitAxis;
            EXPECT_EQ(a.lo[axis], n.lo[axis]);
            EXPECT_EQ(a.hi[axis], b.lo[axis]);
            EXPECT_EQ(b.hi[axis], n.hi[axis]);
            for (int k = 0; k < 3; ++k) {
                if (k == axis) continue;
                EXPECT_TRUE(a.lo[k] == n.lo[k] && a.hi[k] == n.hi[k] && b.lo[k] == n.lo[k] && b.hi[k] == n.hi[k]);
            }
            least = std::min({least, a.minValue, b.minValue});
            most = std::max({most, a.maxValue, b.maxValue});
            EXPECT_EQ(n.minValue, least);
            EXPECT_EQ(n.maxValue, most);
            return check(n.secondChild);
        };
        ASSERT_FALSE(nodes.empty());
        EXPECT_EQ(check(0), uint32_t(nodes.size()));
        EXPECT_EQ(std::count(leaves.begin(), leaves.end(), 1), int64_t(leaves.size())) << "each brick one leaf";
    }
}

}  // namespace
}  // namespace vdiso
