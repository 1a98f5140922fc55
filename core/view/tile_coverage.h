// A polygon's coverage made a tile at a time, straight into the occlusion pyramid's bottom words
// (core/view/occlusion_pyramid.h): the path SAGE's traversal takes for each polygon of a few
// pixels (core/view/polygon_coverage.h), after Masked Occlusion Culling's per-tile masks.
//
// Covers exactly the pixel centres scanConvertPolygon (core/view/scan_convert.h) covers, by its
// rules and its arithmetic: each edge's crossing of a row is computed from its upper end as
// scanRow computes it, and a centre is inside when the crossings at or left of it wind nonzero.
// Instead of sorting crossings into runs and covering each run's words, a row's winding is kept
// as eight byte counters in one word (one per column of the tile), each crossing adds +-1 to
// the bytes at and right of it, and the nonzero bytes become the row's 8 bits of the tile's
// mask. A tile already full is skipped before any crossing is made, and a tile's mask is
// merged into its word once. For polygons of up to kTileCoverageEdges edges (marching cubes
// makes at most 7); returns false without covering anything for more, or for a vertex that is
// not finite.
//
// coverPolygonTiles(v, n, rect, pyramid, newCentres, simd): rect is the polygon's pixel-centre
// rectangle clamped to the image (PolygonCoverage's box) or a larger one; sets newCentres when
// a centre not covered before was covered. The caller runs pyramid.propagate() before the next
// query. `simd` (core/simd.h): the baseline makes each row's crossings and a tile's rows one by
// one; AVX2 a tile row's eight rows at once where none crosses more than two edges (each row a
// run between its least and greatest crossing, each tile's eight bytes made by shifts), else
// four rows at once, each crossing and each tile's counters in one register. All give the same
// bits. Either way, a polygon whose centres lie in one or two rows of one tile
// (most, where cells are a pixel or two) takes a path of its own: every edge on every row, no
// branch on the data (with AVX2 four edges a register, up to 8), the same bits again.
#pragma once

#include <cstdint>

#include <glm/vec2.hpp>

#include "core/simd.h"
#include "core/view/occlusion_pyramid.h"
#include "core/view/scan_convert.h"
#include "core/view/view_culler.h"

namespace vdiso {

constexpr int kTileCoverageEdges = 16;

bool coverPolygonTiles(const glm::dvec2* v, int n, const PixelRect& rect, OcclusionPyramid& pyramid,
                       bool& newCentres, SimdLevel simd);

}  // namespace vdiso
