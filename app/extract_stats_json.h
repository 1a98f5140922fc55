// The statistics of a frame as fields of a --stats JSON object, written the same by vdiso
// extract and the Python module (app/extract_session.h frameStats) and vdiso-mpi extract,
// which adds its ranks' fields between them.
#pragma once

#include <string>

#include "app/extract_settings.h"
#include "core/extract/extract_stats.h"
#include "io/json.h"
#include "io/store/brick_store.h"

namespace vdiso {

// The store a frame came from, as its statistics name it.
struct FrameSource {
    std::string file;
    int levels = 1;
    bool hasOrientation = false;
};
FrameSource frameSourceOf(const BrickStoreReader& store);

// What every frame's statistics open with: file, method, iso, metacell, threads; lod_error,
// coarse_bricks and capped_faces (sage, wise) or level (octree, noise); levels; mesh_space
// when a mesh or points were written; triangles, points, vertices.
void addFrameHeader(JsonObject& s, const ExtractSettings& o, const FrameSource& source, int threads,
                    const ExtractStats& stats, uint64_t points, bool meshWritten);

// The traversal's counts: bricks_active, nodes_visited, meta_cells_active, cells_active, and
// for sage and wise the culling counters below.
void addTraversalCounters(JsonObject& s, const std::string& method, const ExtractStats& stats);

// The culling counters of sage and wise (core/extract/extract_stats.h ViewCounters): culled_range,
// culled_frustum, culled_occlusion, culled_region, dropped_subpixel, meta_cells_extracted,
// scan_s, cells_culled, bricks_prefetched_unused, bricks_culled_by_sub_blocks, polygons_hidden,
// thin_part_points; the visibility work's seconds, sampled: cell_test_s, projection_s, coverage_s,
// box_test_s, the kernel's (kernel_s: scan_s less the first three), and both per kept triangle
// (visibility_ns_per_triangle, kernel_ns_per_triangle).
void addViewCounters(JsonObject& s, const ExtractStats& stats);

}  // namespace vdiso
