#include "core/kernel/edge_vertex_map.h"

#include <algorithm>

namespace vdiso {

SeamTrimmer::SeamTrimmer(const VolumeInfo& volume, const BrickLayout& layout,
                         std::span<const int64_t> bricks, size_t firstTrim)
    : mDims(volume.dims), mLayout(layout), mPending(size_t(layout.brickCount()), 0),
      mFirstTrim(firstTrim), mTrimAt(firstTrim) {
    for (int64_t id : bricks) mPending[size_t(id)] = 1;
}

void SeamTrimmer::maybeTrim(EdgeVertexMap& seams) {
    if (seams.size() < mTrimAt) return;
    seams.retainIf([&](uint64_t key) { return touchesPendingBrick(key); });
    mTrimAt = std::max(mFirstTrim, 2 * seams.size());
}

EdgeOwnership::EdgeOwnership(const Dims3& dims, const BrickLayout& layout, std::span<const int64_t> bricks,
                             bool everyActive)
    : mDims(dims), mLayout(layout), mRank(size_t(layout.brickCount()), -1), mEveryActive(everyActive) {
    for (int64_t id : bricks) mRank[size_t(id)] = int32_t(id);
}

int32_t edgeOwner(const Dims3& dims, const BrickLayout& layout, uint64_t key,
                  std::span<const int32_t> partOfBrick, int32_t self) {
    int64_t bricks[4];
    const int n = bricksOnEdge(dims, layout, key, bricks);
    int32_t owner = self;
    for (int i = 0; i < n; ++i) {
        const int32_t part = partOfBrick[size_t(bricks[i])];
        if (part >= 0 && part < owner) owner = part;
    }
    return owner;
}

int bricksOnEdge(const Dims3& dims, const BrickLayout& layout, uint64_t key, int64_t bricks[4]) {
    const EdgeOfKey edge = decodeEdgeKey(dims, key);
    const int64_t* p = edge.corner;
    // Bricks per axis: along the edge, the one owning its cell; across it, the one or two
    // whose cells have p as a corner.
    int64_t candidates[3][2];
    int count[3];
    const int B = layout.brickSize;
    for (int a = 0; a < 3; ++a) {
        count[a] = 0;
        if (a == edge.axis) {
            candidates[a][count[a]++] = std::min(p[a] / B, layout.brickCounts[a] - 1);
            continue;
        }
        if (p[a] % B == 0 && p[a] > 0) candidates[a][count[a]++] = p[a] / B - 1;
        if (p[a] / B < layout.brickCounts[a]) candidates[a][count[a]++] = p[a] / B;
    }
    int n = 0;
    for (int k = 0; k < count[2]; ++k)
        for (int j = 0; j < count[1]; ++j)
            for (int i = 0; i < count[0]; ++i)
                bricks[n++] = layout.brickId(candidates[0][i], candidates[1][j], candidates[2][k]);
    return n;
}

bool SeamTrimmer::touchesPendingBrick(uint64_t key) const {
    int64_t bricks[4];
    const int n = bricksOnEdge(mDims, mLayout, key, bricks);
    for (int i = 0; i < n; ++i)
        if (mPending[size_t(bricks[i])]) return true;
    return false;
}

}  // namespace vdiso
