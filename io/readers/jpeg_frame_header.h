// The frame header (SOFn, or SOF55 for JPEG-LS) of a JPEG stream: what a decoder will make of
// it, read without decoding. A DICOM file's JPEG pixel data is checked against its header with
// it before GDCM decodes it (GDCM's JPEG codec crashes on a frame of 250-bit samples).
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>

namespace vdiso {

struct JpegFrameHeader {
    int precision = 0;     // bits per sample
    uint32_t lines = 0;    // 0: given later by a DNL marker
    uint32_t columns = 0;  // samples per line
    int components = 0;
};

// The first frame header in `bytes` (which start with SOI); nullopt when there is no SOI, or
// no frame header before the bytes end or the first scan starts.
std::optional<JpegFrameHeader> readJpegFrameHeader(const unsigned char* bytes, size_t n);

}  // namespace vdiso
