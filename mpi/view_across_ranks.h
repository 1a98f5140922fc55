// View-dependent extraction (SAGE, WISE) shared by the ranks of an mpirun job: the library side
// of `vdiso-mpi extract --method sage|wise`. Every rank opens the store with its own cache and
// takes one part:
//
//   Image:  columns of the image (core/extract/image_strips.h's cut, so about as many active bricks
//           project into each): each rank extracts what shows in its columns, as the threads
//           of one process take strips, and reads only the bricks visible there. A cell
//           showing on both sides of a cut is made by both ranks.
//   Object: depth slabs of the volume along the axis nearest the view direction
//           (core/extract/depth_slabs.h). Each rank extracts its slab, and every `exchangeBricks`
//           bricks it acquires all ranks trade coverage: an exclusive OR-scan of their
//           occlusion pyramids' bottom level (width * height / 8 bytes) in depth order, one
//           scan toward each side of the eye's slab, which each rank merges into its pyramid.
//           So a slab behind gets the coverage of the slabs in front while it runs, and skips
//           (does not read) what they hide. Full resolution only (lod error 0): a coarser brick
//           reaches across slabs. A rank whose traversal has ended keeps taking part in the
//           rounds, with its final coverage, until every rank's has.
//
// Rank 0 gathers every rank's triangles and points (rank order) for the picture and the mesh
// file. A failure on any rank (a read error in one brick, say) ends the rounds on every rank and
// throws RankFailure on all of them naming it.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "cache/brick_cache.h"
#include "core/camera.h"
#include "core/extract/extract_view.h"
#include "mpi/communicator.h"

namespace vdiso::mpi {

enum class ViewPartition { Image, Object };

struct RanksViewOptions {
    ViewExtractOptions view;  // threads per rank (1 for Object); its part is set here
    ViewPartition partition = ViewPartition::Image;
    int exchangeBricks = 4;   // Object: bricks a rank acquires between coverage rounds
    bool gather = true;       // rank 0 gathers the surface (for a picture or a mesh file)
};

// One rank's share and figures.
struct RankViewFigures {
    int partBegin = 0, partEnd = 0;  // Image: its columns; Object: its slab's brick layers
    uint64_t bricksLoaded = 0, bytesRead = 0;
    uint64_t triangles = 0, points = 0;
    int64_t bricksActive = 0, culledByRegion = 0, culledByOcclusion = 0;
    double seconds = 0, ioSeconds = 0, decodeSeconds = 0;
};

struct RanksViewResult {
    int ranks = 1;
    ViewPartition partition = ViewPartition::Image;
    int axis = -1, eyeSlab = -1;  // Object: the slabs' axis and the eye's slab
    // Rank 0: every rank's output, in rank order (with options.gather), and the ranks'
    // statistics summed (bricksActive too: a brick two ranks extract counts twice).
    TriangleMesh mesh;
    PointSet points;
    ExtractStats stats;
    uint64_t bricksLoaded = 0, bytesRead = 0;  // summed over ranks (a brick two ranks read counts twice)
    uint64_t rounds = 0;          // Object: coverage rounds
    uint64_t maskBytes = 0;       // Object: bytes of coverage each rank gave per scan, times the scans
    uint64_t gatheredBytes = 0;   // triangles and points sent to rank 0 (0 without options.gather)
    double seconds = 0;           // the whole job, on rank 0
    std::vector<RankViewFigures> perRank;  // rank 0: one per rank
};

// Collective: every rank calls it with its own cache over the same store and the same camera
// and options. Throws RankFailure on every rank if any failed.
RanksViewResult extractViewAcrossRanks(const Communicator& comm, BrickCache& cache, const Camera& camera,
                                       const RanksViewOptions& options);

}  // namespace vdiso::mpi
