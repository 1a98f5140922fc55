// Writers of the readers' benchmark inputs (bench/readers.sh, bench/make_inputs.cpp): the head of
// HeadSlices in each format vdiso reads, as the tools of each field write them. Each streams:
// at most one slab of slices (a layer of chunks, 64 slices) is in memory. Each writes `path` (a
// file or a folder that must not exist yet) and throws std::runtime_error naming it on failure.
#pragma once

#include <cstdint>
#include <string>

#include "bench/inputs/head_slices.h"

namespace vdiso::bench {

// A CT series as a scanner exports it: `slices` files of (N/2)^2 i16, 12 bits stored (every
// second sample in x and y of the head's slices, centred in z), stored value = the head's (at
// most 2047), RescaleSlope 1 and
// RescaleIntercept -1024 (so the reader rescales to Hounsfield units), 0.5 mm pixels, 0.5 mm
// slices, ImagePositionPatient and ImageOrientationPatient on each. Explicit VR Little Endian,
// or JPEG Lossless (process 14, first-order prediction) when `jpegLossless`.
void writeDicomSeries(const HeadSlices& head, const std::string& folder, int64_t slices,
                      bool jpegLossless);

// A multi-page TIFF of N pages of N x N u16 (classic TIFF: below 4 GiB up to N = 1024), in
// strips of libtiff's default size (8 KiB: 4 rows at 1024 wide); uncompressed, or deflate
// (zlib's default level 6) after the horizontal-differencing predictor when `deflate`.
void writeTiffStack(const HeadSlices& head, const std::string& path, bool deflate);

// An OME-Zarr 0.4 image (Zarr v2 folder store, "/" chunk keys): `scales` levels, "0" of N^3
// u16 and level l every 2^l-th sample of it on each axis (ceil(N / 2^l) samples, scale 2^l, no
// translation: a nearest-neighbour pyramid), chunks of `chunk`^3, blosc lz4 level 5 with byte
// shuffle (what ome-zarr-py writes by default).
void writeOmeZarr(const HeadSlices& head, const std::string& folder, int64_t chunk, int scales = 1);

// An HDF5 file with the u16 dataset /volume (z, y, x); chunks of `chunk`^3 with shuffle and
// deflate level 1, or contiguous and uncompressed when `chunk` is 0.
void writeHdf5Volume(const HeadSlices& head, const std::string& path, int64_t chunk);

}  // namespace vdiso::bench
