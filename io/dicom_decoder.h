// Decoding DICOM pixel data with GDCM in a helper process.
//
// Debian builds GDCM with its assertions on, and its codecs assert on damaged compressed data
// (gdcm::JPEG16Codec::GetHeaderInfo aborts on any libjpeg warning, found by fuzz_dicom), which
// would end vdiso itself, output half written. So pixel data is decoded in a child process,
// forked at the first slice: a request names the file, the child decodes it and sends the
// samples back over a socket. If the child dies, the slice is refused by name and the
// conversion fails cleanly; vdiso goes on. The cost is one fork per reader and one copy of each
// slice's samples.
#pragma once

#include <sys/types.h>

#include <cstddef>
#include <cstdint>
#include <string>

namespace vdiso {

// What the header says the pixel data must be.
struct DicomPixelRequest {
    std::string path;
    std::string transferSyntax;  // for messages
    uint32_t rows = 0, columns = 0;
    uint32_t bitsAllocated = 16;
};

class DicomPixelDecoder {
public:
    DicomPixelDecoder() = default;
    ~DicomPixelDecoder();
    DicomPixelDecoder(const DicomPixelDecoder&) = delete;
    DicomPixelDecoder& operator=(const DicomPixelDecoder&) = delete;

    // Decodes the file's pixel data into dst (rows * columns * bitsAllocated / 8 bytes, the
    // stored values in native byte order). Throws IoError naming the file: pixel data that does
    // not match the request, a transfer syntax GDCM cannot decode, or a decoder that died.
    // Not thread-safe (one reader, one decoder).
    void decode(const DicomPixelRequest& request, void* dst);

private:
    void start();
    void stop();
    int mSocket = -1;
    pid_t mChild = -1;
};

}  // namespace vdiso
