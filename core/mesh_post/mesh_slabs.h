// Post-processing a full extraction's surface out of core, slab by slab: a slab is the output of
// one layer of bricks (brick z coordinate k), as core/extract/extract_full.h's BrickMeshSink hands it
// over. Slab k owns the vertices its bricks made, numbered on from slab k-1's, and its triangles
// refer only to those and to slab k-1's; the vertices shared with slab k+1 on their common brick
// face are slab k's.
//
// Each slab is finished with the slabs within haloSlabs() of it at hand (a window), which is all
// the smoothing of its vertices can reach: Taubin smoothing (core/mesh_post/mesh_smooth.h) moves a vertex
// by its neighbours within 2 * iterations + 1 edges, and an edge spans at most one cell, so the
// result equals smoothing the whole mesh at once, bit for bit. Decimation (meshoptimizer's
// simplifier) then works on the slab's triangles alone with the slab's border kept: the
// triangles touching its faces with slabs k-1 and k+1 stay as they are, so neighbouring slabs
// still meet exactly, sharing the vertices on those faces. Piece removal has already taken the triangles of
// dropped pieces out of every slab (core/mesh_post/mesh_pieces.h).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <glm/vec3.hpp>

#include "core/mesh.h"

namespace vdiso {

struct MeshPostOptions {
    int smoothIterations = 0;        // Taubin iterations; 0: none
    double decimateRatio = 1.0;      // fraction of each slab's triangles to keep, in (0, 1]
    bool largestPiece = false;       // keep only the piece with the most triangles
    uint64_t minPieceTriangles = 0;  // drop pieces with fewer triangles
    bool any() const { return smoothIterations > 0 || decimateRatio < 1.0 || removesPieces(); }
    bool removesPieces() const { return largestPiece || minPieceTriangles > 0; }
    int threads = 1;  // slabs shaped at once (the result is the same for any count)
};

// The slabs on each side of the one being finished that a window must hold: at least 1 (the next
// slab tells which of this slab's vertices it shares), more when smoothing reaches further than a
// brick of `brickSize` cells.
int haloSlabs(const MeshPostOptions& options, int brickSize);

// A slab smoothed and decimated, its vertices not yet numbered for writing.
struct ShapedSlab {
    uint32_t firstVertex = 0;
    std::vector<glm::vec3> positions, normals;  // the slab's own vertices
    std::vector<uint32_t> indices;              // its triangles, in the extraction's numbering
    std::vector<bool> usedByNext;               // which own vertices the next slab's triangles use
};

// Smooths and decimates window[center]. `window` holds consecutive slabs (empty ones included: a
// mesh with no vertices and no triangles, numbered on from the one before), with haloSlabs() of
// them on each side of the centre where the volume has them. Slabs may be shaped at once on
// several threads: the result depends on the window alone.
ShapedSlab shapeSlab(const MeshPostOptions& options, std::span<const TriangleMesh> window, size_t center);

// Numbers shaped slabs' vertices for a MeshSink, slab after slab in order, from 0: writes a
// slab's output to `out`, the vertices it writes (those its triangles or the next slab's use)
// numbered out.firstVertex (the count written before) onwards and its triangles in that
// numbering.
class SlabWriter {
public:
    void write(const ShapedSlab& slab, TriangleMesh& out);
    uint64_t verticesWritten() const { return mWritten; }

private:
    uint64_t mWritten = 0;
    // The written number of each of the previous slab's vertices (UINT32_MAX: not written).
    std::vector<uint32_t> mPreviousNumbers;
    uint32_t mPreviousFirst = 0;
};

}  // namespace vdiso
