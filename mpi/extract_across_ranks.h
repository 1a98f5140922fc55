// Full extraction (the octree method) shared by the ranks of an mpirun job, one welded mesh
// written collectively: the library side of `vdiso-mpi extract`.
//
// Every rank opens the store with its own cache, builds the same list of active bricks and
// partition (brick_partition.h), extracts its part with its own threads
// (FullExtractOptions::bricks), welds across ranks (rank_weld.h) and writes its records into
// one mesh file (collective_mesh.h). Phases end in a collective status check (rank_status.h): a
// failure on any rank throws RankFailure on every rank, naming the first failing rank and its
// message, and leaves no output.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "app/extract_settings.h"
#include "app/extract_stats_json.h"
#include "core/extract/extract_stats.h"
#include "io/remote/remote_options.h"
#include "mpi/communicator.h"

namespace vdiso::mpi {

struct RanksExtractOptions {
    std::string store;     // a path or a URL
    RemoteOptions remote;  // for a URL
    // vdiso extract's settings, checked (app/extract_settings.h checkExtractSettings): the
    // isovalue, meta-cell size, threads and cache per rank, read-ahead, the mesh's space.
    ExtractSettings settings;
    std::string meshPath;  // a .ply, or empty for no mesh
    bool overwrite = false;
    bool cold = false;     // as vdiso extract --cold: bricks from disk (O_DIRECT)
};

// One rank's figures.
struct RankExtractFigures {
    uint64_t bricks = 0;          // its part of the active bricks
    int64_t firstBrick = -1, lastBrick = -1;  // ids, -1 for an empty part
    uint64_t weight = 0;          // the part's weight (active sub-blocks)
    uint64_t bricksLoaded = 0, bytesRead = 0;
    uint64_t triangles = 0, verticesOwned = 0, verticesBorrowed = 0;
    uint64_t weldBytesSent = 0;   // to other ranks, welding
    uint64_t meshBytes = 0;       // its records in the PLY
    double seconds = 0;           // extraction, welding and writing on this rank
    double extractSeconds = 0, ioSeconds = 0, decodeSeconds = 0;
};

struct RanksExtractResult {
    int ranks = 1;
    // The job's surface as one extraction's: triangles, vertices, bricks_active (all ranks'),
    // nodes_visited (rank 0's, the same tree on every rank), meta_cells_active and cells_active.
    ExtractStats stats;
    FrameSource source;
    uint64_t bricksLoaded = 0, bytesRead = 0;
    double seconds = 0;  // the whole job, on rank 0
    std::string readMethod;
    std::vector<RankExtractFigures> perRank;  // rank 0 only: one per rank
};

// Collective. Throws RankFailure on every rank if any rank failed (options are the same on all).
RanksExtractResult extractOctreeAcrossRanks(const Communicator& comm, const RanksExtractOptions& options);

}  // namespace vdiso::mpi
