// MetaImage volumes (.mha with the data in the same file, .mhd with a separate data file), as
// ITK, 3D Slicer and Elastix write them.
//
// Fields read: ObjectType (Image), NDims (3, or 4 with a last size of 1), DimSize, ElementType
// (MET_CHAR/UCHAR/SHORT/USHORT/INT/UINT/LONG/ULONG/FLOAT/DOUBLE, mapped as in sample_decode.h),
// ElementNumberOfChannels (1), ElementSpacing (else ElementSize) for spacing, Offset (else
// Origin or Position) for the origin, BinaryDataByteOrderMSB (or ElementByteOrderMSB),
// CompressedData (zlib, as ITK writes it) with CompressedDataSize when given, HeaderSize
// (bytes to skip in the data file; -1: the data ends the file), and ElementDataFile, which ends
// the header: LOCAL (the data follows) or a file name relative to the header. Keys are matched
// without regard to case; unknown ones are ignored. TransformMatrix (else Rotation or
// Orientation) gives the orientation (core/volume.h) as ITK reads it: NDims groups of NDims
// values, group a the direction of axis a, in ITK's LPS (AnatomicalOrientation is a label ITK
// does not apply, nor do we); a singular or non-finite one is refused, and a file without one
// has no orientation. Refused with a message saying so: ASCII data, 64-bit and multi-channel
// element types, and data split over files (LIST and the "name%03d.raw min max step" form).
//
// Streaming: raw data is read slab by slab and its size checked up front; compressed data is
// inflated as it streams, and must end where the volume does.
#pragma once

#include <memory>
#include <string>

#include "io/readers/slice_reader.h"

namespace vdiso {

std::unique_ptr<SliceReader> openMetaImageVolume(const std::string& path);

}  // namespace vdiso
