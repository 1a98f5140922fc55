// A volume read a few samples larger than its source on each axis, the extra samples the
// source's last ones repeated (its faces clamped, as bricks are gathered at a volume's faces):
// an OME-Zarr's coarse scale, one or two samples short of the level of detail it stands for
// (core/brick_levels.h levelDims), read as that level (io/store/zarr_index.h).
#pragma once

#include <memory>

#include "io/readers/slice_reader.h"

namespace vdiso {

// `source` as a volume of `dims` samples (at least its own on every axis); `source` itself when
// they are its dims.
std::unique_ptr<SliceReader> edgePaddedReader(std::unique_ptr<SliceReader> source, const Dims3& dims);

}  // namespace vdiso
