#include "core/trees/minmax_tree.h"

#include <algorithm>
#include <limits>
#include <stdexcept>
#include <string>

#include <tbb/parallel_invoke.h>
#include <tbb/task_arena.h>

#include "core/check.h"

namespace vdiso {

MinMaxTree::MinMaxTree(const BrickLayout& layout, std::span<const BrickRange> ranges, int threads)
    : MinMaxTree(std::vector<BrickLevel>{{VolumeInfo{layout.dims}, layout, 0}},
                 ranges.first(std::min(ranges.size(), size_t(layout.brickCount()))), threads) {}

MinMaxTree::MinMaxTree(std::span<const BrickLevel> levels, std::span<const BrickRange> ranges, int threads)
    : mLayout(levels[0].layout), mLevels(levels.begin(), levels.end()) {
    const BrickLevel& last = mLevels.back();
    VDISO_CHECK_EQ(int64_t(ranges.size()), last.firstBrick + last.layout.brickCount());
    // Readers refuse larger layouts (brickLayoutProblem); this guards other sources.
    if (const std::string problem = brickLayoutProblem(mLayout); !problem.empty())
        throw std::invalid_argument(problem);
    if (ranges.empty()) return;
    // Every node has two children or none: 2n - 1 nodes over n level-0 bricks, each subtree's
    // place known before it is built (build).
    mNodes.resize(size_t(2 * mLayout.brickCount() - 1));
    const uint16_t lo[3] = {0, 0, 0};
    const uint16_t hi[3] = {uint16_t(mLayout.brickCounts[0]), uint16_t(mLayout.brickCounts[1]),
                            uint16_t(mLayout.brickCounts[2])};
    // The padded cube: 2^L bricks a side, the size of the coarsest level's one brick.
    int cube = levelsUntilOneBrick(mLayout) - 1;
    int logSize[3] = {cube, cube, cube};
    if (threads <= 1) {
        build(lo, hi, logSize, 0, ranges, false);
        return;
    }
    tbb::task_arena arena(threads);
    arena.execute([&] { build(lo, hi, logSize, 0, ranges, true); });
}

void MinMaxTree::leaf(const uint16_t lo[3], uint32_t index, std::span<const BrickRange> ranges) {
    // What build makes of one level-0 brick, without its loop: the brick of level 0.
    MinMaxNode node{};
    for (int a = 0; a < 3; ++a) {
        node.lo[a] = lo[a];
        node.hi[a] = uint16_t(lo[a] + 1);
    }
    const BrickRange& r = ranges[size_t(mLayout.brickId(lo[0], lo[1], lo[2]))];
    node.minValue = r.minValue;
    node.maxValue = r.maxValue;
    node.coarseLevel = node.fineLevel = 0;
    mNodes[index] = node;
}

void MinMaxTree::build(const uint16_t lo[3], const uint16_t hi[3], int logSize[3], uint32_t index,
                       std::span<const BrickRange> ranges, bool parallel) {
    MinMaxNode node{};
    node.coarseLevel = node.fineLevel = MinMaxNode::kNoLevel;
    std::copy(lo, lo + 3, node.lo);
    std::copy(hi, hi + 3, node.hi);
    node.minValue = std::numeric_limits<float>::max();
    node.maxValue = std::numeric_limits<float>::lowest();
    auto takeRange = [&](const BrickRange& r) {
        node.minValue = std::min(node.minValue, r.minValue);
        node.maxValue = std::max(node.maxValue, r.maxValue);
    };
    while (true) {
        if (logSize[0] == logSize[1] && logSize[1] == logSize[2] && logSize[0] < int(mLevels.size())) {
            const int l = logSize[0];
            if (node.coarseLevel == MinMaxNode::kNoLevel) node.coarseLevel = uint8_t(l);
            node.fineLevel = uint8_t(l);
            takeRange(ranges[size_t(brickOf(node, l))]);
        }
        int axis = 0;
        for (int a = 1; a < 3; ++a)
            if (logSize[a] > logSize[axis]) axis = a;
        if (logSize[axis] == 0) {  // one level-0 brick: its range was taken as level 0's
            mNodes[index] = node;
            return;
        }
        const int mid = lo[axis] + (1 << (logSize[axis] - 1));
        --logSize[axis];
        if (mid >= hi[axis]) continue;  // the upper half lies beyond the grid
        uint16_t firstHi[3] = {hi[0], hi[1], hi[2]}, secondLo[3] = {lo[0], lo[1], lo[2]};
        firstHi[axis] = uint16_t(mid);
        secondLo[axis] = uint16_t(mid);
        int firstLog[3] = {logSize[0], logSize[1], logSize[2]}, secondLog[3] = {logSize[0], logSize[1], logSize[2]};
        const bool leaves = logSize[0] == 0 && logSize[1] == 0 && logSize[2] == 0;
        // The first child follows its parent; the second its subtree of 2 n - 1 nodes.
        int64_t firstBricks = 1;
        for (int a = 0; a < 3; ++a) firstBricks *= int64_t(firstHi[a]) - lo[a];
        const uint32_t first = index + 1, second = uint32_t(first + 2 * firstBricks - 1);
        if (leaves) {
            leaf(lo, first, ranges);
            leaf(secondLo, second, ranges);
        } else if (parallel && firstBricks >= kParallelBricks) {
            tbb::parallel_invoke([&] { build(lo, firstHi, firstLog, first, ranges, true); },
                                 [&] { build(secondLo, hi, secondLog, second, ranges, true); });
        } else {
            build(lo, firstHi, firstLog, first, ranges, parallel);
            build(secondLo, hi, secondLog, second, ranges, parallel);
        }
        node.secondChild = second;
        node.splitAxis = uint8_t(axis);
        takeRange({mNodes[first].minValue, mNodes[first].maxValue});
        takeRange({mNodes[second].minValue, mNodes[second].maxValue});
        mNodes[index] = node;
        return;
    }
}

}  // namespace vdiso
