// What one extraction did, for every method: the full ones (core/extract/extract_full.h) fill the
// common part, the view-dependent ones (core/extract/extract_view.h) the nested view counters too.
#pragma once

#include <cstdint>

namespace vdiso {

// The view-dependent traversal's tests and what they culled (core/extract/extract_view.h).
struct ViewCounters {
    int64_t culledByRange = 0, culledByFrustum = 0, culledByOcclusion = 0;
    int64_t droppedSubPixel = 0;  // sub-pixel boxes covering no free pixel centre
    int64_t culledByRegion = 0;   // nodes outside the extraction's region (ViewExtractOptions)
    int64_t cellsCulled = 0;      // by the per-cell test
    int64_t polygonsHidden = 0;   // scan-converted without covering a new pixel centre
    int64_t bricksCulledBySubBlocks = 0;  // box passed, no sub-block did: not read
    int64_t bricksPrefetchedUnused = 0;   // read ahead, then hidden before the traversal came
    int64_t coarseBricks = 0;  // of the bricks acquired, those of a coarser level of detail
    int64_t cappedFaces = 0;   // brick faces closed where levels meet (core/lod/face_cap.h)
    uint64_t points = 0;
    int64_t thinPartPoints = 0;  // of the points, those for thin parts a coarse level lost
    bool abandoned = false;  // a stream's beginBrick returned false
    double scanSeconds = 0;  // extracting visible meta-cells, with their projection and scan
                             // conversion into the pyramid (interleaved per polygon)
    // The visibility work, sampled (core/clock.h SampledTimer): the per-cell tests, projecting
    // polygons' vertices, covering polygons (box query, tiles, rounding check), and the tests of
    // the boxes of meta-cells within bricks. All but the last are part of scanSeconds; the rest
    // of it is the cell kernel's (vertices, normals, triangles).
    double cellTestSeconds = 0, projectionSeconds = 0, coverageSeconds = 0, boxTestSeconds = 0;

    ViewCounters& operator+=(const ViewCounters& o) {
        culledByRange += o.culledByRange;
        culledByFrustum += o.culledByFrustum;
        culledByOcclusion += o.culledByOcclusion;
        droppedSubPixel += o.droppedSubPixel;
        culledByRegion += o.culledByRegion;
        cellsCulled += o.cellsCulled;
        polygonsHidden += o.polygonsHidden;
        bricksCulledBySubBlocks += o.bricksCulledBySubBlocks;
        bricksPrefetchedUnused += o.bricksPrefetchedUnused;
        coarseBricks += o.coarseBricks;
        cappedFaces += o.cappedFaces;
        points += o.points;
        thinPartPoints += o.thinPartPoints;
        abandoned |= o.abandoned;
        scanSeconds += o.scanSeconds;
        cellTestSeconds += o.cellTestSeconds;
        projectionSeconds += o.projectionSeconds;
        coverageSeconds += o.coverageSeconds;
        boxTestSeconds += o.boxTestSeconds;
        return *this;
    }
};

struct ExtractStats {
    uint64_t triangles = 0, vertices = 0;  // produced in all (streamed or held)
    // octree: min/max tree nodes; noise: span-space answers; sage/wise: tree nodes and
    // meta-cell boxes tested
    int64_t nodesVisited = 0;
    int64_t bricksActive = 0;     // bricks acquired for extraction (by any strip: once)
    int64_t metaCellsActive = 0;  // meta-cells extracted
    int64_t cellsActive = 0;      // cells whose polygons were made
    double preprocessSeconds = 0;  // noise: building the meta-cell span space
    double extractSeconds = 0;     // everything else, brick reads included
    // Of which waiting for bricks (reads and decodes not hidden); with image strips summed
    // over strips, where a strip also waits for a brick another strip is loading.
    double brickWaitSeconds = 0;
    ViewCounters view;  // sage and wise only

    // Sums the counters and seconds of parts run side by side (image strips), but not
    // triangles, vertices, bricksActive and extractSeconds: the caller knows those of the whole.
    ExtractStats& addPart(const ExtractStats& o) {
        nodesVisited += o.nodesVisited;
        metaCellsActive += o.metaCellsActive;
        cellsActive += o.cellsActive;
        brickWaitSeconds += o.brickWaitSeconds;
        view += o.view;
        return *this;
    }
};

}  // namespace vdiso
