// Marching-cubes extraction of the cells of one brick, meta-cell by meta-cell.
//
// A brick's cells are grouped into meta-cells of M^3 cells (the last ones on an axis may be
// smaller or empty). The range of a meta-cell is the min and max of its corner samples; only
// meta-cells whose range holds the isovalue are visited (the min/max tree idea continued
// inside the brick). In a visited cell, the case index selects the polygons of the polygon
// form (core/mc_tables.h); each crossed edge's vertex is computed once, by linear
// interpolation, with a normal interpolated from central-difference gradients at the edge's
// corners. The brick's ghost samples make those gradients exact at brick borders, so shading
// has no seams; vertices on brick faces are welded across bricks through an EdgeVertexMap,
// so an edge shared by two bricks yields one vertex.
//
// The sample type is dispatched once per brick; the cell loop is a template over it.
// One BrickExtractor per thread (it owns scratch arrays reused across bricks).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "core/brick_layout.h"
#include "core/brick_source.h"
#include "core/mesh.h"
#include "core/volume.h"

namespace vdiso {

constexpr int kDefaultMetaCellSize = 4;
// Meta-cell sizes are clamped to 1..32: a row of a meta-cell's corners fits one 64-bit word.
constexpr int kMaxMetaCellSize = 32;

// Vertices of edges on brick faces, by global edge key, so neighbouring bricks share them.
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

// Called with each polygon's outline (global vertex numbers into the mesh, in order) before
// its fan triangles are appended: the view-dependent traversal scan-converts it (SAGE §3.2)
// and returns whether its triangles are wanted (false: they would draw no visible pixel). A
// cell's triangles are appended when any of its polygons is wanted: the polygons of one cell
// come in no front-to-back order, so one of them may hide another.
using PolygonCallback = bool (*)(void* context, const uint32_t* vertices, int count);

// Asked for each active cell (global cell coordinates) before its surface is made; false
// skips the cell. The view-dependent traversal's per-cell visibility test.
using CellFilter = bool (*)(void* context, int64_t x, int64_t y, int64_t z);

struct KernelCounters {
    int64_t metaCellsTested = 0, metaCellsActive = 0, cellsVisited = 0, cellsActive = 0;
};

class BrickExtractor {
public:
    BrickExtractor(const VolumeInfo& volume, const BrickLayout& layout, int metaCellSize);

    int metaCellSize() const { return mMetaCellSize; }
    // Meta-cells per brick (ceil(B/M)^3), numbered x fastest.
    int metaCellsPerBrick() const { return mMetaPerAxis * mMetaPerAxis * mMetaPerAxis; }

    // The range of every meta-cell of brick `id` ((B+3)^3 samples of the volume's type), in
    // meta-cell order; empty meta-cells (beyond a partial brick's cells) get an empty range.
    void metaCellRanges(int64_t id, const void* samples, std::vector<BrickRange>& out);

    // Appends the surface of every cell of brick `id` whose meta-cell range holds iso.
    void extractBrick(int64_t id, const void* samples, double iso, TriangleMesh& mesh,
                      EdgeVertexMap& seams);

    // Appends the surface of the listed meta-cells of brick `id` (their ranges already known
    // to hold iso, e.g. from a span-space query).
    void extractMetaCells(int64_t id, const void* samples, double iso,
                          std::span<const uint32_t> metaCells, TriangleMesh& mesh,
                          EdgeVertexMap& seams);

    // One meta-cell at a time, for traversals that decide per meta-cell (SAGE): beginBrick
    // makes `samples` the current brick (its vertices are shared across its meta-cells) and
    // computes its meta-cell ranges; extractMetaCell appends one meta-cell's surface, its
    // cells front to back from `eye` (world) when given, else in memory order.
    void beginBrick(int64_t id, const void* samples);
    const std::vector<BrickRange>& currentRanges() const { return mRanges; }
    void extractMetaCell(uint32_t metaCell, double iso, TriangleMesh& mesh, EdgeVertexMap& seams,
                         PolygonCallback onPolygon = nullptr, void* context = nullptr,
                         CellFilter keepCell = nullptr, const glm::dvec3* eye = nullptr);
    int metaCellsPerAxis() const { return mMetaPerAxis; }
    // The first crossing of the isovalue along the ray origin + t * direction, t in
    // [tEnter, tExit], through the current brick's trilinear interpolant (world units; the
    // segment must lie within the brick's cells). Marched in quarter-sample steps, refined by
    // linear interpolation; the normal is minus the gradient there (central differences at the
    // cell's corners, interpolated: the vertex normals' estimator). Returns
    // false when the segment does not cross the surface.
    bool firstHit(const glm::dvec3& origin, const glm::dvec3& direction, double tEnter,
                  double tExit, double iso, glm::vec3& position, glm::vec3& normal) const;

    const KernelCounters& counters() const { return mCounters; }

private:
    template <class T>
    friend struct BrickKernel;

    VolumeInfo mVolume;
    BrickLayout mLayout;
    int mMetaCellSize;
    int mMetaPerAxis;
    // Vertex + 1 of each local edge of the current brick, 0 for none. Vertex numbers only
    // grow within a mesh, so an entry is the current brick's exactly when it is above the
    // brick's first vertex number: nothing is cleared between bricks, and an entry is 4 bytes
    // (the array, (B+1)^3 * 3 entries, is the kernel's most-missed memory). Vertices welded
    // from the seam map are older, so their edges are looked up in the map each time. When
    // the numbers start again (the extractor used on another mesh), the array is cleared.
    std::vector<uint32_t> mEdgeVertex;
    static constexpr uint32_t kNoFirstVertex = UINT32_MAX;
    uint32_t mBrickFirstVertex = kNoFirstVertex;  // set by the brick's first kernel
    uint32_t mVerticesMade = 0;                   // the largest entry written
    void forgetBrickVertices();  // a new brick: forget the vertices of the last one
    std::vector<BrickRange> mRanges;
    int64_t mCurrentBrick = -1;
    const void* mCurrentSamples = nullptr;
    KernelCounters mCounters;
};

}  // namespace vdiso
