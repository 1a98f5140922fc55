#include "io/mesh/mesh_writer.h"

#include <cstdio>
#include <cstring>
#include <span>
#include <stdexcept>

#include "io/atomic_output.h"
#include "io/error.h"
#include "io/readers/file_names.h"
#include "io/mesh/glb_writer.h"
#include "io/mesh/mesh_output.h"
#include "io/mesh/stl_writer.h"
#include "io/mesh/vtp_writer.h"

namespace vdiso {

namespace {

void encodePlyVertex(const glm::vec3& position, const glm::vec3& normal, unsigned char* record) {
    const float v[6] = {position.x, position.y, position.z, normal.x, normal.y, normal.z};
    std::memcpy(record, v, kPlyVertexBytes);
}

void encodePlyFace(const uint32_t* indices, unsigned char* record) {
    record[0] = 3;
    std::memcpy(record + 1, indices, 12);
}

void putVertices(BufferedAppender& w, std::span<const glm::vec3> positions,
                 std::span<const glm::vec3> normals) {
    for (size_t i = 0; i < positions.size(); ++i) {
        unsigned char record[kPlyVertexBytes];
        encodePlyVertex(positions[i], normals[i], record);
        w.put(record, sizeof record);
    }
}

const char* kVertexProperties =
    "property float x\nproperty float y\nproperty float z\n"
    "property float nx\nproperty float ny\nproperty float nz\n";

}  // namespace

// Padded by a comment line to a fixed length: the final header, written last over the
// placeholder, then has the placeholder's length whatever the counts' digits.
std::string plyMeshHeader(uint64_t vertices, uint64_t triangles) {
    const std::string head =
        "ply\nformat binary_little_endian 1.0\ncomment vdiso isosurface\nelement vertex " +
        std::to_string(vertices) + "\n" + kVertexProperties + "element face " +
        std::to_string(triangles) + "\nproperty list uchar uint vertex_indices\n";
    const std::string tail = "end_header\n";
    const size_t padding = kPlyHeaderBytes - head.size() - tail.size() - std::strlen("comment \n");
    return head + "comment " + std::string(padding, '.') + "\n" + tail;
}

std::vector<unsigned char> plyVertexRecords(const TriangleMesh& part) {
    std::vector<unsigned char> bytes(part.positions.size() * kPlyVertexBytes);
    for (size_t i = 0; i < part.positions.size(); ++i)
        encodePlyVertex(part.positions[i], part.normals[i], bytes.data() + i * kPlyVertexBytes);
    return bytes;
}

std::vector<unsigned char> plyFaceRecords(const TriangleMesh& part) {
    std::vector<unsigned char> bytes(part.triangleCount() * kPlyFaceBytes);
    for (size_t t = 0; t < part.triangleCount(); ++t) encodePlyFace(&part.indices[3 * t], bytes.data() + t * kPlyFaceBytes);
    return bytes;
}

namespace {

// PLY and OBJ: vertex records go to the output as they come, face records to a side file,
// appended by finish(), which then writes PLY's header with the final counts.
class PlyObjWriter final : public MeshFormatWriter {
public:
    PlyObjWriter(const std::string& path, bool overwrite, MeshFormat format)
        : mOut(path, overwrite), mFaces(path, ".faces"), mPly(format == MeshFormat::Ply) {
        mVertexWriter.put(mPly ? plyMeshHeader(0, 0) : std::string("# vdiso isosurface\n"));
    }

    void append(const TriangleMesh& part) override {
        if (mPly) {
            putVertices(mVertexWriter, part.positions, part.normals);
            for (size_t t = 0; t < part.triangleCount(); ++t) {
                unsigned char face[kPlyFaceBytes];
                encodePlyFace(&part.indices[3 * t], face);
                mFaces.put(face, sizeof face);
            }
        } else {
            char line[160];
            for (size_t i = 0; i < part.positions.size(); ++i) {
                const glm::vec3 &p = part.positions[i], &n = part.normals[i];
                const int k = std::snprintf(line, sizeof line, "v %.7g %.7g %.7g\nvn %.5f %.5f %.5f\n",
                                            p.x, p.y, p.z, n.x, n.y, n.z);
                mVertexWriter.put(line, size_t(k));
            }
            for (size_t t = 0; t < part.triangleCount(); ++t) {
                // OBJ counts from 1; vertex i's normal is vn i, as they were written in pairs.
                const uint32_t a = part.indices[3 * t] + 1, b = part.indices[3 * t + 1] + 1,
                               c = part.indices[3 * t + 2] + 1;
                const int k = std::snprintf(line, sizeof line, "f %u//%u %u//%u %u//%u\n", a, a,
                                            b, b, c, c);
                mFaces.put(line, size_t(k));
            }
        }
        mVertices += part.positions.size();
        mTriangles += part.triangleCount();
    }

