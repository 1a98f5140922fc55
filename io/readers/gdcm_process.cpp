#include "io/readers/gdcm_process.h"

#include <cstdint>
#include <string>

#include "io/readers/dicom_wire.h"
#include "io/error.h"
#include "io/readers/gdcm_module/gdcm_module.h"
#include "io/readers/helper_process.h"
#include "io/readers/run_time_module.h"

namespace vdiso {
namespace {

constexpr const char* kModuleName = "libvdiso_gdcm_module.so";

}  // namespace

int GdcmProcess::call(char kind, const std::string& path, const std::string& request,
                      std::string& body, void* dst, size_t dstBytes) {
    if (!mHelper.running()) {
        // Loaded here, in vdiso, once: each helper forked after inherits it rather than paying
        // GDCM's loading again. Only the helper calls into it.
        const auto serve = reinterpret_cast<decltype(&vdiso_gdcm_serve)>(
            runTimeModuleSymbol(kModuleName, "vdiso_gdcm_serve", path, "reading DICOM files"));
        mHelper.start(path, [serve](int socket) { serve(socket); });
    }
    const int fd = mHelper.socket();
    const uint64_t sizes[2] = {path.size(), request.size()};
    uint8_t status = 0;
    bool ok = sendAll(fd, &kind, 1) && sendAll(fd, sizes, sizeof(sizes)) &&
              sendAll(fd, path.data(), path.size()) && sendAll(fd, request.data(), request.size());
    if (ok && dst) {
        // Pixels arrive straight into dst: a status, a length that must be dstBytes, the samples.
        uint64_t size = 0;
        ok = receiveAll(fd, &status, 1) && receiveAll(fd, &size, sizeof(size));
        if (ok && status == 0) {
            if (size == dstBytes && receiveAll(fd, dst, dstBytes)) return 0;
            ok = false;
        } else if (ok) {
            ok = size < (uint64_t(1) << 20);
            body.resize(ok ? size_t(size) : 0);
            ok = ok && receiveAll(fd, body.data(), body.size());
        }
    } else if (ok) {
        ok = receiveReply(fd, status, body);
    }
    if (!ok)
        mHelper.died(path, "GDCM", "reading it", "the file is damaged or in a form GDCM cannot handle");
    if (status == 1) throwIoError(path, body);
    return status;
}

std::optional<DicomHeader> GdcmProcess::readHeader(const std::string& path) {
    std::string body;
    if (call('H', path, "", body) == 2) return std::nullopt;
    return getDicomHeader(body, path);
}

std::vector<std::string> GdcmProcess::dicomdirFiles(const std::string& path) {
    std::string body;
    call('D', path, "", body);
    WireReader r(body);
    uint64_t n = 0;
    r.get(n);
    std::vector<std::string> files;
    for (uint64_t i = 0; i < n; ++i) {
        std::string f;
        r.get(f);
        files.push_back(std::move(f));
    }
    return files;
}

void GdcmProcess::decodePixels(const DicomHeader& h, void* dst) {
    WireWriter w;
    putDicomHeader(w, h);
    std::string body;
    call('P', h.path, w.bytes(), body, dst, size_t(h.rows) * h.columns * fileScalarSize(h.pixelType));
}

}  // namespace vdiso
