// Rounding pixel coordinates to ints, for values already clamped to a few pixels beyond the
// image (so that they fit an int): ceil and floor by truncation and one comparison, exactly
// std::ceil's and std::floor's results there. Built for the x86-64 baseline (no SSE4.1
// roundsd), std::ceil is a dozen instructions, and the per-cell and per-polygon tests round
// several coordinates each: the one line of scan_convert.h that did was 8 % of a CT's normal
// view.
#pragma once

namespace vdiso {

// ceil(x) and floor(x) for finite x with |x| < 2^31.
inline int ceilToInt(double x) {
    const int i = int(x);  // towards zero: the ceiling of a negative x, the floor of a positive one
    return i + (double(i) < x);
}
inline int floorToInt(double x) {
    const int i = int(x);
    return i - (double(i) > x);
}

}  // namespace vdiso
