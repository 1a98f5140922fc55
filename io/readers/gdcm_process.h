// GDCM in a helper process (io/readers/helper_process.h): every call into GDCM (headers, DICOMDIR
// records, pixel data) runs in a child process, so that GDCM failing on a file refuses that file
// and leaves vdiso running.
//
// Why: Debian builds GDCM with its assertions on, and they fire on damaged input. fuzz_dicom
// found aborts in gdcm::ReadExplicitDataElement (meta header), gdcm::BasicOffsetTable::Read
// (header parsing) and gdcm::JPEG16Codec::GetHeaderInfo (any libjpeg warning), each of which
// would have ended vdiso with its output half written. io/readers/dicom_structure.h refuses most damaged
// files before GDCM sees them; this catches what no check ahead can (codec internals).
//
// The child is forked at the first request and serves requests over a socket until the object
// goes; if it dies, the request fails with an IoError naming the file and how the child ended,
// and the next request starts a new child. Its data memory stays bounded (1 GiB more than at the
// fork), since GDCM allocates what a file's lengths claim. The cost: one fork, and one copy of
// each slice's samples through the socket. Not thread-safe: one reader, one process.
//
// GDCM itself is in a run-time module (io/readers/gdcm_module/gdcm_module.h), loaded at the first
// request; when it cannot be, the request fails with an IoError naming the file and the module.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "io/readers/dicom_series.h"
#include "io/readers/helper_process.h"

namespace vdiso {

class GdcmProcess {
public:
    GdcmProcess() = default;
    GdcmProcess(const GdcmProcess&) = delete;
    GdcmProcess& operator=(const GdcmProcess&) = delete;

    // The file's header fields (DicomHeader), up to the pixel data; nullopt when GDCM does not
    // read it as an image (no Rows/Columns: a DICOMDIR, a report). Throws IoError if the helper
    // dies on it.
    std::optional<DicomHeader> readHeader(const std::string& path);

    // The files a DICOMDIR's records name (ReferencedFileID), relative to its folder. Throws
    // IoError naming the DICOMDIR.
    std::vector<std::string> dicomdirFiles(const std::string& path);

    // Decodes the pixel data of `h`'s file into dst (rows * columns samples of h.pixelType, the
    // stored values, native byte order). Throws IoError naming the file: pixel data unlike its
    // header, a transfer syntax GDCM cannot decode, or GDCM dying on it.
    void decodePixels(const DicomHeader& h, void* dst);

private:
    // Sends one request; returns the reply's status (0 ok, 1 error, 2 none) and body, or throws
    // if the child died. A pixel reply's body goes to `dst` when given.
    int call(char kind, const std::string& path, const std::string& request, std::string& body,
             void* dst = nullptr, size_t dstBytes = 0);
    HelperProcess mHelper;
};

}  // namespace vdiso
