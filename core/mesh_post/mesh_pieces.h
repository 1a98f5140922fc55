// The connected pieces of a welded mesh too large for memory, handed over in slabs: union-find
// (disjoint sets, by size, with path halving) over each slab's vertices, then over the slabs'
// pieces where they share vertices. Memory holds two slabs' vertex labels and one entry per
// piece of a slab, never a table over the whole mesh.
//
// Slabs come in order; slab s owns the vertices [firstVertex, firstVertex + count) (numbered on
// from the slab before it) and its triangles refer only to those and to the previous slab's.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

namespace vdiso {

class MeshPieces {
public:
    // Adds a slab; `labels` receives one label per triangle, to be resolved by pieceOf() once
    // every slab is in. Throws std::invalid_argument for a triangle referring elsewhere.
    void addSlab(uint32_t firstVertex, uint32_t vertexCount, std::span<const uint32_t> indices,
                 std::vector<uint32_t>& labels);

    // After the last slab: the piece of a triangle's label (a number below labelCount()) and
    // its size in triangles.
    uint32_t pieceOf(uint32_t label);
    uint64_t trianglesOf(uint32_t label) { return mTriangles[pieceOf(label)]; }
    uint32_t labelCount() const { return uint32_t(mParent.size()); }
    // The number of pieces with triangles.
    uint64_t pieceCount();
    // The label of the piece with the most triangles (the first such, by label); none for an
    // empty mesh.
    uint32_t largestPiece();

private:
    uint32_t unite(uint32_t a, uint32_t b);

    std::vector<uint32_t> mParent;     // per label (a slab's piece), towards its piece
    std::vector<uint64_t> mTriangles;  // per root label: the piece's triangles
    // The previous slab's vertices, by their number minus mPreviousFirst: their labels.
    std::vector<uint32_t> mPreviousLabels;
    uint32_t mPreviousFirst = 0;
    uint32_t mNextFirst = 0;
};

}  // namespace vdiso
