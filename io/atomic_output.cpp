#include "io/atomic_output.h"

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstdio>
#include <filesystem>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include "io/error.h"

namespace vdiso {

// What may stand at an output path: nothing, or a regular file (directly or through links) that is
// none of the inputs. Throws otherwise.
void checkOutputReplaceable(const std::string& path, bool overwrite, const std::vector<std::string>& inputs) {
    struct stat link;
    if (::lstat(path.c_str(), &link) != 0) return;  // nothing there (or a dangling path)
    if (!overwrite) throw OutputExistsError(path + ": already exists");
    struct stat target;
    const bool resolved = ::stat(path.c_str(), &target) == 0;
    if (!S_ISREG(link.st_mode) && !(S_ISLNK(link.st_mode) && (!resolved || S_ISREG(target.st_mode))))
        throwIoError(path, "is not a regular file (a device, FIFO, socket or directory); vdiso "
                           "replaces only regular files, even when asked to replace one");
    if (!resolved) return;
    for (const std::string& input : inputs) {
        struct stat in;
        if (::stat(input.c_str(), &in) == 0 && in.st_dev == target.st_dev && in.st_ino == target.st_ino)
            throwIoError(path, "is the input " + input + " under another name; not replaced");
    }
}

void writeAllAt(int fd, const void* data, size_t n, uint64_t offset, const std::string& path) {
    const char* p = static_cast<const char*>(data);
    while (n > 0) {
        ssize_t w = ::pwrite(fd, p, n, off_t(offset));
        if (w < 0) {
            if (errno == EINTR) continue;
            throwSystemError(path, "write failed", errno);
        }
        p += w;
        n -= size_t(w);
        offset += uint64_t(w);
    }
}

void startWriteback(int fd, uint64_t offset, uint64_t n) {
    ::sync_file_range(fd, off_t(offset), off_t(n), SYNC_FILE_RANGE_WRITE);
}

AtomicOutputFile::AtomicOutputFile(std::string path, bool overwrite,
                                   const std::vector<std::string>& inputs)
    : mPath(std::move(path)), mOverwrite(overwrite) {
    checkOutputReplaceable(mPath, mOverwrite, inputs);
    // An unnamed file in the output's directory: nothing to leave behind if the process dies
    // (SIGKILL, the OOM killer), since the file system frees it with its last descriptor.
    const std::string directory = std::filesystem::path(mPath).parent_path().string();
    mFd = ::open(directory.empty() ? "." : directory.c_str(), O_TMPFILE | O_RDWR | O_CLOEXEC, 0644);
    if (mFd >= 0) return;
    if (errno != EOPNOTSUPP && errno != EISDIR && errno != EINVAL)
        throwSystemError(mPath, "cannot write", errno);
    // File systems without O_TMPFILE: a named temporary, removed on any failure we live through.
    // (A name a killed process left, its id now ours, is passed over for the next.)
    for (int attempt = 0; mFd < 0 && attempt < 100; ++attempt) {
        mTempPath = temporaryName();
        mFd = ::open(mTempPath.c_str(), O_RDWR | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
        if (mFd < 0 && errno != EEXIST) break;
    }
    if (mFd < 0) {
        const int error = errno;
        mTempPath.clear();  // not ours: never unlinked
        throwSystemError(mPath, "cannot write", error);
    }
}

AtomicOutputFile::AtomicOutputFile(std::string path, bool overwrite, const std::vector<std::string>& inputs,
                                   std::string partialPath, bool resume)
    : mPath(std::move(path)), mTempPath(std::move(partialPath)), mOverwrite(overwrite), mKeepPartial(resume) {
    checkOutputReplaceable(mPath, mOverwrite, inputs);
    checkOutputReplaceable(mTempPath, true, inputs);  // a regular file, if anything
    mFd = ::open(mTempPath.c_str(), O_RDWR | O_CREAT | O_CLOEXEC | (resume ? 0 : O_TRUNC), 0644);
    if (mFd < 0) {
        const int error = errno;
        const std::string partial = mTempPath;
        mTempPath.clear();
        throwSystemError(partial, "cannot write", error);
    }
    struct stat st;
    if (::fstat(mFd, &st) == 0) mSize = uint64_t(st.st_size);
}

std::string AtomicOutputFile::temporaryName() const {
    // Unique per process and per object: two writers of one path never share a temporary.
    static std::atomic<unsigned> counter{0};
    return mPath + ".partial." + std::to_string(::getpid()) + "." + std::to_string(counter++);
}

AtomicOutputFile::~AtomicOutputFile() {
    if (mFd >= 0) ::close(mFd);
    if (!mTempPath.empty() && !mKeepPartial) ::unlink(mTempPath.c_str());
}

void AtomicOutputFile::truncate(uint64_t size) {
    if (::ftruncate(mFd, off_t(size)) != 0) throwSystemError(mTempPath.empty() ? mPath : mTempPath, "cannot truncate", errno);
    mSize = size;
}

void AtomicOutputFile::flush() {
    if (::fdatasync(mFd) != 0) throwSystemError(mTempPath.empty() ? mPath : mTempPath, "cannot flush", errno);
}

void AtomicOutputFile::writeAt(const void* data, size_t n, uint64_t offset) {
    writeAllAt(mFd, data, n, offset, mPath);
    mSize = std::max(mSize, offset + n);
}

void AtomicOutputFile::append(const void* data, size_t n) { writeAt(data, n, mSize); }

void AtomicOutputFile::startWriteback(uint64_t offset, uint64_t n) { vdiso::startWriteback(mFd, offset, n); }

void AtomicOutputFile::commit() {
    if (::fsync(mFd) != 0) throwSystemError(mPath, "cannot flush", errno);
    if (mTempPath.empty()) {
        // The unnamed file gets its name. Without overwrite, linkat itself refuses an existing
        // file; with it, the file is linked under a temporary name and renamed over the old one
        // (the temporary exists for the moment between the two calls only).
        const std::string self = "/proc/self/fd/" + std::to_string(mFd);
        const std::string name = mOverwrite ? temporaryName() : mPath;
        if (::linkat(AT_FDCWD, self.c_str(), AT_FDCWD, name.c_str(), AT_SYMLINK_FOLLOW) != 0) {
            if (errno == EEXIST && !mOverwrite)
                throwIoError(mPath, "appeared while it was being written; not replaced");
            throwSystemError(mPath, "cannot give the finished file its name", errno);
        }
        if (mOverwrite && ::rename(name.c_str(), mPath.c_str()) != 0) {
            const int error = errno;
            ::unlink(name.c_str());
            throwSystemError(mPath, "cannot rename the finished file into place", error);
        }
        const int fd = mFd;
        mFd = -1;
        if (::close(fd) != 0) throwSystemError(mPath, "cannot close", errno);
        return;
    }
    int fd = mFd;
    mFd = -1;
    if (::close(fd) != 0) throwSystemError(mPath, "cannot close", errno);
    // Without overwrite, the rename itself refuses an existing file: no window between a
    // check and the rename in which another writer's file could be replaced.
    const unsigned flags = mOverwrite ? 0 : RENAME_NOREPLACE;
    if (::renameat2(AT_FDCWD, mTempPath.c_str(), AT_FDCWD, mPath.c_str(), flags) != 0) {
        if (errno == EEXIST) throwIoError(mPath, "appeared while it was being written; not replaced");
        throwSystemError(mPath, "cannot rename the finished file into place", errno);
    }
    mTempPath.clear();
}

}  // namespace vdiso
