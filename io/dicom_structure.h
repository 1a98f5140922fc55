// A check of a DICOM file's element structure, made before GDCM parses it.
//
// Debian builds GDCM with its assertions on, and some of them fire on malformed input (a file
// cut inside its meta header aborts the process in gdcm::Reader). So every file is first walked
// here: the 128-byte preamble and DICM signature, the meta header, then every data element's
// tag and length (explicit or implicit VR, either byte order), sequences and items of defined or
// undefined length, and encapsulated pixel data fragments, each within the bytes that contain
// it, nesting at most 64 deep. Only element headers are read; values are skipped by seeking.
// A deflated data set (transfer syntax 1.2.840.10008.1.2.1.99) is checked up to its meta header.
// Files without the DICM signature (pre-Part-10) are refused here.
#pragma once

#include <string>

namespace vdiso {

struct DicomStructure {
    std::string transferSyntax;  // from the meta header (0002,0010)
    bool hasPixelData = false;   // (7FE0,0010) is there (always false for a deflated data set)
};

// Walks the file up to the pixel data (7FE0,0010) or, with `throughPixelData`, to its end.
// Throws IoError "<path>: ..." saying where (byte offset, tag) the structure breaks.
DicomStructure checkDicomStructure(const std::string& path, bool throughPixelData);

}  // namespace vdiso