    void finish() override {
        mFaces.copyTo(mVertexWriter);
        mVertexWriter.flush();
        if (mPly) {
            const std::string header = plyMeshHeader(mVertices, mTriangles);
            mOut.writeAt(header.data(), header.size(), 0);
        }
        mOut.commit();
    }

private:
    AtomicOutputFile mOut;  // header and vertices, then the faces appended by finish()
    BufferedAppender mVertexWriter{mOut};
    SideFile mFaces;
    bool mPly;
    uint64_t mVertices = 0, mTriangles = 0;
};

}  // namespace

MeshFormat meshFormatFor(const std::string& path) {
    if (endsWithIgnoreCase(path, ".ply")) return MeshFormat::Ply;
    if (endsWithIgnoreCase(path, ".obj")) return MeshFormat::Obj;
    if (endsWithIgnoreCase(path, ".stl")) return MeshFormat::Stl;
    if (endsWithIgnoreCase(path, ".glb")) return MeshFormat::Glb;
    if (endsWithIgnoreCase(path, ".vtp")) return MeshFormat::Vtp;
    throwIoError(path, "unknown mesh format (expected a .ply, .obj, .stl, .glb or .vtp name)");
}

MeshFileWriter::MeshFileWriter(const std::string& path, bool overwrite, bool compress,
                               const SpaceTransform& transform)
    : mTransform(transform) {
    const MeshFormat format = meshFormatFor(path);
    if (compress && format != MeshFormat::Glb)
        throwIoError(path, "mesh compression applies to .glb output only");
    switch (format) {
        case MeshFormat::Ply:
        case MeshFormat::Obj: mWriter = std::make_unique<PlyObjWriter>(path, overwrite, format); break;
        case MeshFormat::Stl: mWriter = makeStlWriter(path, overwrite); break;
        case MeshFormat::Glb: mWriter = makeGlbWriter(path, overwrite, compress); break;
        case MeshFormat::Vtp: mWriter = makeVtpWriter(path, overwrite); break;
    }
}

MeshFileWriter::~MeshFileWriter() = default;

void MeshFileWriter::append(const TriangleMesh& part) {
    if (part.firstVertex != mVertices)
        throw std::logic_error("MeshFileWriter: pieces must arrive in vertex order");
    if (mTransform.isIdentity()) {
        mWriter->append(part);
    } else {
        mTransformed = part;
        transformMesh(mTransform, mTransformed);
        mWriter->append(mTransformed);
    }
    mVertices += part.positions.size();
    mTriangles += part.triangleCount();
}

void MeshFileWriter::finish() {
    mWriter->finish();
    mWriter.reset();  // removes the side files now, not when the writer goes
}

void writeMesh(const std::string& path, const TriangleMesh& mesh, bool overwrite, bool compress,
               const SpaceTransform& transform) {
    MeshFileWriter writer(path, overwrite, compress, transform);
    writer.append(mesh);
    writer.finish();
}

void writePointsPly(const std::string& path, const PointSet& points, bool overwrite,
                    const SpaceTransform& transform) {
    if (!transform.isIdentity()) {
        PointSet mapped = points;
        transformPoints(transform, mapped);
        return writePointsPly(path, mapped, overwrite);
    }
    AtomicOutputFile out(path, overwrite);
    BufferedAppender w(out);
    w.put("ply\nformat binary_little_endian 1.0\ncomment vdiso points\nelement vertex " +
          std::to_string(points.size()) + "\n" + kVertexProperties + "end_header\n");
    putVertices(w, points.positions, points.normals);
    w.flush();
    out.commit();
}

}  // namespace vdiso
