// HDF5 datasets through libhdf5: "FILE.h5:/path/to/dataset" (also .hdf5, .he5, .hdf), or the
// file alone when it holds exactly one 3-D numeric dataset.
//
// The dataset is 3-D, C order (its last dimension is x, its first z), of 8, 16 or 32-bit
// integers or 32/64-bit floats of either byte order (mapped to store types as in
// sample_decode.h; HDF5 converts the byte order), contiguous or chunked, with any filter this
// HDF5 decodes (deflate, shuffle, Fletcher-32, szip when built in, and plugins on
// HDF5_PLUGIN_PATH); a filter it cannot is refused at open, naming it. Anything else (a group,
// a 2-D or 4-D dataset, compound or string data) is refused with a message saying what it is.
// Spacing: 1, or the dataset's "element_size_um" attribute (z, y, x) as Fiji and ilastik
// write it; --spacing overrides either.
//
// Streaming: z-slices are read as hyperslabs; for chunked data the chunk cache holds one layer of
// chunks, so each chunk is decoded once. HDF5's own error printing is turned off; its innermost
// message becomes part of the IoError. libhdf5 runs in a helper process (io/readers/isolated_reader.h):
// it allocates and fills what a damaged file's metadata claims, so a hostile file must not cost
// vdiso its memory.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <utility>

#include "io/readers/slice_reader.h"

namespace vdiso {

// Splits "FILE.h5:/dataset" into the file and the dataset path ("" when only a file with an
// HDF5 suffix is named); nullopt when `path` names no HDF5 file.
std::optional<std::pair<std::string, std::string>> splitHdf5Path(const std::string& path);

// Opens `path` ("FILE.h5:/dataset" or "FILE.h5"). Throws IoError naming the file and dataset.
std::unique_ptr<SliceReader> openHdf5Volume(const std::string& path);

// Opens `dataset` of `file` (empty: the only 3-D numeric dataset).
std::unique_ptr<SliceReader> openHdf5Dataset(const std::string& file, const std::string& dataset);

}  // namespace vdiso
