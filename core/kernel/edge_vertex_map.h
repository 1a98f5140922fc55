// The vertices of edges on brick faces, so that neighbouring bricks (and the chunks of a
// parallel extraction) weld an edge they share into one vertex.
//
// An edge is named by a global key: its lower corner's sample index in the volume, times 3,
// plus its axis (edgeKey / decodeEdgeKey, the only place that encoding lives). EdgeVertexMap
// maps keys to vertex numbers; SeamTrimmer forgets the keys no brick still to come can ask for.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "core/brick_layout.h"
#include "core/volume.h"

namespace vdiso {

// The key of the edge from global sample corner (x, y, z) along `axis` (0, 1, 2).
inline uint64_t edgeKey(const Dims3& dims, int64_t x, int64_t y, int64_t z, int axis) {
    return ((uint64_t(z) * uint64_t(dims[1]) + uint64_t(y)) * uint64_t(dims[0]) + uint64_t(x)) * 3 +
           uint64_t(axis);
}

struct EdgeOfKey {
    int64_t corner[3];  // the edge's lower corner, global sample coordinates
    int axis;
};

inline EdgeOfKey decodeEdgeKey(const Dims3& dims, uint64_t key) {
    const int axis = int(key % 3);
    key /= 3;
    return {{int64_t(key % uint64_t(dims[0])), int64_t(key / uint64_t(dims[0]) % uint64_t(dims[1])),
             int64_t(key / (uint64_t(dims[0]) * uint64_t(dims[1])))},
            axis};
}

// The bricks with a cell on edge `key` (1, 2 or 4 of them, written to `bricks`); returns how
// many. Each of them makes the edge's vertex when the surface crosses the edge (the cell's
// range, its meta-cell's and its brick's all hold the isovalue then).
int bricksOnEdge(const Dims3& dims, const BrickLayout& layout, uint64_t key, int64_t bricks[4]);

// Who owns the vertex on edge `key` when bricks are split into parts (chunks of one process,
// ranks of a job): the lowest part, in `partOfBrick` (negative: a brick in no part), of the
// bricks on the edge, and `self` when none is lower. Every part that makes the vertex finds
// the same owner, so welding takes the owner's vertex.
int32_t edgeOwner(const Dims3& dims, const BrickLayout& layout, uint64_t key,
                  std::span<const int32_t> partOfBrick, int32_t self);

// Which brick makes the vertex of an edge that several extracted bricks hold, when each brick
// writes only its own vertices (core/extract/extract_in_place.h): the lowest-numbered extracted
// brick on the edge. Where the ranges agree with the cell test (core/kernel/iso.h), every brick
// on a crossed edge visits a cell of it, so that brick is also the first to make it in id order.
class EdgeOwnership {
public:
    // `bricks`: those extracted, increasing ids. `everyActive`: they are every brick whose range
    // holds the isovalue (no part of the volume left out), so every brick on a crossed edge is
    // among them and a brick owns exactly the crossed edges off its lower faces.
    EdgeOwnership(const Dims3& dims, const BrickLayout& layout, std::span<const int64_t> bricks, bool everyActive);
    // The owner of edge `key`, which brick `self` (extracted) holds.
    int64_t owner(int64_t self, uint64_t key) const {
        return edgeOwner(mDims, mLayout, key, mRank, int32_t(self));
    }
    // The owner of edge `key`; -1 when no extracted brick holds it.
    int64_t owner(uint64_t key) const {
        const int32_t o = edgeOwner(mDims, mLayout, key, mRank, INT32_MAX);
        return o == INT32_MAX ? -1 : o;
    }
    // Whether brick `self`, whose first cell corner is corner0 (global), owns the edge from its
    // local corner p along `axis`: always, unless the edge lies on a face the brick shares with
    // a lower brick.
    bool owns(int64_t self, const int64_t corner0[3], const int p[3], int axis) const {
        bool lowerFace = false;
        for (int a = 0; a < 3; ++a) lowerFace |= a != axis && p[a] == 0 && corner0[a] > 0;
        if (!lowerFace || mEveryActive) return !lowerFace;
        const uint64_t key = edgeKey(mDims, corner0[0] + p[0], corner0[1] + p[1], corner0[2] + p[2], axis);
        return owner(self, key) == self;
    }

private:
    Dims3 mDims;
    BrickLayout mLayout;
    std::vector<int32_t> mRank;  // brick id for extracted bricks, -1 for the others
    bool mEveryActive;
};

// Vertex numbers by edge key.
// Open addressing with linear probing on a power-of-two table (keys are stored plus one, so
// zero marks an empty slot); it grows at half full.
class EdgeVertexMap {
public:
    EdgeVertexMap() { mSlots.resize(1u << 12); }
    // Returns the vertex of `edgeKey`, or UINT32_MAX.
    uint32_t find(uint64_t edgeKey) const {
        const uint64_t stored = edgeKey + 1;
        for (size_t i = slotOf(stored);; i = (i + 1) & (mSlots.size() - 1)) {
            if (mSlots[i].key == stored) return mSlots[i].vertex;
            if (mSlots[i].key == 0) return UINT32_MAX;
        }
    }
    // Asks the memory for the slot where find(edgeKey) starts, ahead of it.
    void prefetch(uint64_t edgeKey) const { __builtin_prefetch(&mSlots[slotOf(edgeKey + 1)]); }
    // Adds a key that is not present.
    void insert(uint64_t edgeKey, uint32_t vertex) {
        if (2 * (mSize + 1) > mSlots.size()) grow();
        place(edgeKey + 1, vertex);
        ++mSize;
    }
    size_t size() const { return mSize; }
    // Forgets every entry (the table shrinks back to its first size).
    void clear() {
        if (mSize == 0) return;
        mSlots.assign(size_t(1) << 12, Slot{});
        mSize = 0;
    }

