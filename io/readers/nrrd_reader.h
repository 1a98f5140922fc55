// NRRD volumes (teem's format, as ITK, 3D Slicer and teem write them).
//
// Attached (.nrrd) and detached (.nhdr + "data file:") headers; raw and gzip encodings;
// the types that map to the store (see sample_decode.h); endian; byte skip and line skip;
// "space directions"/"spacings" for spacing and "space origin" for origin. With an anatomical
// "space" (right-anterior-superior, left-anterior-superior, left-posterior-superior, their short
// and -time forms) and a vector for each axis, the space directions also give the orientation
// (core/volume.h), converted to LPS with the origin; a singular or non-finite one is refused.
// Spaces without patient directions (scanner-xyz, 3D-right-handed, 3D-left-handed) and headers
// without "space" are read without orientation (vdiso convert and vdiso info say so); an
// unknown space is refused. Three-dimensional
// scalar volumes only (a 4-D header whose first or last axis has size 1 counts as 3-D): anything
// else is refused with a message saying what is unsupported, as are the ascii, hex and bzip2
// encodings, 64-bit integer and block types, and multi-file data ("data file: LIST" and the
// "name%03d.raw <min> <max> <step>" form).
#pragma once

#include <memory>
#include <string>

#include "io/readers/slice_reader.h"

namespace vdiso {

std::unique_ptr<SliceReader> openNrrdVolume(const std::string& path);

}  // namespace vdiso
