#include "io/mesh_writer.h"

#include <cstdio>
#include <span>
#include <cstring>
#include <stdexcept>

#include <unistd.h>
#include <vector>

#include "io/atomic_output.h"
#include "io/error.h"
#include "io/file_names.h"

namespace vdiso {

namespace {

// Appends to a file through a 4 MiB buffer: a few large writes instead of millions of small.
class BufferedAppender {
public:
    explicit BufferedAppender(AtomicOutputFile& out) : mOut(out) { mBuffer.reserve(kSize); }
    void put(const void* data, size_t n) {
        if (mBuffer.size() + n > kSize) flush();
        const auto* p = static_cast<const unsigned char*>(data);
        mBuffer.insert(mBuffer.end(), p, p + n);
    }
    void put(const std::string& s) { put(s.data(), s.size()); }
    void flush() {
        mOut.append(mBuffer.data(), mBuffer.size());
        mBuffer.clear();
    }

private:
    static constexpr size_t kSize = 4u << 20;
    AtomicOutputFile& mOut;
    std::vector<unsigned char> mBuffer;
};

void putVertices(BufferedAppender& w, std::span<const glm::vec3> positions,
                 std::span<const glm::vec3> normals) {
    for (size_t i = 0; i < positions.size(); ++i) {
        float v[6] = {positions[i].x, positions[i].y, positions[i].z,
                      normals[i].x,   normals[i].y,   normals[i].z};
        w.put(v, sizeof v);
    }
}

const char* kVertexProperties =
    "property float x\nproperty float y\nproperty float z\n"
    "property float nx\nproperty float ny\nproperty float nz\n";

// The PLY header, padded by a comment line to a fixed length: the final header, written last
// over the placeholder, then has the placeholder's length whatever the counts' digits.
std::string plyHeader(uint64_t vertices, uint64_t triangles) {
    constexpr size_t kHeaderBytes = 512;
    const std::string head =
        "ply\nformat binary_little_endian 1.0\ncomment vdiso isosurface\nelement vertex " +
        std::to_string(vertices) + "\n" + kVertexProperties + "element face " +
        std::to_string(triangles) + "\nproperty list uchar uint vertex_indices\n";
    const std::string tail = "end_header\n";
    const size_t padding = kHeaderBytes - head.size() - tail.size() - std::strlen("comment \n");
    return head + "comment " + std::string(padding, '.') + "\n" + tail;
}

}  // namespace

MeshFormat meshFormatFor(const std::string& path) {
    if (endsWithIgnoreCase(path, ".ply")) return MeshFormat::Ply;
    if (endsWithIgnoreCase(path, ".obj")) return MeshFormat::Obj;
    throwIoError(path, "unknown mesh format (expected a .ply or .obj name)");
}

struct MeshFileWriter::Files {
    AtomicOutputFile out;    // header and vertices, then the faces appended by finish()
    AtomicOutputFile faces;  // a side file, never committed: removed with the object
    BufferedAppender vertexWriter{out}, faceWriter{faces};
    uint64_t headerBytes = 0;
    Files(const std::string& path, bool overwrite)
        : out(path, overwrite), faces(path + ".faces", true) {}
};

MeshFileWriter::MeshFileWriter(const std::string& path, bool overwrite)
    : mFiles(std::make_unique<Files>(path, overwrite)), mFormat(meshFormatFor(path)) {
    if (mFormat == MeshFormat::Ply) {
        const std::string header = plyHeader(0, 0);
        mFiles->vertexWriter.put(header);
        mFiles->headerBytes = header.size();
    } else {
        mFiles->vertexWriter.put(std::string("# vdiso isosurface\n"));
    }
}

MeshFileWriter::~MeshFileWriter() = default;

void MeshFileWriter::append(const TriangleMesh& part) {
    if (part.firstVertex != mVertices)
        throw std::logic_error("MeshFileWriter: pieces must arrive in vertex order");
    BufferedAppender& v = mFiles->vertexWriter;
    BufferedAppender& f = mFiles->faceWriter;
    if (mFormat == MeshFormat::Ply) {
        putVertices(v, part.positions, part.normals);
        for (size_t t = 0; t < part.triangleCount(); ++t) {
            unsigned char face[13];
            face[0] = 3;
            std::memcpy(face + 1, &part.indices[3 * t], 12);
            f.put(face, sizeof face);
        }
    } else {
        char line[160];
        for (size_t i = 0; i < part.positions.size(); ++i) {
            const glm::vec3 &p = part.positions[i], &n = part.normals[i];
            const int k = std::snprintf(line, sizeof line, "v %.7g %.7g %.7g\nvn %.5f %.5f %.5f\n",
                                        p.x, p.y, p.z, n.x, n.y, n.z);
            v.put(line, size_t(k));
        }
        for (size_t t = 0; t < part.triangleCount(); ++t) {
            // OBJ counts from 1; vertex i's normal is vn i, as they were written in pairs.
            const uint32_t a = part.indices[3 * t] + 1, b = part.indices[3 * t + 1] + 1,
                           c = part.indices[3 * t + 2] + 1;
            const int k = std::snprintf(line, sizeof line, "f %u//%u %u//%u %u//%u\n", a, a, b,
                                        b, c, c);
            f.put(line, size_t(k));
        }
    }
    mVertices += part.positions.size();
    mTriangles += part.triangleCount();
}

void MeshFileWriter::finish() {
    Files& files = *mFiles;
    files.vertexWriter.flush();
    files.faceWriter.flush();
    // Append the side file's faces to the output, a few MB at a time.
    std::vector<unsigned char> buffer(8u << 20);
    const int facesFd = files.faces.fd();
    for (uint64_t at = 0; at < files.faces.size();) {
        const ssize_t n = ::pread(facesFd, buffer.data(), buffer.size(), off_t(at));
        if (n <= 0) throwIoError(files.out.path(), "cannot read back the faces written");
        files.out.append(buffer.data(), size_t(n));
        at += uint64_t(n);
    }
    if (mFormat == MeshFormat::Ply) {
        const std::string header = plyHeader(mVertices, mTriangles);
        files.out.writeAt(header.data(), header.size(), 0);
    }
    files.out.commit();
    mFiles.reset();  // removes the side file now, not when the writer goes
}

void writeMesh(const std::string& path, const TriangleMesh& mesh, bool overwrite) {
    MeshFileWriter writer(path, overwrite);
    writer.append(mesh);
    writer.finish();
}

void writePointsPly(const std::string& path, const PointSet& points, bool overwrite) {
    AtomicOutputFile out(path, overwrite);
    BufferedAppender w(out);
    w.put("ply\nformat binary_little_endian 1.0\ncomment vdiso points\nelement vertex " +
          std::to_string(points.size()) + "\n" + kVertexProperties + "end_header\n");
    putVertices(w, points.positions, points.normals);
    w.flush();
    out.commit();
}

}  // namespace vdiso
