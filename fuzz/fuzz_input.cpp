#include "fuzz/fuzz_input.h"

#include <stdexcept>

#include <sys/mman.h>
#include <unistd.h>

namespace vdiso::fuzz {

MemoryFile::MemoryFile(const uint8_t* data, size_t size) {
    mFd = ::memfd_create("fuzz-input", 0);
    if (mFd < 0) throw std::runtime_error("memfd_create failed");
    for (size_t done = 0; done < size;) {
        const ssize_t n = ::write(mFd, data + done, size - done);
        if (n <= 0) throw std::runtime_error("writing the memfd failed");
        done += size_t(n);
    }
    mPath = "/proc/self/fd/" + std::to_string(mFd);
}

MemoryFile::~MemoryFile() {
    if (mFd >= 0) ::close(mFd);
}

}  // namespace vdiso::fuzz
