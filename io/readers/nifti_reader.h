// NIfTI-1 volumes: single-file .nii and .nii.gz, and .hdr/.img pairs (either half may be
// gzipped, either may be named). Gzip is recognised by its magic bytes, not the name.
//
// Datatypes u8, i8, i16, u16, i32, u32, f32, f64 (mapped as in sample_decode.h); either byte
// order, detected from sizeof_hdr. scl_slope/scl_inter are applied (the store then holds f32)
// unless the slope is 0, NaN (as nibabel writes for unscaled images, and nifti1_io reads as 0),
// or 1 with intercept 0; an infinite slope is refused. Placement (core/volume.h, converted from
// NIfTI's RAS to LPS): the qform when qform_code > 0 (quaternion, qfac = pixdim[0], qoffset;
// pixdim gives spacing), else the sform when sform_code > 0 (its columns give direction and
// spacing, its last column the origin), else none (pixdim's spacing, origin 0, no orientation).
// A placement that is not finite or singular is refused. Volumes with more than one frame, complex and RGB
// types, and NIfTI-2 are refused with a message saying so.
#pragma once

#include <memory>
#include <string>

#include "io/readers/slice_reader.h"

namespace vdiso {

std::unique_ptr<SliceReader> openNiftiVolume(const std::string& path);

}  // namespace vdiso
