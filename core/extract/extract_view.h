// View-dependent isosurface extraction: SAGE (Livnat & Hansen) and WISE, its predecessor.
//
// For one camera, the min/max tree over bricks is walked front to back (children on the
// eye's side of each split first: exact for axis-aligned splits), and inside each loaded brick
// its meta-cells likewise. Each node or meta-cell is tested in turn:
//   1. range: skipped if its [min, max] cannot hold the isovalue;
//   2. frustum: skipped if its screen box (SAGE §3.4 estimate, or the exact 8-corner box)
//      misses the image; a box crossing the near plane counts as visible and is refined,
//      unless it lies wholly outside one of the frustum's planes (behind the near plane or the
//      eye: an eye inside the volume sees none of what lies behind it);
//   3. occlusion: skipped if every pixel centre in its screen box is already covered in the
//      occlusion pyramid — bricks are acquired only after passing 1-3, and after one of their
//      sub-blocks (ranges from the store's index, core/trees/sub_blocks.h) passes 1-3 too, which
//      is how the pyramid culls disk reads;
//   4. points (SAGE §3.3): a box under two pixels each way becomes one point with a normal
//      if the Fig. 4 rule finds the pixel centre it covers (and that pixel is marked), or is
//      dropped;
//   5. otherwise a node descends, and a meta-cell is extracted: the corners of its crossed
//      cells are projected once (core/view/corner_projection.h), its polygons placed from them
//      and scan-converted into the bottom of the pyramid, changed tiles propagated upward
//      after the meta-cell (SAGE §3.1-3.2), and the triangles of the cells that draw something
//      appended. Its cells are visited front to back too; with cellTests, each is first tested
//      like a node by its corners' exact box (no pixel centre, or all covered, or all eight
//      corners behind the near plane: skipped), so cells hide cells, and a polygon whose scan
//      conversion covers no new pixel centre, or whose vertices all lie behind the near plane,
//      keeps no triangles (nor makes a vertex).
// WISE = exact boxes, no points, one triangle at a time inserted top-down (Greene's masks).
// Every SAGE feature is a switch, for the ablations of the paper's Tables 3-4.
#pragma once

#include <cstdint>

#include "core/kernel/brick_extractor.h"
#include "core/brick_source.h"
#include "core/extract/brick_prefetcher.h"
#include "core/camera.h"
#include "core/extract/extract_stats.h"
#include "core/mesh.h"
#include "core/view/occlusion_pyramid.h"
#include "core/lod/thin_parts.h"
#include "core/trees/meta_cell_range_cache.h"
#include "core/trees/minmax_tree.h"
#include "core/progress.h"