    // Calls f(edgeKey, vertex) for every entry, in no particular order.
    template <class F>
    void forEach(F&& f) const {
        for (const Slot& slot : mSlots)
            if (slot.key != 0) f(slot.key - 1, slot.vertex);
    }

    // Keeps the entries whose key satisfies keep(edgeKey), in a table sized for them (at
    // most half full, as ever). One pass over the old table.
    template <class Keep>
    void retainIf(Keep&& keep) {
        std::vector<Slot> old;
        old.swap(mSlots);
        size_t kept = 0;
        for (const Slot& slot : old) kept += slot.key != 0 && keep(slot.key - 1);
        size_t capacity = size_t(1) << 12;
        while (2 * (kept + 1) > capacity) capacity *= 2;
        mSlots.resize(capacity);
        mSize = 0;
        for (const Slot& slot : old)
            if (slot.key != 0 && keep(slot.key - 1)) {
                place(slot.key, slot.vertex);
                ++mSize;
            }
    }

private:
    struct Slot {
        uint64_t key = 0;
        uint32_t vertex = 0;
    };
    size_t slotOf(uint64_t stored) const {
        return size_t((stored * 0x9E3779B97F4A7C15ull) >> 20) & (mSlots.size() - 1);
    }
    void place(uint64_t stored, uint32_t vertex) {
        size_t i = slotOf(stored);
        while (mSlots[i].key != 0) i = (i + 1) & (mSlots.size() - 1);
        mSlots[i] = {stored, vertex};
    }
    void grow() {
        std::vector<Slot> old(mSlots.size() * 2);
        old.swap(mSlots);
        for (const Slot& slot : old)
            if (slot.key != 0) place(slot.key, slot.vertex);
    }
    std::vector<Slot> mSlots;
    size_t mSize = 0;
};

// The bricks whose extraction is still to come, so that the map of brick-face vertices can
// forget the faces no extraction will meet again: without that it holds a key for every vertex
// on a brick face of the whole surface (64 MB at 2048^3); with it, about those on the faces
// between finished and pending bricks. Trimmed whenever the map has doubled since the last
// trim, so the cost is linear in what is inserted.
class SeamTrimmer {
public:
    // `bricks`: those still to be extracted.
    SeamTrimmer(const VolumeInfo& volume, const BrickLayout& layout, std::span<const int64_t> bricks,
                size_t firstTrim);
    void finished(int64_t brick) { mPending[size_t(brick)] = 0; }
    void maybeTrim(EdgeVertexMap& seams);

private:
    // Whether a brick holding edge `key` is still to be extracted.
    bool touchesPendingBrick(uint64_t key) const;
    Dims3 mDims;
    BrickLayout mLayout;
    std::vector<uint8_t> mPending;
    size_t mFirstTrim, mTrimAt;
};

}  // namespace vdiso
