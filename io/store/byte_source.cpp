#include "io/store/byte_source.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdint>

#include "io/error.h"

namespace vdiso {

void ByteSource::readCoveringAsync(uint64_t offset, size_t n, void* dst, std::vector<ByteRange> pieces,
                                   const char* what, RangeCheck intact, const std::atomic<bool>*,
                                   ReadDone done, bool) const {
    try {
        readCovering(offset, n, dst, pieces, what, intact);
    } catch (...) {
        return done(std::current_exception());
    }
    done(nullptr);
}

namespace {

class LocalFileSource final : public ByteSource {
public:
    LocalFileSource(std::string path, ReadMode mode) : mPath(std::move(path)), mMode(mode) {
        mFd = ::open(mPath.c_str(), O_RDONLY | O_CLOEXEC);
        if (mFd < 0) throwSystemError(mPath, "cannot open", errno);
        const off_t end = ::lseek(mFd, 0, SEEK_END);
        if (end < 0) {
            const int e = errno;
            ::close(mFd);
            throwSystemError(mPath, "cannot seek", e);
        }
        mSize = uint64_t(end);
        if (mMode == ReadMode::Cold) {
            // Start cold: whatever of the file the page cache holds (from conversion, or an
            // earlier run) is dropped.
            ::posix_fadvise(mFd, 0, 0, POSIX_FADV_DONTNEED);
            mDirectFd = ::open(mPath.c_str(), O_RDONLY | O_CLOEXEC | O_DIRECT);
        }
    }
    ~LocalFileSource() override {
        ::close(mFd);
        if (mDirectFd >= 0) ::close(mDirectFd);
    }

    const std::string& name() const override { return mPath; }
    uint64_t size() const override { return mSize; }
    const char* method() const override {
        if (mMode == ReadMode::Buffered) return "buffered";
        return mDirectFd >= 0 ? "direct" : "fadvise";
    }
    uint64_t bytesRead() const override { return mBytesRead.load(std::memory_order_relaxed); }

    void read(uint64_t offset, size_t n, void* dst, const char* what, const RangeCheck& = {}) const override {
        auto* p = static_cast<char*>(dst);
        // O_DIRECT reads whole aligned blocks; the padding after a brick (or the index) fills
        // the last one, and the end of the file may cut it.
        const bool direct = mDirectFd >= 0 && offset % kByteSourceAlignment == 0 &&
                            reinterpret_cast<uintptr_t>(dst) % kByteSourceAlignment == 0;
        const size_t want = direct ? (n + kByteSourceAlignment - 1) / kByteSourceAlignment * kByteSourceAlignment : n;
        size_t done = 0;
        while (done < n) {
            const ssize_t r = ::pread(direct ? mDirectFd : mFd, p + done, want - done, off_t(offset + done));
            if (r < 0) {
                if (errno == EINTR) continue;
                throwSystemError(mPath, std::string("cannot read ") + what + " at byte offset " +
                                            std::to_string(offset + done), errno);
            }
            if (r == 0)
                throwIoError(mPath, std::string("ends inside the ") + what + " (byte offset " +
                                        std::to_string(offset + done) + "): the file is truncated");
            // (Counted as asked for: not the block padding an O_DIRECT read brings beyond n.)
            mBytesRead.fetch_add(std::min(uint64_t(r), uint64_t(n - done)), std::memory_order_relaxed);
            done += size_t(r);
        }
        if (mMode == ReadMode::Cold && !direct) ::posix_fadvise(mFd, off_t(offset), off_t(n), POSIX_FADV_DONTNEED);
    }

private:
    std::string mPath;
    ReadMode mMode;
    int mFd = -1;
    int mDirectFd = -1;  // O_DIRECT descriptor in cold mode, when the file system allows it
    uint64_t mSize = 0;
    mutable std::atomic<uint64_t> mBytesRead{0};
};

class RemoteSource final : public ByteSource {
public:
    RemoteSource(const std::string& location, const RemoteOptions& options, size_t headBytes)
        : mFile(location, options, headBytes) {}
    const std::string& name() const override { return mFile.name(); }
    uint64_t size() const override { return mFile.size(); }
    const char* method() const override { return mFile.scheme(); }
    uint64_t bytesRead() const override { return mFile.bytesFetched(); }
    const RemoteFile* remote() const override { return &mFile; }
    void read(uint64_t offset, size_t n, void* dst, const char*, const RangeCheck& intact) const override {
        mFile.read(offset, n, dst, intact);
    }
    void readCovering(uint64_t offset, size_t n, void* dst, std::span<const ByteRange> pieces, const char*,
                      const RangeCheck& intact) const override {
        mFile.readCovering(offset, n, dst, pieces, intact);
    }
    void readCoveringAsync(uint64_t offset, size_t n, void* dst, std::vector<ByteRange> pieces, const char*,
                           RangeCheck intact, const std::atomic<bool>* cancel, ReadDone done,
                           bool alone) const override {
        mFile.readCoveringAsync(offset, n, dst, std::move(pieces), std::move(intact), cancel, std::move(done), alone);
    }
    bool readsInBackground() const override { return true; }

private:
    RemoteFile mFile;
};

}  // namespace

std::unique_ptr<ByteSource> openByteSource(const std::string& location, ReadMode mode,
                                           const RemoteOptions& remote, size_t headBytes) {
    if (isRemoteLocation(location)) return std::make_unique<RemoteSource>(location, remote, headBytes);
    return std::make_unique<LocalFileSource>(location, mode);
}

}  // namespace vdiso