namespace vdiso {

// Receives a view-dependent extraction brick by brick, front to back, as it runs (remote
// viewing streams each brick's surface as soon as it is made: serve/). For each brick that
// passes the tests, beginBrick chooses what the traversal makes of it:
//   Whole: the brick's whole surface, the same for every camera (its hidden meta-cells are
//          extracted too, without scan conversion; no points, no per-cell tests). Every polygon
//          it scan-converts lies in that surface, so the coverage stays conservative.
//   Held:  the consumer has the brick's whole surface already: the visible part is made only
//          to mark the occlusion pyramid (its polygons are scan-converted; no triangle is
//          appended and no normal computed), and what is left handed over to be dropped.
//   Part:  what SAGE makes of it for this camera: points and the triangles of visible cells.
// endBrick then gets that output: mesh.positions hold the vertices numbered mesh.firstVertex
// onwards (with per-cell tests, also some no kept triangle refers to: a consumer that packs
// vertices drops them anyway), mesh.indices refer to those only (bricks share no vertices in
// streaming), points
// hold its points; both are cleared after the call. `seams`: the caps closing the brick's faces
// that meet another level of detail for this camera (core/lod/face_cap.h; empty without levels),
// vertices numbered from seams.firstVertex, whatever the use: they depend on the camera, so
// they are never part of a Whole brick's surface. Calls come from the strip's thread, so an
// implementation used with threads > 1 must be thread-safe; a brick showing in two strips
// is offered by both.
class ViewStream {
public:
    enum class Use { Whole, Held, Part };
    virtual ~ViewStream() = default;
    // Before brick `brick` (of level of detail `level`) is read. `cellPixels`: how many pixels a
    // cell's side spans on screen at most (infinite for a brick crossing the near plane).
    // Returns false to abandon the extraction here (a newer camera came): nothing more is read
    // or made.
    virtual bool beginBrick(int64_t brick, int level, double cellPixels, Use& use) = 0;
    virtual void endBrick(int64_t brick, Use use, const TriangleMesh& mesh, const PointSet& points,
                          const TriangleMesh& seams) = 0;
};

// Coverage made elsewhere, merged into a traversal's pyramid while it runs: the other
// processes' surfaces in front of this one's part of the volume (object-space partition, mpi/).
// Coverage only grows and what is merged lies in front, so culling stays conservative. Called
// from the traversal's own thread (threads must be 1 with it).
class CoverageExchange {
public:
    virtual ~CoverageExchange() = default;
    // Between two nodes of the traversal, `bricks` acquired so far: may cover more pixels of
    // `pyramid` (OcclusionPyramid::coverTiles, then propagate()). May throw to end the
    // extraction (another process failed): the traversal unwinds (its reads ahead stop, pinned
    // bricks are released), ended() is not called, and the exception leaves
    // extractViewDependent.
    virtual void between(OcclusionPyramid& pyramid, int64_t bricks) = 0;
    // The traversal has ended with `pyramid` as its coverage.
    virtual void ended(const OcclusionPyramid& pyramid) = 0;
};

struct ViewExtractOptions {
    double iso = 0;
    // Halved for a level whose meta-cells would be under 4 pixels wherever they are
    // (extract_view.cpp's viewMetaCellSize), down to 4.
    int metaCellSize = kDefaultMetaCellSize;
    bool scanPolygons = true;  // false: scan-convert each fan triangle on its own
    bool estimateBox = true;   // false: the exact 8-corner box
    bool points = true;        // sub-pixel nodes become points
    bool bottomUp = true;      // false: top-down insertion of each triangle (WISE)
    // Beyond the paper: inside an extracted meta-cell, skip each cell whose screen box covers
    // no pixel centre, or only centres nearer meta-cells already cover, and keep a polygon's
    // triangles only when its scan conversion covers a pixel centre not covered before. Where
    // cells are about the size of pixels this brings the output near the visible-surface
    // oracle.
    bool cellTests = true;
    // False: no occlusion culling at all (for the measures of what it saves): nothing is
    // scan-converted into the pyramid, so no box is ever hidden, and there are no cell tests.
    bool occlusion = true;
    // Bricks a reader thread loads ahead of the traversal (core/extract/brick_prefetcher.h), found by
    // a look-ahead that runs tests 1-3 ahead of it; 0: none. The source's cache must hold
    // more than this many bricks.
    int prefetchBricks = 0;
    int prefetchReaders = BrickPrefetcher::kDefaultReaders;  // threads reading them
    // Bricks next in turn read ahead before they are known to show (core/extract/brick_look_ahead.h):
    // a few for a disk, more for a store at a URL, where each read waits a round trip.
    int prefetchNear = 2;  // BrickLookAhead::kNearBricks
    // Vertical strips of the image extracted in parallel, one thread each, with about as many
    // active bricks projecting into each. A strip's traversal treats the rest of the image as
    // covered, so it extracts what shows in its strip; a cell showing on both sides of a strip
    // border is kept by both (its triangles appear twice: 0.3% more for SAGE, 1% for WISE,
    // whose meta-cells on a border are whole in both). Bricks are read once, through the
    // shared source; each strip prefetches prefetchBricks / threads.
    int threads = 1;
    // When set, output goes brick by brick to the stream instead of the mesh and points.
    ViewStream* stream = nullptr;
    // Levels of detail (docs/design.md): a node is extracted at the coarsest level of the source
    // whose cells span at most this many pixels on screen where the node is nearest the eye
    // (core/lod/view_levels.h); 0: level 0 only. Points stay for what is under a pixel.
    double lodError = 0;
    // Where a brick meets another level, close its surface on that face (core/lod/face_cap.h), so
    // no crack between levels shows; false leaves the seams open (for the measure of it).
    bool capSeams = true;
    // When set, bricks' meta-cell ranges are kept there from one extraction to the next (frames
    // of a moving camera over the same source and meta-cell size).
    MetaCellRangeCache* rangeCache = nullptr;
    // When set, the parts coarse bricks lose (core/lod/thin_parts.h) are kept there likewise
    // (frames over the same source).
    LostPartMemo* lostParts = nullptr;
    // When set, the min/max tree over the source, built once for many extractions (frames of a
    // moving camera): MinMaxTree(source.levels(), source.brickRanges()). Otherwise each
    // extraction builds its own (a 2560^3 volume's 512,000 bricks take tens of ms).
    const MinMaxTree* tree = nullptr;

    // The part of the image to extract: pixel columns [columnBegin, columnEnd) (end -1: the
    // image's width), the rest treated as covered; threads split this part into strips. A
    // process's share of an image-space partition (mpi/).
    int columnBegin = 0, columnEnd = -1;
    // When set, only the bricks of this region are extracted: nodes wholly outside it are culled
    // (counted in culledByRegion), nodes reaching across its faces descend. Full resolution only
    // (lodError 0): a coarser level's brick reaches across the region's faces, so the parts would
    // no longer be sorted in depth.
    const BrickRegion* region = nullptr;
    // When set, coverage from elsewhere merged as the traversal runs (threads 1).
    CoverageExchange* coverage = nullptr;

    static ViewExtractOptions sage(double iso) { return {iso}; }
    static ViewExtractOptions wise(double iso) {
        ViewExtractOptions o{iso};
        o.scanPolygons = false;
        o.estimateBox = false;
        o.points = false;
        o.bottomUp = false;
        o.cellTests = false;
        return o;
    }
};

// Appends the surface visible from `camera` to `mesh` and sub-pixel points to `points`.
// Culling is conservative: rendered from the same camera, the result looks like the full
// surface. options.threads strips run in parallel; the source must then be thread-safe (a
// BrickCache is).
ExtractStats extractViewDependent(BrickSource& source, const Camera& camera,
                                      const ViewExtractOptions& options, TriangleMesh& mesh,
                                      PointSet& points, const ProgressFn& progress = {});
// The same, each brick's surface handed to options.stream (required) as it is made: nothing is
// kept past its brick.
ExtractStats streamViewDependent(BrickSource& source, const Camera& camera, const ViewExtractOptions& options);

}  // namespace vdiso
