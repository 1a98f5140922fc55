// The filter that makes level l of a volume from level l-1 (core/brick_levels.h): the separable
// tent [1/4, 1/2, 1/4] on each axis, centred on the level-(l-1) sample 2s under level-l sample
// s, indices clamped to the volume.
//
// Why the tent: it is the smallest filter that is a true low-pass centred on the coarse
// sample, so the coarse sample stays where the coarse grid puts it (a box filter over 2^3
// would shift it half a fine cell) and detail finer than a coarse cell is averaged away rather
// than aliased, as plain subsampling would (a thin wall is kept or lost depending on where the
// grid falls). A step edge between two values crosses their mid value at the same place after
// the filter, so isosurfaces of scans (skin, bone) stay put from level to level. Weights sum to
// one and are positive: every coarse sample lies within the range of the fine samples it
// averages; integers are rounded to the nearest. A NaN among them makes the sample NaN.
#pragma once

#include <cstdint>

#include "core/volume.h"

namespace vdiso {

// Rows [y0, y1) of level-l slice z, `coarse` samples in x and y, from the three level-(l-1)
// slices 2z-1, 2z and 2z+1 (clamped to the fine volume: the caller passes the same slice
// twice at a border), each `fine` samples in x and y. Output rows are x fastest, coarse[0]
// samples each, written to out + y * coarse[0].
template <class T>
void downsampleRows(const T* below, const T* at, const T* above, const Dims3& fine, const Dims3& coarse,
                    int64_t y0, int64_t y1, T* out);

}  // namespace vdiso
