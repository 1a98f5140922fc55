#include "bench/inputs/head_slices.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include "core/synth/synth.h"

namespace vdiso::bench {

HeadSlices::HeadSlices(const std::string& rawPath, int64_t synthSize) {
    if (rawPath.empty()) {
        mSize = synthSize;
        mName = "synth:head " + std::to_string(synthSize) + "^3";
        return;
    }
    mName = rawPath;
    mFd = ::open(rawPath.c_str(), O_RDONLY | O_CLOEXEC);
    if (mFd < 0) throw std::runtime_error(rawPath + ": cannot open: " + std::strerror(errno));
    const off_t bytes = ::lseek(mFd, 0, SEEK_END);
    const auto n = int64_t(std::llround(std::cbrt(double(bytes) / 2.0)));
    if (bytes <= 0 || 2 * n * n * n != int64_t(bytes)) {
        ::close(mFd);
        throw std::runtime_error(rawPath + ": " + std::to_string(bytes) +
                                 " bytes is not a cube of u16 samples (2 * N^3)");
    }
    mSize = n;
}

HeadSlices::~HeadSlices() {
    if (mFd >= 0) ::close(mFd);
}

void HeadSlices::read(int64_t z, int64_t count, uint16_t* dst) const {
    if (z < 0 || count < 0 || z + count > mSize)
        throw std::runtime_error(mName + ": slices " + std::to_string(z) + " + " +
                                 std::to_string(count) + " are outside the volume");
    if (mFd < 0) {
        SynthParams p;
        p.kind = SynthKind::Head;
        p.dims = {mSize, mSize, mSize};
        p.type = ScalarType::U16;
        synthesizeSlices(p, z, count, dst);
        return;
    }
    const size_t bytes = size_t(count * mSize * mSize) * 2;
    auto* out = reinterpret_cast<char*>(dst);
    const off_t offset = off_t(z * mSize * mSize) * 2;
    for (size_t done = 0; done < bytes;) {
        const ssize_t n = ::pread(mFd, out + done, bytes - done, offset + off_t(done));
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0)
            throw std::runtime_error(mName + ": cannot read slice " + std::to_string(z) + ": " +
                                     (n == 0 ? "unexpected end" : std::strerror(errno)));
        done += size_t(n);
    }
}

}  // namespace vdiso::bench
