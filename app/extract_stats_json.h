// The statistics of a view-dependent extraction as fields of a --stats JSON object, written
// the same by vdiso extract, vdiso-mpi extract and the Python module.
#pragma once

#include "core/extract/extract_stats.h"
#include "io/json.h"

namespace vdiso {

// The culling counters of sage and wise (core/extract/extract_stats.h ViewCounters): culled_range,
// culled_frustum, culled_occlusion, culled_region, dropped_subpixel, meta_cells_extracted,
// scan_s, cells_culled, bricks_prefetched_unused, bricks_culled_by_sub_blocks, polygons_hidden,
// thin_part_points; the visibility work's seconds, sampled: cell_test_s, projection_s, coverage_s,
// box_test_s, the kernel's (kernel_s: scan_s less the first three), and both per kept triangle
// (visibility_ns_per_triangle, kernel_ns_per_triangle).
void addViewCounters(JsonObject& s, const ExtractStats& stats);

}  // namespace vdiso
