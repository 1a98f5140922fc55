// Post-processing a full extraction's surface out of core, slab by slab: a slab is the output of
// one layer of bricks (brick z coordinate k), as core/extract_full.h's BrickMeshSink hands it
// over. Slab k owns the vertices its bricks made, numbered on from slab k-1's, and its triangles
// refer only to those and to slab k-1's; the vertices shared with slab k+1 on their common brick
// face are slab k's.
//
// Each slab is finished with the slabs within haloSlabs() of it at hand (a window), which is all
// the smoothing of its vertices can reach: Taubin smoothing (core/mesh_smooth.h) moves a vertex
// by its neighbours within 2 * iterations + 1 edges, and an edge spans at most one cell, so the
// result equals smoothing the whole mesh at once, bit for bit. Decimation (meshoptimizer's
// simplifier) then works on the slab's triangles alone with the slab's border kept: the
// triangles touching its faces with slabs k-1 and k+1 stay as they are, so neighbouring slabs
// still meet exactly, sharing the vertices on those faces. Piece removal has already taken the triangles of
// dropped pieces out of every slab (core/mesh_pieces.h).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "core/mesh.h"

namespace vdiso {

struct MeshPostOptions {
    int smoothIterations = 0;        // Taubin iterations; 0: none
    double decimateRatio = 1.0;      // fraction of each slab's triangles to keep, in (0, 1]
    bool largestPiece = false;       // keep only the piece with the most triangles
    uint64_t minPieceTriangles = 0;  // drop pieces with fewer triangles
    bool any() const { return smoothIterations > 0 || decimateRatio < 1.0 || removesPieces(); }
    bool removesPieces() const { return largestPiece || minPieceTriangles > 0; }
};

// The slabs on each side of the one being finished that a window must hold: at least 1 (the next
// slab tells which of this slab's vertices it shares), more when smoothing reaches further than a
// brick of `brickSize` cells.
int haloSlabs(const MeshPostOptions& options, int brickSize);

// Finishes slabs in order, numbering the vertices it writes from 0.
class SlabFinisher {
public:
    explicit SlabFinisher(const MeshPostOptions& options) : mOptions(options) {}

    // `window` holds consecutive slabs (empty ones included: a mesh with no vertices and no
    // triangles, numbered on from the one before), window[center] the one to finish, with
    // haloSlabs() of them on each side where the volume has them. Writes its finished
    // output to `out`: the vertices it writes, numbered out.firstVertex onwards (set to the
    // count written before), and its triangles in the written numbering, for a MeshSink.
    void finish(std::span<const TriangleMesh> window, size_t center, TriangleMesh& out);

    uint64_t verticesWritten() const { return mWritten; }

private:
    MeshPostOptions mOptions;
    uint64_t mWritten = 0;
    // The written number of each of the previous slab's vertices (UINT32_MAX: not written).
    std::vector<uint32_t> mPreviousNumbers;
    uint32_t mPreviousFirst = 0;
};

}  // namespace vdiso
