// An output file that appears under its final name only when complete.
//
// The file is written unnamed (O_TMPFILE) in the output's directory, and commit() links it
// into place (with `overwrite`, under a temporary name renamed over the old file). If the
// process dies before that, even by SIGKILL or the OOM killer, nothing is left behind: the file
// system frees an unnamed file with its last descriptor. On file systems without O_TMPFILE the
// file is written under a temporary name (OUTPUT.partial.<pid>.<n>) and renamed into place;
// there, only an exception or an interrupt removes it, and a killed process leaves it.
// A failed write never leaves a half file nor touches an existing one. Without `overwrite`, an
// existing destination is refused up front and again at commit.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "io/error.h"

namespace vdiso {

// Writes all of `n` bytes at `offset` of the file open as `fd`; throws IoError naming `path` on
// failure (disk full). The one write loop of AtomicOutputFile and of writers that share a file.
void writeAllAt(int fd, const void* data, size_t n, uint64_t offset, const std::string& path);

// Starts writing [offset, offset + n) of `fd` back to disk without waiting (sync_file_range):
// a hint, whose failures surface at the flush.
void startWriteback(int fd, uint64_t offset, uint64_t n);

// Whether an output may be written at `path`: throws IoError naming it if something is there
// and `overwrite` is false, or (even with `overwrite`) if it is not a regular file (a device, a
// FIFO, a directory; through a symbolic link too) or is one of `inputs` under another name
// (compared by device and inode). Nothing there passes.
void checkOutputReplaceable(const std::string& path, bool overwrite, const std::vector<std::string>& inputs);

// Something stands at an output path and replacing it was not asked for. Front ends name their
// own way to ask (--force, a keyword).
class OutputExistsError : public IoError {
public:
    using IoError::IoError;
};

class AtomicOutputFile {
public:
    // Creates the temporary file; throws IoError naming `path` if it cannot be written. Also
    // refuses, even with `overwrite`, to replace anything but a regular file (a device, a FIFO,
    // a directory; through a symbolic link too) or a file that is one of `inputs` under another
    // name (compared by device and inode: "./vol.nrrd", a link to it, a header's data file).
    AtomicOutputFile(std::string path, bool overwrite, const std::vector<std::string>& inputs = {});
    // A resumable output (vdiso index): written under `partialPath`, which outlives a failure,
    // an interrupt or a kill so that a later run can go on with it. With `resume` the partial
    // file there is opened as it is (its bytes are the interrupted run's) and kept on failure;
    // else it is created empty and removed on a failure unless keepOnFailure() was called (a
    // checkpoint names it). commit() renames it into place; `path` is checked as above, up front
    // and at commit.
    AtomicOutputFile(std::string path, bool overwrite, const std::vector<std::string>& inputs,
                     std::string partialPath, bool resume);
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

    // A resumable output's partial file stays if this object goes without commit().
    void keepOnFailure() { mKeepPartial = true; }

    // Cuts the file to `size` bytes (a resumed output, back to its checkpoint's end).
    void truncate(uint64_t size);
    // Makes what was written so far durable (fdatasync): a resumable output's checkpoint.
    void flush();

    // Flushes, closes and renames into place. Throws on failure, leaving no output.
    void commit();

private:
    std::string temporaryName() const;

    std::string mPath;
    std::string mTempPath;  // empty while the file is unnamed (O_TMPFILE)
    bool mOverwrite;
    bool mKeepPartial = false;  // a resumable output's partial file stays after a failure
    int mFd = -1;
    uint64_t mSize = 0;
};

}  // namespace vdiso
