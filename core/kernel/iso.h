// The one convention for which side of an isovalue a sample lies on.
//
// A sample is above the isosurface when s > iso. A cell (or brick, or node) whose samples span
// [lo, hi] holds surface exactly when some sample is above and some is not: lo <= iso < hi.
//
// Non-finite samples (f32 volumes; a float64 input outside the float range becomes ±inf):
// +inf is above every isovalue and -inf below, as ordered values. NaN is below every isovalue
// (s > iso is false), so wherever values are ranged it counts as -inf (rangeValue()): a range
// is never NaN, and the range test agrees with the cell test. Where a crossing is interpolated,
// an edge from a non-finite sample to a finite one crosses at the finite end (the limit of
// linear interpolation as one end grows without bound), and an edge between two non-finite
// samples crosses at its middle (crossingFraction()). Isovalues themselves must be finite.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <type_traits>

namespace vdiso {

inline bool isAbove(double sample, double iso) { return sample > iso; }

inline bool rangeHoldsIso(double lo, double hi, double iso) { return lo <= iso && iso < hi; }

// Throws std::invalid_argument unless the isovalue is finite (every extractor's entry calls it).
inline void requireFiniteIso(double iso) {
    if (!std::isfinite(iso)) throw std::invalid_argument("the isovalue must be a finite number");
}

// The value a sample takes where ranges are measured: itself, but -inf for NaN. A select, not a
// branch, so range loops still vectorise.
template <class T>
inline T rangeValue(T v) {
    if constexpr (std::is_floating_point_v<T>)
        return v == v ? v : -std::numeric_limits<T>::infinity();
    else
        return v;
}

// Where along the edge from s0 to s1 (0 at s0, 1 at s1) the isosurface crosses, for samples on
// opposite sides of `iso` (one above, one not). Always in [0, 1], never NaN.
inline double crossingFraction(double s0, double s1, double iso) {
    const double t = (iso - s0) / (s1 - s0);
    if (t >= 0 && t <= 1) return t;
    const bool finite0 = std::isfinite(s0), finite1 = std::isfinite(s1);
    if (finite0 && !finite1) return 0.0;
    if (!finite0 && finite1) return 1.0;
    if (!finite0 && !finite1) return 0.5;
    // Rounding, or samples not on opposite sides (then t may be NaN: 0/0).
    return t > 1 ? 1.0 : t < 0 ? 0.0 : 0.5;
}

}  // namespace vdiso
