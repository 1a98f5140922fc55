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

#include <cstdint>
#include <string>

namespace vdiso {

// Deflated explicit VR little endian: the data set after the meta header is a zlib stream.
inline constexpr const char* kDeflatedTransferSyntax = "1.2.840.10008.1.2.1.99";

struct DicomStructure {
    std::string transferSyntax;  // from the meta header (0002,0010)
    bool hasPixelData = false;   // (7FE0,0010) is there (always false for a deflated data set)
    // The top-level pixel data as the walk found it (with `throughPixelData`): native, its
    // value's length in bytes; encapsulated, the fragments after the basic offset table (their
    // count and bytes) and the table's length.
    bool encapsulated = false;
    uint64_t pixelBytes = 0;
    uint64_t fragments = 0;
    uint64_t offsetTableBytes = 0;
    uint64_t firstFragmentOffset = 0, firstFragmentBytes = 0;  // encapsulated: where it is
};

// The bytes native pixel data must hold: Rows x Columns x SamplesPerPixel x BitsAllocated / 8
// x NumberOfFrames (Part 5, 8.1.1); 0 when a factor is out of range.
uint64_t nativePixelBytes(uint64_t rows, uint64_t columns, uint64_t samplesPerPixel,
                          uint64_t bitsAllocated, uint64_t frames);

// Walks the file up to the pixel data (7FE0,0010) or, with `throughPixelData`, to its end.
// Throws IoError "<path>: ..." saying where (byte offset, tag) the structure breaks.
DicomStructure checkDicomStructure(const std::string& path, bool throughPixelData);

}  // namespace vdiso
