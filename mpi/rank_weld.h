// One vertex numbering across the ranks of a full extraction, the one a single process gives.
//
// Each rank extracts its part of the bricks (mpi/brick_partition.h) with vertices numbered from
// 0, including those on edges it shares with other ranks' bricks (FullExtractOptions::
// borderVertices lists these by edge key). Such a vertex belongs to the rank of the earliest
// active brick with a cell on its edge (core/kernel/edge_vertex_map.h bricksOnEdge), as in one process
// it belongs to the first brick making it; the other ranks borrow its number. An exclusive
// scan of the counts of owned vertices gives each rank its first global number; borrowers send
// the edge keys to the owners and get the numbers back (two all-to-all exchanges). As parts are
// contiguous in brick id order and a part numbers its vertices in the single process's order,
// the result is that numbering exactly: rank r's owned vertices follow rank r-1's.
#pragma once

#include <cstdint>

#include "core/brick_layout.h"
#include "core/kernel/edge_vertex_map.h"
#include "core/mesh.h"
#include "core/volume.h"
#include "mpi/brick_partition.h"
#include "mpi/communicator.h"

namespace vdiso::mpi {

struct RankMeshNumbering {
    uint64_t firstVertex = 0, ownedVertices = 0, totalVertices = 0;
    uint64_t firstTriangle = 0, triangles = 0, totalTriangles = 0;
    uint64_t borrowedVertices = 0;  // this rank's vertices owned by an earlier rank
    uint64_t bytesSent = 0;         // edge keys asked and numbers answered, to other ranks
};

// Collective. `mesh`: this rank's part (partition.part(comm.rank())) as extractOctree made it,
// vertices from 0; `border`: its border vertices. On return `mesh` holds the vertices this rank
// owns, in order, with firstVertex set, and its triangles refer to global vertex numbers.
// Throws std::runtime_error, only after the last collective call (so a phase check can follow),
// when the mesh has more
// than 2^32 - 1 vertices (PLY's u32 indices) or an owner lacks a vertex it should have made.
RankMeshNumbering weldAcrossRanks(const Communicator& comm, const BrickPartition& partition,
                                  const VolumeInfo& volume, const BrickLayout& layout,
                                  const EdgeVertexMap& border, TriangleMesh& mesh);

}  // namespace vdiso::mpi
