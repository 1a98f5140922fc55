// Marching-cubes extraction of the cells of one brick, meta-cell by meta-cell.
//
// A brick's cells are grouped into meta-cells of M^3 cells (the last ones on an axis may be
// smaller or empty). The range of a meta-cell is the min and max of its corner samples; only
// meta-cells whose range holds the isovalue are visited (the min/max tree idea continued
// inside the brick). In a visited cell, the case index selects the polygons of the polygon
// form (core/kernel/mc_tables.h); each crossed edge's vertex is computed once, by linear
// interpolation, with a normal interpolated from central-difference gradients at the edge's
// corners. The brick's ghost samples make those gradients exact at brick borders, so shading
// has no seams; vertices on brick faces are welded across bricks through an EdgeVertexMap
// (core/kernel/edge_vertex_map.h), so an edge shared by two bricks yields one vertex.
//
// The sample type is dispatched once per brick; the cell loop is a template over it.
// One BrickExtractor per thread (it owns scratch arrays reused across bricks).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "core/brick_layout.h"
#include "core/brick_source.h"
#include "core/kernel/edge_vertex_map.h"
#include "core/mesh.h"
#include "core/volume.h"

namespace vdiso {

// 8: with every crossed cell tested on its own (core/kernel/shown_meta_cell.h), a larger
// meta-cell culls no worse and pays its fixed costs (the walk's box tests, classification,
// corner rows) half as often a triangle: SAGE frames 0.72-0.98x the time of 4 on the real
// scans, the same triangles (bench/log.md); 16 was slower on the CT's closeup.
constexpr int kDefaultMetaCellSize = 8;
// Meta-cell sizes are clamped to 1..32: a row of a meta-cell's corners fits one 64-bit word.
constexpr int kMaxMetaCellSize = 32;

struct KernelCounters {
    int64_t metaCellsTested = 0, metaCellsActive = 0, cellsVisited = 0, cellsActive = 0;
    KernelCounters& operator+=(const KernelCounters& o) {
        metaCellsTested += o.metaCellsTested;
        metaCellsActive += o.metaCellsActive;
        cellsVisited += o.cellsVisited;
        cellsActive += o.cellsActive;
        return *this;
    }
};

// Vertices a brick of `brickSize` cells is expected to make, at most about: a surface crossing it
// twice (2 B^2). What a full extraction reserves ahead; pages never written cost nothing.
inline uint64_t expectedVerticesPerBrick(int brickSize) { return 2 * uint64_t(brickSize) * uint64_t(brickSize); }

// What one brick writes into a PlacedMesh: the vertices it owns and its triangles.
struct BrickCount {
    uint64_t vertices = 0, triangles = 0;
};

struct PlacedMesh;
class EdgeOwnership;
template <class T, class Mesh = TriangleMesh>
struct BrickKernel;  // core/kernel/brick_kernel.h

class BrickExtractor {
public:
    // `trilinear`: cells whose case can be cut otherwise (ambiguous faces, tunnels) are cut as
    // their trilinear interpolant is (core/kernel/trilinear_cell.h) in full extractions
    // (extractBrick, extractMetaCells, extractInPlace and its count); a view's meta-cells
    // (beginBrick) keep the tables' cut.
    BrickExtractor(const VolumeInfo& volume, const BrickLayout& layout, int metaCellSize, bool trilinear = false);

    int metaCellSize() const { return mMetaCellSize; }
    // Meta-cells per brick (ceil(B/M)^3), numbered x fastest.
    int metaCellsPerBrick() const { return mMetaPerAxis * mMetaPerAxis * mMetaPerAxis; }

    // The range of every meta-cell of brick `id` ((B+3)^3 samples of the volume's type), in
    // meta-cell order; empty meta-cells (beyond a partial brick's cells) get an empty range.
    void metaCellRanges(int64_t id, const void* samples, std::vector<BrickRange>& out);

    // Appends the surface of every cell of brick `id` whose meta-cell range holds iso: with
    // wholeBricks(), every crossed cell of the brick at once (BrickKernel::emitBrick), in rows.
    void extractBrick(int64_t id, const void* samples, double iso, TriangleMesh& mesh,
                      EdgeVertexMap& seams);

    // Appends the surface of the listed meta-cells of brick `id` (their ranges already known
    // to hold iso, e.g. from a span-space query).
    void extractMetaCells(int64_t id, const void* samples, double iso,
                          std::span<const uint32_t> metaCells, TriangleMesh& mesh,
                          EdgeVertexMap& seams);

    // Written in place (core/kernel/placed_mesh.h): the same, but brick `id` makes only the
    // vertices it owns (mesh.ownership); `metaCells` empty: every one whose range holds iso.
    void extractInPlace(int64_t id, const void* samples, double iso,
                        std::span<const uint32_t> metaCells, PlacedMesh& mesh, EdgeVertexMap& seams);
    // What extractInPlace writes, by classification alone (the count before the emission).
    // With `activeMetaCells`, no metaCells listed and bricks not taken whole, appends the
    // meta-cells whose range holds iso, in increasing order: the list extractInPlace then takes
    // instead of ranging the brick.
    BrickCount countInPlace(int64_t id, const void* samples, double iso,
                            std::span<const uint32_t> metaCells, const EdgeOwnership& ownership,
                            std::vector<uint32_t>* activeMetaCells = nullptr);

    // One meta-cell at a time, for traversals that decide per meta-cell (SAGE): beginBrick
    // makes `samples` the current brick (its vertices are shared across its meta-cells); a
    // BrickKernel (core/kernel/brick_kernel.h) made after it then extracts meta-cells one by one
    // under the traversal's cell policy. currentRanges: the ranges of all its meta-cells,
    // computed on the first call (a view visits a few meta-cells of most bricks, and can take
    // their ranges one by one from the kernel instead).
    void beginBrick(int64_t id, const void* samples);
    const std::vector<BrickRange>& currentRanges();
    int metaCellsPerAxis() const { return mMetaPerAxis; }

    const KernelCounters& counters() const { return mCounters; }
    // A full extraction takes a brick whole, a 64-bit word per row of corners, when its rows
    // have at most 64 corners; larger bricks go meta-cell by meta-cell.
    bool wholeBricks() const { return mLayout.brickSize < 64; }

private:
    template <class T, class Mesh>
    friend struct BrickKernel;

    VolumeInfo mVolume;
    glm::dvec3 mGradientScale;  // 1 / (2 spacing): a central difference to a gradient component
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
    std::vector<uint64_t> mEdgeSeen;  // countInPlace: a bit per local edge, or a word per corner row
    std::vector<uint32_t> mLayerVertex;  // emitBrick's vertex slots
    static constexpr uint32_t kNoFirstVertex = UINT32_MAX;
    uint32_t mBrickFirstVertex = kNoFirstVertex;  // set by the brick's first kernel
    uint32_t mVerticesMade = 0;                   // the largest entry written
    void forgetBrickVertices();  // a new brick: forget the vertices of the last one
    template <class Mesh>
    void extractInto(int64_t id, const void* samples, double iso, std::span<const uint32_t> metaCells,
                     Mesh& mesh, EdgeVertexMap& seams);
    template <class F>
    void forEachActiveMetaCell(int64_t id, const void* samples, double iso,
                               std::span<const uint32_t> metaCells, F&& f);
    std::vector<BrickRange> mRanges;
    bool mRangesCurrent = false;  // mRanges are the current brick's
    int64_t mCurrentBrick = -1;
    const void* mCurrentSamples = nullptr;
    KernelCounters mCounters;
    bool mTrilinear = false;
};

}  // namespace vdiso
