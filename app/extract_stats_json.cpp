#include "app/extract_stats_json.h"

namespace vdiso {

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
}

}  // namespace vdiso
