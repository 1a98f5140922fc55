// From the headers of DICOM files to the volume they make: which series, in what order, on what
// grid, stored as what type. No file access and no GDCM here (io/readers/dicom_reader.cpp reads the
// headers), so the geometry rules are tested on headers alone.
//
// Order: slices are sorted by their ImagePositionPatient projected on the slice normal (the cross
// product of the ImageOrientationPatient row and column directions), as ITK and 3D Slicer do;
// file names and InstanceNumber are not trusted. Only when a slice has no position or
// orientation does InstanceNumber order them, with SpacingBetweenSlices (else SliceThickness,
// else 1) as the z spacing.
//
// Gaps: the store is a regular grid, so the slice positions must be evenly spaced. A missing
// slice or an uneven gap (more than 1% off the median step) is refused with a message naming
// the two slices around the gap and its size, rather than accepted with a warning: a stretched
// skull is easy to miss in a pipeline, and a warning scrolls away. So are two slices at one
// position (several acquisitions in one series), slices of other orientations or sizes, and a
// sheared stack (gantry tilt), which a grid of origin and spacing cannot place.
//
// Spacing: x from PixelSpacing's column spacing (its second value), y from its row spacing,
// z from the positions' step. Origin: the first slice's ImagePositionPatient (in that order).
// Orientation (core/volume.h, LPS as DICOM's patient coordinates are): i along the row cosines
// of ImageOrientationPatient, j along the column cosines, k along their cross product (the
// direction the slices were sorted in). Slices ordered by InstanceNumber have none.
//
// Type: RescaleSlope/RescaleIntercept are applied. The store holds i16 when every slice's slope
// and intercept are integers and every stored value (per BitsStored) maps into i16, as CT's
// slope 1, intercept -1024 does; f32 otherwise. Without rescaling, the pixel type's own store
// type (sample_decode.h).
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "core/volume.h"
#include "io/error.h"
#include "io/readers/sample_decode.h"

namespace vdiso {

// What vdiso reads from one DICOM file's header.
struct DicomHeader {
    std::string path;
    std::string seriesUid, seriesDescription, modality, transferSyntax;
    uint32_t rows = 0, columns = 0;
    FileScalar pixelType = FileScalar::U16;
    int bitsStored = 16;
    std::optional<glm::dvec3> position;                // ImagePositionPatient
    std::optional<std::array<double, 6>> orientation;  // ImageOrientationPatient: row, column
    std::optional<std::array<double, 2>> pixelSpacing;  // PixelSpacing: row (y), column (x)
    std::optional<double> sliceSpacing;  // SpacingBetweenSlices, else SliceThickness
    std::optional<int64_t> instanceNumber;
    double slope = 1.0, intercept = 0.0;
    std::string problem;  // why vdiso cannot read this image ("" if it can), said if it is chosen
};

// One series, ordered and placed.
struct DicomVolume {
    std::vector<DicomHeader> slices;  // slice z is slices[z]
    VolumeInfo info;
    bool scaled = false;  // apply each slice's slope and intercept
};

// The headers of the series to read: all of them when they are one series; those of
// `seriesUid` when it is given. Throws IoError "<where>: ..." listing every series
// (SeriesInstanceUID, description, modality, slice count, columns x rows) when there are
// several and none is chosen (a DicomSeriesChoiceError) or the chosen one is not there.
// An input that holds several series, none of which was chosen: the message lists them, and
// front ends say how to choose in their own terms (--series UID, a keyword).
class DicomSeriesChoiceError : public IoError {
public:
    using IoError::IoError;
};

std::vector<DicomHeader> selectDicomSeries(std::vector<DicomHeader> headers,
                                           const std::string& seriesUid, const std::string& where);

// Orders one series' slices and derives its grid and store type (the rules above). Throws
// IoError "<where>: ..." naming the slices at fault, or if there are fewer than `minSlices`
// (2 for a volume; 1 to read a single image, as the fuzz target does).
DicomVolume arrangeDicomSeries(std::vector<DicomHeader> slices, const std::string& where,
                               size_t minSlices = 2);

}  // namespace vdiso
