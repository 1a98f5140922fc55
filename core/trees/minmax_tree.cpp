#include "core/trees/minmax_tree.h"

#include <algorithm>
#include <limits>
#include <stdexcept>
#include <string>

#include "core/check.h"

namespace vdiso {

MinMaxTree::MinMaxTree(const BrickLayout& layout, std::span<const BrickRange> ranges)
    : MinMaxTree(std::vector<BrickLevel>{{VolumeInfo{layout.dims}, layout, 0}},
                 ranges.first(std::min(ranges.size(), size_t(layout.brickCount())))) {}

MinMaxTree::MinMaxTree(std::span<const BrickLevel> levels, std::span<const BrickRange> ranges)
    : mLayout(levels[0].layout), mLevels(levels.begin(), levels.end()) {
    const BrickLevel& last = mLevels.back();
    VDISO_CHECK_EQ(int64_t(ranges.size()), last.firstBrick + last.layout.brickCount());
    // Readers refuse larger layouts (brickLayoutProblem); this guards other sources.
    if (const std::string problem = brickLayoutProblem(mLayout); !problem.empty())
        throw std::invalid_argument(problem);
    if (ranges.empty()) return;
    mNodes.reserve(size_t(2 * mLayout.brickCount()));
    const uint16_t lo[3] = {0, 0, 0};
    const uint16_t hi[3] = {uint16_t(mLayout.brickCounts[0]), uint16_t(mLayout.brickCounts[1]),
                            uint16_t(mLayout.brickCounts[2])};
    // The padded cube: 2^L bricks a side, the size of the coarsest level's one brick.
    int cube = levelsUntilOneBrick(mLayout) - 1;
    int logSize[3] = {cube, cube, cube};
    build(lo, hi, logSize, ranges);
}

uint32_t MinMaxTree::leaf(const uint16_t lo[3], std::span<const BrickRange> ranges) {
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
    mNodes.push_back(node);
    return uint32_t(mNodes.size() - 1);
}

uint32_t MinMaxTree::build(const uint16_t lo[3], const uint16_t hi[3], int logSize[3],
                           std::span<const BrickRange> ranges) {
    const uint32_t index = uint32_t(mNodes.size());
    mNodes.push_back({});
    MinMaxNode node{};
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
            return index;
        }
        const int mid = lo[axis] + (1 << (logSize[axis] - 1));
        --logSize[axis];
        if (mid >= hi[axis]) continue;  // the upper half lies beyond the grid
        uint16_t firstHi[3] = {hi[0], hi[1], hi[2]}, secondLo[3] = {lo[0], lo[1], lo[2]};
        firstHi[axis] = uint16_t(mid);
        secondLo[axis] = uint16_t(mid);
        int firstLog[3] = {logSize[0], logSize[1], logSize[2]}, secondLog[3] = {logSize[0], logSize[1], logSize[2]};
        const bool leaves = logSize[0] == 0 && logSize[1] == 0 && logSize[2] == 0;
        const uint32_t first = leaves ? leaf(lo, ranges) : build(lo, firstHi, firstLog, ranges);
        const uint32_t second = leaves ? leaf(secondLo, ranges) : build(secondLo, hi, secondLog, ranges);
        node.secondChild = second;
        node.splitAxis = uint8_t(axis);
        takeRange({mNodes[first].minValue, mNodes[first].maxValue});
        takeRange({mNodes[second].minValue, mNodes[second].maxValue});
        mNodes[index] = node;
        return index;
    }
}

}  // namespace vdiso
