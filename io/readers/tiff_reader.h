// TIFF stacks through libtiff: a multi-page TIFF or BigTIFF (one page per z-slice), or a folder
// or glob of single-page slices taken in natural order (slice_2 before slice_10, io/readers/file_list.h).
//
// Pages are single-channel (grayscale) images of 8, 16 or 32-bit integers or 32/64-bit floats
// (mapped to store types as in sample_decode.h), in strips or tiles, with any compression this
// libtiff decodes. Pages marked as reduced-resolution copies (NewSubfileType bit 0, the
// previews some writers add) are skipped. Every page must have the first page's width, height
// and sample type: a page that differs is refused, naming it. Colour, palette, 1/4/12-bit and
// 3-D (ImageDepth) pages are refused with a message saying so.
//
// Spacing: TIFF has no z spacing, so it is 1 unless the file is an ImageJ stack (its
// ImageDescription "spacing=" and the X/YResolution it writes as pixels per unit); `--spacing`
// (InputOptions::spacing) overrides either. The origin is 0.
//
// Streaming: the pages are checked at open (their directories only), and read one at a time;
// memory is one page's strips or tiles, whatever the number of pages. libtiff's messages are
// caught and become part of the IoError, never printed.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "io/readers/slice_reader.h"

namespace vdiso {

// `path` is a TIFF file (every page a slice), a folder (its .tif/.tiff files, each one slice)
// or a glob pattern (isGlobPattern). Throws IoError naming the file or page on any problem.
std::unique_ptr<SliceReader> openTiffVolume(const std::string& path);

// One single-page TIFF file per slice, in the order given (z = index).
std::unique_ptr<SliceReader> openTiffSlices(const std::vector<std::string>& files);

// True if the file starts with a TIFF or BigTIFF signature (II or MM, then 42 or 43).
bool hasTiffMagic(const std::string& path);

}  // namespace vdiso
