#include "core/minmax_tree.h"

#include <algorithm>
#include <stdexcept>
#include <string>

#include "core/check.h"

namespace vdiso {

MinMaxTree::MinMaxTree(const BrickLayout& layout, std::span<const BrickRange> ranges)
    : mLayout(layout) {
    VDISO_CHECK_EQ(int64_t(ranges.size()), layout.brickCount());
    // Readers refuse larger layouts (brickLayoutProblem); this guards other sources.
    if (const std::string problem = brickLayoutProblem(layout); !problem.empty())
        throw std::invalid_argument(problem);
    if (ranges.empty()) return;
    mNodes.reserve(size_t(2 * layout.brickCount()));
    const uint16_t lo[3] = {0, 0, 0};
    const uint16_t hi[3] = {uint16_t(layout.brickCounts[0]), uint16_t(layout.brickCounts[1]),
                            uint16_t(layout.brickCounts[2])};
    build(lo, hi, ranges);
}

uint32_t MinMaxTree::build(const uint16_t lo[3], const uint16_t hi[3],
                           std::span<const BrickRange> ranges) {
    const uint32_t index = uint32_t(mNodes.size());
    mNodes.push_back({});
    MinMaxNode node{};
    std::copy(lo, lo + 3, node.lo);
    std::copy(hi, hi + 3, node.hi);
    int axis = 0;
    for (int a = 1; a < 3; ++a)
        if (hi[a] - lo[a] > hi[axis] - lo[axis]) axis = a;
    if (hi[axis] - lo[axis] == 1) {
        const BrickRange& r = ranges[size_t(mLayout.brickId(lo[0], lo[1], lo[2]))];
        node.minValue = r.minValue;
        node.maxValue = r.maxValue;
        mNodes[index] = node;
        return index;
    }
    const uint16_t mid = uint16_t((lo[axis] + hi[axis]) / 2);
    uint16_t firstHi[3] = {hi[0], hi[1], hi[2]}, secondLo[3] = {lo[0], lo[1], lo[2]};
    firstHi[axis] = mid;
    secondLo[axis] = mid;
    const uint32_t first = build(lo, firstHi, ranges);
    const uint32_t second = build(secondLo, hi, ranges);
    node.secondChild = second;
    node.splitAxis = uint8_t(axis);
    node.minValue = std::min(mNodes[first].minValue, mNodes[second].minValue);
    node.maxValue = std::max(mNodes[first].maxValue, mNodes[second].maxValue);
    mNodes[index] = node;
    return index;
}

}  // namespace vdiso
