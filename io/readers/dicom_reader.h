// DICOM series through GDCM: a folder (searched with its subfolders), a DICOMDIR, one file (the
// series it belongs to, from its folder) or a list of files of one series.
//
// Files are DICOM Part 10 files (the DICM signature at byte 128); anything else in a folder, and
// DICOM files that are not images (DICOMDIR, reports), are passed over. Each file's element
// structure is checked before GDCM parses it (io/readers/dicom_structure.h says why). A
// folder holding several series is refused with a list of them unless `seriesUid` (--series)
// picks one. Order, spacing, gaps, rescaling and the store type follow io/readers/dicom_series.h; the
// orientation is not kept (see there).
//
// Pixels: single-channel (MONOCHROME1/2, values as stored) 8, 16 or 32-bit integers, one frame
// per file, in any transfer syntax this GDCM decodes (uncompressed, deflate, RLE, JPEG baseline
// and lossless, JPEG-LS, JPEG 2000); one it cannot is refused naming the syntax and the file.
// Colour, multi-frame (enhanced) files and 12-bit packed pixels are refused with a message
// saying so. Only headers are read at open; each slice is decoded as it is read, so memory is
// one slice whatever the series' length. GDCM runs in a helper process (io/readers/gdcm_process.h says
// why) with its diagnostics silenced: every problem is an IoError naming the file.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "io/readers/slice_reader.h"

namespace vdiso {

// `path`: a folder, a DICOMDIR file, or one DICOM file. Throws IoError on any problem.
std::unique_ptr<SliceReader> openDicomVolume(const std::string& path, const std::string& seriesUid);

// The given files, which must all be DICOM images (of one series, or `seriesUid` picks one).
std::unique_ptr<SliceReader> openDicomFiles(const std::vector<std::string>& files,
                                            const std::string& seriesUid);

// One DICOM image as a volume one slice deep (dims[2] == 1, which a store refuses): the file
// level of the reader, for the fuzz target and tests.
std::unique_ptr<SliceReader> openDicomImage(const std::string& path);

// True if the file has the DICM signature of a DICOM Part 10 file at byte 128.
bool hasDicomMagic(const std::string& path);

// True if the folder (or a subfolder, looking at a few dozen files) holds a DICOMDIR or a file
// with the DICM signature.
bool looksLikeDicomFolder(const std::string& dir);

}  // namespace vdiso
