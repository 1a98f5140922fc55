#include "io/readers/byte_stream.h"

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <vector>

#include <sys/stat.h>
#include <zlib.h>

#include "core/interrupt.h"
#include "io/error.h"

namespace vdiso {

void ByteStream::skip(uint64_t n) {
    std::vector<char> scratch(1 << 16);
    while (n > 0) {
        size_t chunk = size_t(std::min<uint64_t>(n, scratch.size()));
        throwIfInterrupted(mPath);  // a skip of many GB, or over an endless stream
        size_t got = read(scratch.data(), chunk);
        if (got == 0) throwIoError(mPath, "ends before the data it declares");
        n -= got;
    }
}

void ByteStream::readExact(void* dst, size_t n, const char* what) {
    size_t got = 0;
    while (got < n) {
        throwIfInterrupted(mPath);
        // At most 16 MiB a read, so that a large slab still yields to an interrupt.
        size_t r = read(static_cast<char*>(dst) + got, std::min<size_t>(n - got, size_t(16) << 20));
        if (r == 0)
            throwIoError(mPath, "ends after " + std::to_string(got) + " of " + std::to_string(n) +
                                    " bytes of " + what);
        got += r;
    }
}

bool ByteStream::atEnd() {
    char c;
    return read(&c, 1) == 0;
}

namespace {

class FileStream final : public ByteStream {
public:
    FileStream(const std::string& path, uint64_t offset) : ByteStream(path) {
        mFile = std::fopen(path.c_str(), "rb");
        if (!mFile) throwSystemError(path, "cannot open", errno);
        if (offset && fseeko(mFile, off_t(offset), SEEK_SET) != 0)
            throwSystemError(path, "cannot seek to byte " + std::to_string(offset), errno);
    }
    ~FileStream() override { std::fclose(mFile); }
    size_t read(void* dst, size_t n) override {
        size_t got = std::fread(dst, 1, n, mFile);
        if (got < n && std::ferror(mFile)) throwSystemError(mPath, "read failed", errno);
        return got;
    }
    // A seek, refused (as the reading skip would fail) where it would pass the file's end.
    void skip(uint64_t n) override {
        struct stat st;
        const off_t at = ftello(mFile);
        if (at < 0 || ::fstat(fileno(mFile), &st) != 0) throwSystemError(mPath, "cannot seek", errno);
        if (n > uint64_t(st.st_size) - std::min<uint64_t>(uint64_t(at), uint64_t(st.st_size)))
            throwIoError(mPath, "ends before the data it declares");
        if (fseeko(mFile, off_t(n), SEEK_CUR) != 0)
            throwSystemError(mPath, "cannot skip " + std::to_string(n) + " bytes", errno);
    }

private:
    FILE* mFile = nullptr;
};

class GzipStream final : public ByteStream {
public:
    GzipStream(const std::string& path, uint64_t offset) : ByteStream(path), mFile(path, offset) {
        std::memset(&mZ, 0, sizeof mZ);
        // 15 + 32: accept both gzip and zlib headers, as NRRD writers use either.
        if (inflateInit2(&mZ, 15 + 32) != Z_OK) throwIoError(path, "cannot start zlib");
        mIn.resize(1 << 18);
    }
    ~GzipStream() override { inflateEnd(&mZ); }
    size_t read(void* dst, size_t n) override {
        mZ.next_out = static_cast<Bytef*>(dst);
        size_t done = 0;
        while (done < n && !mEnded) {
            if (mZ.avail_in == 0) {
                size_t got = mFile.read(mIn.data(), mIn.size());
                if (got == 0) throwIoError(mPath, "corrupt gzip data: stream is truncated");
                mZ.next_in = reinterpret_cast<Bytef*>(mIn.data());
                mZ.avail_in = uInt(got);
            }
            size_t want = std::min<size_t>(n - done, 1u << 30);
            mZ.avail_out = uInt(want);
            int rc = inflate(&mZ, Z_NO_FLUSH);
            done += want - mZ.avail_out;
            if (rc == Z_STREAM_END) {
                // A gzip file may hold several members back to back (gzip's own rule).
                if (mZ.avail_in == 0) {
                    size_t got = mFile.read(mIn.data(), mIn.size());
                    mZ.next_in = reinterpret_cast<Bytef*>(mIn.data());
                    mZ.avail_in = uInt(got);
                }
                if (mZ.avail_in == 0 || mZ.next_in[0] != 0x1f) {
                    mEnded = true;
                } else if (inflateReset(&mZ) != Z_OK) {
                    throwIoError(mPath, "corrupt gzip data");
                }
            } else if (rc != Z_OK && rc != Z_BUF_ERROR) {
                throwIoError(mPath, std::string("corrupt gzip data: ") +
                                        (mZ.msg ? mZ.msg : "inflate failed"));
            }
        }
        return done;
    }

private:
    FileStream mFile;
    z_stream mZ;
    std::vector<char> mIn;
    bool mEnded = false;
};

}  // namespace

std::unique_ptr<ByteStream> openFileStream(const std::string& path, uint64_t offset) {
    return std::make_unique<FileStream>(path, offset);
}

std::unique_ptr<ByteStream> openGzipStream(const std::string& path, uint64_t offset) {
    return std::make_unique<GzipStream>(path, offset);
}

uint64_t fileSize(const std::string& path) {
    struct stat st;
    if (::stat(path.c_str(), &st) != 0) throwSystemError(path, "cannot open", errno);
    if (S_ISDIR(st.st_mode)) throwIoError(path, "is a directory, not a file");
    return uint64_t(st.st_size);
}

bool hasGzipMagic(const std::string& path, uint64_t offset) {
    unsigned char magic[2] = {0, 0};
    FileStream f(path, offset);
    return f.read(magic, 2) == 2 && magic[0] == 0x1f && magic[1] == 0x8b;
}

}  // namespace vdiso
