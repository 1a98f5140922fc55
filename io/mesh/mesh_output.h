// What the mesh writers (io/mesh/mesh_writer.h) are built from: buffered appending to an output,
// side files that hold a part of the output until finish() copies it in, and the interface
// each format implements. Not for use outside the writers.
//
// A side file is written beside the output (unnamed, O_TMPFILE, where the file system allows;
// else OUTPUT<suffix>.partial.*) and never committed: it goes with its object, whatever happens.
#pragma once

#include <bit>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "core/mesh.h"
#include "io/atomic_output.h"

namespace vdiso {

// Appends to a file through a 4 MiB buffer: a few large writes instead of millions of small.
class BufferedAppender {
public:
    explicit BufferedAppender(AtomicOutputFile& out) : mOut(out) { mBuffer.reserve(kSize); }
    void put(const void* data, size_t n) {
        if (mBuffer.size() + n > kSize) flush();
        if (n >= kSize) return mOut.append(data, n);  // large: straight through
        const auto* p = static_cast<const unsigned char*>(data);
        mBuffer.insert(mBuffer.end(), p, p + n);
    }
    void put(const std::string& s) { put(s.data(), s.size()); }
    void flush() {
        mOut.append(mBuffer.data(), mBuffer.size());
        mBuffer.clear();
    }
    // Bytes appended so far, buffered ones included.
    uint64_t size() const { return mOut.size() + mBuffer.size(); }

private:
    static constexpr size_t kSize = 4u << 20;
    AtomicOutputFile& mOut;
    std::vector<unsigned char> mBuffer;
};

class SideFile {
public:
    // `outputPath` + `suffix` names it where it needs a name; errors name the output.
    SideFile(const std::string& outputPath, const char* suffix);
    void put(const void* data, size_t n) { mWriter.put(data, n); }
    uint64_t size() const { return mWriter.size(); }
    // Reads `n` bytes at `offset` back (what was put, buffered or not).
    void read(void* data, size_t n, uint64_t offset);
    // Everything put, in memory.
    std::vector<unsigned char> readAll();
    // Appends everything put to `out`, a few MB at a time.
    void copyTo(BufferedAppender& out);

private:
    AtomicOutputFile mFile;
    BufferedAppender mWriter{mFile};
    std::string mOutputPath;
};

// One format's writer, behind MeshFileWriter (which checks the pieces' order and counts).
class MeshFormatWriter {
public:
    virtual ~MeshFormatWriter() = default;
    // `part` holds the vertices numbered part.firstVertex (== all appended before) onwards.
    virtual void append(const TriangleMesh& part) = 0;
    // Completes the file and renames it into place; called once, last.
    virtual void finish() = 0;
};

// The formats' numbers are little-endian: written as the host holds them.
static_assert(std::endian::native == std::endian::little, "the mesh writers assume little-endian");

// Appends one number (or a struct of them) as it is in memory.
template <class T>
void putRaw(BufferedAppender& out, const T& value) {
    out.put(&value, sizeof value);
}

}  // namespace vdiso
