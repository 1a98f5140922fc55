// The part of a volume one process of a shared extraction is given (FullExtractOptions::bricks,
// core/extract/extract_full.h), and which of its vertices another part makes too.
#pragma once

#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/brick_layout.h"
#include "core/kernel/edge_vertex_map.h"
#include "core/volume.h"

namespace vdiso {

// The part of the volume given by FullExtractOptions::bricks, and the test of whether an edge
// also has a cell in a brick outside it (then another part makes its vertex too).
class PartBorder {
public:
    PartBorder(const VolumeInfo& volume, const BrickLayout& layout, std::span<const int64_t> part)
        : mDims(volume.dims), mLayout(layout), mInPart(size_t(layout.brickCount()), part.empty()) {
        for (int64_t id : part) {
            if (id < 0 || id >= layout.brickCount())
                throw std::invalid_argument("FullExtractOptions::bricks: brick " + std::to_string(id) +
                                            " is not in the volume");
            mInPart[size_t(id)] = 1;
        }
    }
    bool holds(int64_t id) const { return mInPart[size_t(id)] != 0; }
    bool crossesEdge(uint64_t key) const {
        int64_t bricks[4];
        const int n = bricksOnEdge(mDims, mLayout, key, bricks);
        for (int i = 0; i < n; ++i)
            if (!holds(bricks[i])) return true;
        return false;
    }
    // The bricks outside the part.
    std::vector<int64_t> outside() const {
        std::vector<int64_t> ids;
        for (size_t id = 0; id < mInPart.size(); ++id)
            if (!mInPart[id]) ids.push_back(int64_t(id));
        return ids;
    }
    // Copies the entries of `seams` on the part's border to `out` (numbers mapped by `number`;
    // an entry it maps to UINT32_MAX is left out).
    template <class Number>
    void collect(const EdgeVertexMap& seams, EdgeVertexMap& out, Number&& number) const {
        seams.forEach([&](uint64_t key, uint32_t v) {
            if (!crossesEdge(key) || out.find(key) != UINT32_MAX) return;
            const uint32_t n = number(v);
            if (n != UINT32_MAX) out.insert(key, n);
        });
    }

private:
    Dims3 mDims;
    BrickLayout mLayout;
    std::vector<uint8_t> mInPart;
};

}  // namespace vdiso
