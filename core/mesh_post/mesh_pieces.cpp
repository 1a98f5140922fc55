#include "core/mesh_post/mesh_pieces.h"

#include <numeric>
#include <stdexcept>
#include <string>

namespace vdiso {

namespace {

// Union-find over a slab's local vertex numbers.
struct LocalSets {
    std::vector<uint32_t> parent;
    explicit LocalSets(size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0u); }
    uint32_t find(uint32_t v) {
        while (parent[v] != v) v = parent[v] = parent[parent[v]];
        return v;
    }
    void unite(uint32_t a, uint32_t b) {
        a = find(a);
        b = find(b);
        if (a != b) parent[std::max(a, b)] = std::min(a, b);
    }
};

}  // namespace

void MeshPieces::addSlab(uint32_t firstVertex, uint32_t vertexCount, std::span<const uint32_t> indices,
                         std::vector<uint32_t>& labels) {
    if (firstVertex != mNextFirst)
        throw std::invalid_argument("mesh slab starts at vertex " + std::to_string(firstVertex) +
                                    ", not " + std::to_string(mNextFirst));
    // Local numbers: this slab's vertices first, then the previous slab's.
    const uint32_t previousCount = uint32_t(mPreviousLabels.size());
    auto local = [&](uint32_t v) -> uint32_t {
        if (v - firstVertex < vertexCount) return v - firstVertex;
        if (v - mPreviousFirst < previousCount) return vertexCount + (v - mPreviousFirst);
        throw std::invalid_argument("mesh slab's triangle refers to vertex " + std::to_string(v) +
                                    ", outside this slab and the one before");
    };
    LocalSets sets(size_t(vertexCount) + previousCount);
    for (size_t t = 0; t + 2 < indices.size(); t += 3) {
        const uint32_t a = local(indices[t]);
        sets.unite(a, local(indices[t + 1]));
        sets.unite(a, local(indices[t + 2]));
    }
    // A label per local piece; a piece holding previous-slab vertices joins their labels.
    constexpr uint32_t kNone = UINT32_MAX;
    std::vector<uint32_t> labelOfRoot(sets.parent.size(), kNone);
    auto labelOf = [&](uint32_t v) {
        const uint32_t root = sets.find(v);
        if (labelOfRoot[root] == kNone) {
            labelOfRoot[root] = uint32_t(mParent.size());
            mParent.push_back(labelOfRoot[root]);
            mTriangles.push_back(0);
        }
        return labelOfRoot[root];
    };
    labels.resize(indices.size() / 3);
    for (size_t t = 0; t < labels.size(); ++t) {
        labels[t] = labelOf(local(indices[3 * t]));
        ++mTriangles[labels[t]];
    }
    for (uint32_t p = 0; p < previousCount; ++p) {
        const uint32_t root = sets.find(vertexCount + p);
        if (labelOfRoot[root] != kNone) unite(labelOfRoot[root], mPreviousLabels[p]);
    }
    mPreviousLabels.assign(vertexCount, kNone);
    for (uint32_t v = 0; v < vertexCount; ++v) mPreviousLabels[v] = labelOf(v);
    mPreviousFirst = firstVertex;
    mNextFirst = firstVertex + vertexCount;
}

uint32_t MeshPieces::pieceOf(uint32_t label) {
    while (mParent[label] != label) label = mParent[label] = mParent[mParent[label]];
    return label;
}

uint32_t MeshPieces::unite(uint32_t a, uint32_t b) {
    a = pieceOf(a);
    b = pieceOf(b);
    if (a == b) return a;
    if (mTriangles[a] < mTriangles[b] || (mTriangles[a] == mTriangles[b] && b < a)) std::swap(a, b);
    mParent[b] = a;
    mTriangles[a] += mTriangles[b];
    mTriangles[b] = 0;
    return a;
}

uint64_t MeshPieces::pieceCount() {
    uint64_t count = 0;
    for (uint32_t l = 0; l < labelCount(); ++l) count += pieceOf(l) == l && mTriangles[l] > 0;
    return count;
}

uint32_t MeshPieces::largestPiece() {
    uint32_t best = UINT32_MAX;
    for (uint32_t l = 0; l < labelCount(); ++l)
        if (pieceOf(l) == l && mTriangles[l] > 0 && (best == UINT32_MAX || mTriangles[l] > mTriangles[best]))
            best = l;
    return best;
}

}  // namespace vdiso
