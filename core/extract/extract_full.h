// Full isosurface extraction over a BrickSource: the comparison methods of the SAGE paper
// (Tables 1-2, rows "Octree" and "NOISE").
//
// octree: the min/max tree (Wilhelms & Van Gelder) over bricks, from the store's index, then
//   meta-cells inside each active brick. Only bricks whose range holds iso are acquired.
// noise: span space (Livnat, Shen & Johnson 1996) over all meta-cells of the volume: a
//   preprocessing pass acquires every brick once to compute the meta-cell ranges and build the
//   kd-tree (timed apart as preprocessSeconds); the query returns exactly the active
//   meta-cells, which are then extracted brick by brick.
// Both visit the active bricks in increasing id order (the file's order) and produce the same
// triangles (vertex numbering aside) through the same kernel
// (core/kernel/brick_extractor.h), with vertices welded across bricks.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "core/kernel/brick_extractor.h"
#include "core/extract/brick_prefetcher.h"
#include "core/brick_source.h"
#include "core/kernel/edge_vertex_map.h"
#include "core/extract/extract_stats.h"
#include "core/mesh.h"
#include "core/progress.h"

namespace vdiso {

// Receives a full extraction brick by brick (FullExtractOptions::brickSink), in increasing brick
// id order (x fastest, z slowest). Each call holds one active brick's triangles and the vertices
// it made, numbered part.firstVertex onwards (== all handed over before); its triangles refer
// only to those and to vertices of earlier bricks that share a face, edge or corner with it
// (a vertex on a brick border belongs to the first brick that made it).
class BrickMeshSink {
public:
    virtual ~BrickMeshSink() = default;
    virtual void appendBrick(int64_t id, const TriangleMesh& part) = 0;
};

struct FullExtractOptions {
    double iso = 0;
    int metaCellSize = kDefaultMetaCellSize;
    // Threads extracting bricks. 1 runs on the calling thread alone, appending brick by brick.
    // More: the bricks are counted, then written in place, chunks of about equal triangles in
    // parallel (core/extract/extract_in_place.h), held or streamed to `sink` round by round;
    // handed to `brickSink`, contiguous chunks of a few dozen bricks a round at a time are
    // extracted into chunk meshes and merged chunk by chunk. The mesh is the same, vertex
    // numbers included, for any thread count.
    int threads = 1;
    // When set, the surface is streamed: every streamPieceVertices vertices, what the mesh holds is
    // handed to the sink and dropped (drainInto), and at the end the mesh is empty. Memory then
    // holds a bounded part of the output instead of all of it.
    MeshSink* sink = nullptr;
    size_t streamPieceVertices = size_t(1) << 20;  // vertices per piece handed to the sink
    // When set (and sink is not), the surface is handed over brick by brick instead, and at the
    // end the mesh is empty: what the out-of-core post-processing (core/mesh_post/mesh_slabs.h) reads.
    BrickMeshSink* brickSink = nullptr;
    // Bricks a prefetch thread loads ahead of the extraction (threads == 1), from the list of
    // bricks the traversal already decided to visit: reads overlap extraction and no other
    // brick is read. 0: none. Prefetched bricks stay pinned until used, so the source's cache
    // must hold more than this many bricks (vdiso extract uses at most half the cache).
    int prefetchBricks = 0;
    int prefetchReaders = BrickPrefetcher::kDefaultReaders;  // threads reading them
    // The map of brick-face vertices forgets faces no pending brick shares once it holds this
    // many entries, and again each time it doubles (see SeamTrimmer in extract_full.cpp).
    size_t seamTrimEntries = size_t(1) << 16;
    // A part of the volume: when not empty, only these bricks (increasing ids) are extracted,
    // those of them the method finds active; the others are skipped unread. What each process
    // of a shared extraction is given (mpi/). The part's vertices are numbered from 0 in the
    // order one process extracting everything would number them, vertices a brick outside the
    // part shares included (each part makes its own).
    std::span<const int64_t> bricks{};
    // With `bricks`: receives the vertices of the part on an edge that a brick outside it also
    // has a cell on (edge key -> vertex number in the output), the ones another part makes too
    // and that a caller welds across parts. Entries already there are kept.
    EdgeVertexMap* borderVertices = nullptr;
    // Cells cut as their trilinear interpolant (core/kernel/trilinear_cell.h: ambiguous faces
    // by the asymptotic decider, tunnels inside a cell): Lewiner's topology, marching_cubes'
    // method="lewiner". Off: the tables' cut, every front end's.
    bool trilinear = false;
};

// The bricks whose range holds options.iso by the min/max tree over source.brickRanges(), in
// increasing id order: those extractOctree extracts (all of them without `bricks`). Sets
// *nodesVisited to the tree nodes tested when given.
std::vector<int64_t> octreeActiveBricks(const BrickSource& source, double iso,
                                        int64_t* nodesVisited = nullptr);

ExtractStats extractOctree(BrickSource& source, const FullExtractOptions& options,
                               TriangleMesh& mesh, const ProgressFn& progress = {});

ExtractStats extractNoise(BrickSource& source, const FullExtractOptions& options,
                              TriangleMesh& mesh, const ProgressFn& progress = {});

}  // namespace vdiso
