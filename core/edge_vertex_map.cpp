#include "core/edge_vertex_map.h"

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

bool SeamTrimmer::touchesPendingBrick(uint64_t key) const {
    const EdgeOfKey edge = decodeEdgeKey(mDims, key);
    const int axis = edge.axis;
    const int64_t* p = edge.corner;
    // Bricks per axis owning the edge: along its axis the one owning its cell; across it,
    // the one or two whose cell corners include p.
    int64_t candidates[3][2];
    int count[3];
    const int B = mLayout.brickSize;
    for (int a = 0; a < 3; ++a) {
        count[a] = 0;
        if (a == axis) {
            candidates[a][count[a]++] = std::min(p[a] / B, mLayout.brickCounts[a] - 1);
            continue;
        }
        if (p[a] % B == 0 && p[a] > 0) candidates[a][count[a]++] = p[a] / B - 1;
        if (p[a] / B < mLayout.brickCounts[a]) candidates[a][count[a]++] = p[a] / B;
    }
    for (int k = 0; k < count[2]; ++k)
        for (int j = 0; j < count[1]; ++j)
            for (int i = 0; i < count[0]; ++i)
                if (mPending[size_t(mLayout.brickId(candidates[0][i], candidates[1][j], candidates[2][k]))])
                    return true;
    return false;
}

}  // namespace vdiso
