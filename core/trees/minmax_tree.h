// The min/max tree over bricks (Wilhelms & Van Gelder's octree, as a kd-tree with axis-aligned
// splits): each node holds a box of bricks and the [min, max] of all samples below it, so a
// traversal skips every subtree whose range excludes the isovalue without touching its bricks.
//
// Flat array of 32-byte nodes in depth-first order (pbrt's LinearBVHNode): the first child of
// an interior node is the next node, the second is at `secondChild`. The splits are an octree's
// over the brick grid padded to a cube of 2^L bricks a side, one axis at a time: a node owns an
// aligned box of 2^s bricks per axis (clipped to the grid) and halves its axis of largest s
// (x first on ties), or only narrows s where the upper half lies beyond the grid. So visiting
// the child on the eye's side of the split plane first is an exact front-to-back order
// (pushChildrenFarFirst; the view-dependent traversal), and every brick of every level of
// detail is a node: where s is l on all three axes, the node's box is exactly level l's brick
// (lo >> l) (core/brick_levels.h). A node notes the levels it is a brick of, and its range
// takes in their bricks' ranges as well as level 0's below it, so a node whose range excludes
// the isovalue holds no surface at any level.
// Immutable after construction; traversals are thread-safe.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <glm/vec3.hpp>

#include "core/brick_layout.h"
#include "core/brick_levels.h"
#include "core/brick_source.h"
#include "core/huge_pages.h"
#include "core/kernel/iso.h"

namespace vdiso {

struct MinMaxNode {
    static constexpr uint8_t kNoLevel = 255;
    float minValue, maxValue;
    uint16_t lo[3], hi[3];   // level-0 brick coordinates, [lo, hi) on each axis
    uint32_t secondChild;    // 0 for a leaf (one level-0 brick)
    uint8_t splitAxis;       // interior nodes: axis of the split plane
    // The node's box is a brick of every level in [fineLevel, coarseLevel] (of those the tree
    // was given; kNoLevel: of none). A leaf is a brick of level 0 at least; several levels
    // share a box at the grid's far faces. (No initializers: the tree's array is made without
    // writing it, so that its pages are first touched by the threads that build it.)
    uint8_t coarseLevel, fineLevel;
    uint8_t pad[5];

    bool isLeaf() const { return secondChild == 0; }
    bool isBrickOfLevel(int l) const {
        return coarseLevel != kNoLevel && l <= coarseLevel && l >= fineLevel;
    }
};
static_assert(sizeof(MinMaxNode) == 32);

class MinMaxTree {
public:
    // Over level 0's bricks, `ranges` indexed by their ids.
    MinMaxTree(const BrickLayout& layout, std::span<const BrickRange> ranges, int threads = 1);
    // Over `levels` (level 0 first), `ranges` indexed by brick ids through all of them. Built
    // on `threads` threads (subtrees of kParallelBricks bricks or more apart): the same nodes
    // however many.
    MinMaxTree(std::span<const BrickLevel> levels, std::span<const BrickRange> ranges, int threads = 1);
    static constexpr int64_t kParallelBricks = 4096;

    std::span<const MinMaxNode> nodes() const { return mNodes; }
    const BrickLayout& layout() const { return mLayout; }
    int64_t brickOf(const MinMaxNode& leaf) const {
        return mLayout.brickId(leaf.lo[0], leaf.lo[1], leaf.lo[2]);
    }
    // The brick id (numbered through all levels) of node at level l; node.isBrickOfLevel(l).
    int64_t brickOf(const MinMaxNode& node, int l) const {
        const BrickLevel& level = mLevels[size_t(l)];
        return level.firstBrick + level.layout.brickId(node.lo[0] >> l, node.lo[1] >> l, node.lo[2] >> l);
    }
    int levelCount() const { return int(mLevels.size()); }

    // Where interior node `index` splits, in bricks along node.splitAxis: its first child holds
    // the bricks below, its second those at and above.
    int64_t splitOf(uint32_t index) const { return mNodes[index + 1].hi[mNodes[index].splitAxis]; }
    // The child of interior node `index` that holds level-0 brick c.
    uint32_t childHolding(uint32_t index, const int64_t c[3]) const {
        return c[mNodes[index].splitAxis] < splitOf(index) ? index + 1 : mNodes[index].secondChild;
    }

    // Pushes the children of interior node `index` on `stack`, the far one first, so that the
    // one on the eye's side of the split plane pops first: with the eye in brick coordinates
    // (grid coordinates / brickSize), the front-to-back order.
    template <class Stack>
    void pushChildrenFarFirst(Stack& stack, uint32_t index, const glm::dvec3& eyeInBricks) const {
        const MinMaxNode& node = mNodes[index];
        const bool lowerIsNear = eyeInBricks[node.splitAxis] < double(splitOf(index));
        stack.push_back(lowerIsNear ? node.secondChild : index + 1);
        stack.push_back(lowerIsNear ? index + 1 : node.secondChild);
    }

    // Calls visit(brickId) for each brick whose range holds iso, depth first; counts the nodes
    // visited. Returns the number of nodes visited.
    template <class Visit>
    int64_t forEachActiveBrick(double iso, Visit&& visit) const {
        int64_t visited = 0;
        uint32_t stack[64];
        int top = 0;
        if (!mNodes.empty()) stack[top++] = 0;
        while (top > 0) {
            const uint32_t n = stack[--top];
            const MinMaxNode& node = mNodes[n];
            ++visited;
            if (!rangeHoldsIso(node.minValue, node.maxValue, iso)) continue;
            if (node.isLeaf()) {
                visit(brickOf(node));
                continue;
            }
            stack[top++] = node.secondChild;
            stack[top++] = n + 1;
        }
        return visited;
    }

private:
    // The subtree over box [lo, hi) (aligned, 2^logSize bricks a side before clipping) into
    // nodes [index, index + 2 n - 1) for its n level-0 bricks.
    void build(const uint16_t lo[3], const uint16_t hi[3], int logSize[3], uint32_t index,
               std::span<const BrickRange> ranges, bool parallel);
    void leaf(const uint16_t lo[3], uint32_t index, std::span<const BrickRange> ranges);

    BrickLayout mLayout;
    std::vector<BrickLevel> mLevels;
    // In huge pages past 2 MB (core/huge_pages.h): a 2560^3 store's tree reserves 32 MB, which
    // in 4 KB pages took a fault each as the build first wrote them (a third of the build).
    std::vector<MinMaxNode, UninitializedAllocator<MinMaxNode>> mNodes;
};

}  // namespace vdiso
