#include "io/mesh_writer.h"

#include <cstdio>
#include <cstring>
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
    ~BufferedAppender() = default;
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

void putVertices(BufferedAppender& w, const std::vector<glm::vec3>& positions,
                 const std::vector<glm::vec3>& normals) {
    for (size_t i = 0; i < positions.size(); ++i) {
        float v[6] = {positions[i].x, positions[i].y, positions[i].z,
                      normals[i].x,   normals[i].y,   normals[i].z};
        w.put(v, sizeof v);
    }
}

const char* kVertexProperties =
    "property float x\nproperty float y\nproperty float z\n"
    "property float nx\nproperty float ny\nproperty float nz\n";

void writePly(const std::string& path, const TriangleMesh& mesh, bool overwrite) {
    AtomicOutputFile out(path, overwrite);
    BufferedAppender w(out);
    w.put("ply\nformat binary_little_endian 1.0\ncomment vdiso isosurface\nelement vertex " +
          std::to_string(mesh.vertexCount()) + "\n" + kVertexProperties + "element face " +
          std::to_string(mesh.triangleCount()) +
          "\nproperty list uchar uint vertex_indices\nend_header\n");
    putVertices(w, mesh.positions, mesh.normals);
    for (size_t t = 0; t < mesh.triangleCount(); ++t) {
        unsigned char face[13];
        face[0] = 3;
        std::memcpy(face + 1, &mesh.indices[3 * t], 12);
        w.put(face, sizeof face);
    }
    w.flush();
    out.commit();
}

void writeObj(const std::string& path, const TriangleMesh& mesh, bool overwrite) {
    AtomicOutputFile out(path, overwrite);
    BufferedAppender w(out);
    w.put("# vdiso isosurface\n");
    char line[128];
    for (const glm::vec3& p : mesh.positions) {
        const int n = std::snprintf(line, sizeof line, "v %.7g %.7g %.7g\n", p.x, p.y, p.z);
        w.put(line, size_t(n));
    }
    for (const glm::vec3& v : mesh.normals) {
        const int n = std::snprintf(line, sizeof line, "vn %.5f %.5f %.5f\n", v.x, v.y, v.z);
        w.put(line, size_t(n));
    }
    for (size_t t = 0; t < mesh.triangleCount(); ++t) {
        const uint32_t a = mesh.indices[3 * t] + 1, b = mesh.indices[3 * t + 1] + 1,
                       c = mesh.indices[3 * t + 2] + 1;
        const int n = std::snprintf(line, sizeof line, "f %u//%u %u//%u %u//%u\n", a, a, b, b, c, c);
        w.put(line, size_t(n));
    }
    w.flush();
    out.commit();
}

}  // namespace

MeshFormat meshFormatFor(const std::string& path) {
    if (endsWithIgnoreCase(path, ".ply")) return MeshFormat::Ply;
    if (endsWithIgnoreCase(path, ".obj")) return MeshFormat::Obj;
    throwIoError(path, "unknown mesh format (expected a .ply or .obj name)");
}

void writeMesh(const std::string& path, const TriangleMesh& mesh, bool overwrite) {
    if (meshFormatFor(path) == MeshFormat::Ply)
        writePly(path, mesh, overwrite);
    else
        writeObj(path, mesh, overwrite);
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
