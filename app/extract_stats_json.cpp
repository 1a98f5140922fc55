#include "app/extract_stats_json.h"

#include <algorithm>

namespace vdiso {

FrameSource frameSourceOf(const BrickStoreReader& store) {
    return {store.path(), store.header().levelCount, store.volume().hasOrientation};
}

void addFrameHeader(JsonObject& s, const ExtractSettings& o, const FrameSource& source, int threads,
                    const ExtractStats& stats, uint64_t points, bool meshWritten) {
    s.add("file", source.file).add("method", o.method).add("iso", *o.iso);
    s.add("metacell", o.metaCellSize).add("threads", threads);
    if (isViewDependent(o.method))
        s.add("lod_error", o.lodError).add("coarse_bricks", stats.view.coarseBricks)
            .add("capped_faces", stats.view.cappedFaces);
    else
        s.add("level", o.level);
    s.add("levels", source.levels);
    if (meshWritten)
        s.add("mesh_space",
              o.physicalMeshes.value_or(true) && source.hasOrientation ? "physical" : "volume");
    s.add("triangles", stats.triangles).add("points", points).add("vertices", stats.vertices);
}

void addTraversalCounters(JsonObject& s, const std::string& method, const ExtractStats& stats) {
    s.add("bricks_active", stats.bricksActive).add("nodes_visited", stats.nodesVisited);
    s.add("meta_cells_active", stats.metaCellsActive).add("cells_active", stats.cellsActive);
    if (isViewDependent(method)) addViewCounters(s, stats);
}

void addViewCounters(JsonObject& s, const ExtractStats& stats) {
    const ViewCounters& view = stats.view;
    s.add("culled_range", view.culledByRange).add("culled_frustum", view.culledByFrustum);
    s.add("culled_occlusion", view.culledByOcclusion).add("culled_region", view.culledByRegion);
    s.add("dropped_subpixel", view.droppedSubPixel);
    s.add("meta_cells_extracted", stats.metaCellsActive).add("scan_s", view.scanSeconds);
    s.add("cells_culled", view.cellsCulled);
    s.add("bricks_prefetched_unused", view.bricksPrefetchedUnused);
    s.add("bricks_culled_by_sub_blocks", view.bricksCulledBySubBlocks);
    s.add("polygons_hidden", view.polygonsHidden);
    s.add("thin_part_points", view.thinPartPoints);
    // The visibility work and the kernel, sampled (core/extract/extract_stats.h), and per kept
    // triangle.
    const double kernel = std::max(view.scanSeconds - view.cellTestSeconds - view.projectionSeconds -
                                       view.coverageSeconds, 0.0);
    const double visibility = view.cellTestSeconds + view.projectionSeconds + view.coverageSeconds + view.boxTestSeconds;
    s.add("cell_test_s", view.cellTestSeconds).add("projection_s", view.projectionSeconds);
    s.add("coverage_s", view.coverageSeconds).add("box_test_s", view.boxTestSeconds).add("kernel_s", kernel);
    const double perTriangle = stats.triangles > 0 ? 1e9 / double(stats.triangles) : 0.0;
    s.add("visibility_ns_per_triangle", visibility * perTriangle).add("kernel_ns_per_triangle", kernel * perTriangle);
}

}  // namespace vdiso
