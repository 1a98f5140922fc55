// An output file that appears under its final name only when complete.
//
// The file is written under a temporary name in the same directory; commit() renames it into
// place. If the object is destroyed without commit() (an exception, an interrupt), the
// temporary file is removed, so a failed write never leaves a half file nor touches an existing
// one. Without `overwrite`, an existing destination is refused up front and again at commit.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace vdiso {

class AtomicOutputFile {
public:
    // Creates the temporary file; throws IoError naming `path` if it cannot be written. Also
    // refuses, even with `overwrite`, to replace anything but a regular file (a device, a FIFO,
    // a directory; through a symbolic link too) or a file that is one of `inputs` under another
    // name (compared by device and inode: "./vol.nrrd", a link to it, a header's data file).
    AtomicOutputFile(std::string path, bool overwrite, const std::vector<std::string>& inputs = {});
    ~AtomicOutputFile();
    AtomicOutputFile(const AtomicOutputFile&) = delete;
    AtomicOutputFile& operator=(const AtomicOutputFile&) = delete;

    int fd() const { return mFd; }
    const std::string& path() const { return mPath; }

    // Writes all of `n` bytes at `offset` of the temporary file; throws on failure (disk full).
    void writeAt(const void* data, size_t n, uint64_t offset);
    // Appends at the current end (tracked by the object).
    void append(const void* data, size_t n);
    uint64_t size() const { return mSize; }

    // Starts writing [offset, offset + n) back to disk without waiting, so that commit()'s
    // flush has little left to do. A hint: failures surface at commit().
    void startWriteback(uint64_t offset, uint64_t n);

    // Flushes, closes and renames into place. Throws on failure, leaving no output.
    void commit();

private:
    std::string mPath, mTempPath;
    bool mOverwrite;
    int mFd = -1;
    uint64_t mSize = 0;
};

}  // namespace vdiso
