#include "io/mesh/mesh_output.h"

#include <algorithm>
#include <memory>

#include <unistd.h>

#include "io/error.h"

namespace vdiso {

SideFile::SideFile(const std::string& outputPath, const char* suffix)
    : mFile(outputPath + suffix, true), mOutputPath(outputPath) {}

void SideFile::read(void* data, size_t n, uint64_t offset) {
    if (offset + n > mFile.size()) mWriter.flush();
    auto* p = static_cast<unsigned char*>(data);
    while (n > 0) {
        const ssize_t got = ::pread(mFile.fd(), p, n, off_t(offset));
        if (got <= 0) throwIoError(mOutputPath, "cannot read back what was written beside it");
        p += got;
        n -= size_t(got);
        offset += uint64_t(got);
    }
}

std::vector<unsigned char> SideFile::readAll() {
    std::vector<unsigned char> all(size());
    read(all.data(), all.size(), 0);
    return all;
}

void SideFile::copyTo(BufferedAppender& out) {
    mWriter.flush();
    // As large as the file up to 8 MiB, and not zeroed: a small mesh's faces made a whole 8 MiB
    // buffer be cleared and faulted in (a sixth of the process time of a CT closeup's mesh).
    const size_t size = size_t(std::min<uint64_t>(mFile.size(), 8u << 20));
    const std::unique_ptr<unsigned char[]> buffer(new unsigned char[std::max<size_t>(size, 1)]);
    for (uint64_t at = 0; at < mFile.size();) {
        const size_t n = size_t(std::min<uint64_t>(size, mFile.size() - at));
        read(buffer.get(), n, at);
        out.put(buffer.get(), n);
        at += n;
    }
}

}  // namespace vdiso
