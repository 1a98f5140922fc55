// The one convention for which side of an isovalue a sample lies on.
//
// A sample is above the isosurface when s > iso. A cell (or brick, or node) whose samples span
// [lo, hi] holds surface exactly when some sample is above and some is not: lo <= iso < hi.
#pragma once

namespace vdiso {

inline bool isAbove(double sample, double iso) { return sample > iso; }

inline bool rangeHoldsIso(double lo, double hi, double iso) { return lo <= iso && iso < hi; }

}  // namespace vdiso
