// Sequential byte input from a plain file or a gzip stream, for the volume readers.
//
// Readers pull samples slab by slab through this interface, so a gzip-compressed NRRD or NIfTI
// is decompressed as it streams and never held whole. Errors throw IoError naming the file.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

namespace vdiso {

class ByteStream {
public:
    virtual ~ByteStream() = default;
    // Reads up to n bytes; returns how many were read (less than n only at the end of input).
    virtual size_t read(void* dst, size_t n) = 0;
    // Discards n bytes; throws if the input ends first. A plain file seeks; a gzip stream
    // decompresses what it discards.
    virtual void skip(uint64_t n);
    // Reads exactly n bytes or throws "<path>: ends after N bytes of <what>".
    void readExact(void* dst, size_t n, const char* what);
    // True when no byte is left.
    bool atEnd();
    const std::string& path() const { return mPath; }

protected:
    explicit ByteStream(std::string path) : mPath(std::move(path)) {}
    std::string mPath;
};

// Opens `path` as raw bytes starting at `offset`. Throws if it cannot be opened.
std::unique_ptr<ByteStream> openFileStream(const std::string& path, uint64_t offset = 0);

// Opens `path` as a gzip (or zlib) stream; `offset` is where the compressed stream starts.
// Corrupt compressed data throws "<path>: corrupt gzip data: ..." on the read that meets it.
std::unique_ptr<ByteStream> openGzipStream(const std::string& path, uint64_t offset = 0);

// Size of the file at `path` in bytes; throws if it cannot be stat'ed.
uint64_t fileSize(const std::string& path);

// True if the file starts with the gzip magic bytes 1f 8b.
bool hasGzipMagic(const std::string& path, uint64_t offset = 0);

}  // namespace vdiso
