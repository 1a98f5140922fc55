#include "io/mesh/vtp_writer.h"

#include <string>
#include <vector>

#include "io/error.h"
#include "io/mesh/mesh_output.h"

namespace vdiso {

namespace {

constexpr size_t kHeaderBytes = 1024;

std::string dataArray(const char* type, const char* name, int components, uint64_t offset) {
    return std::string("        <DataArray type=\"") + type + "\" Name=\"" + name +
           "\" NumberOfComponents=\"" + std::to_string(components) +
           "\" format=\"appended\" offset=\"" + std::to_string(offset) + "\"/>\n";
}

// The XML up to the appended data's '_', padded by a comment to kHeaderBytes whatever the
// numbers' digits. The appended arrays, each a UInt64 byte count then the bytes: points,
// normals, connectivity, offsets.
std::string vtpHeader(uint64_t vertices, uint64_t triangles) {
    const uint64_t normalsAt = 8 + 12 * vertices, connectivityAt = 2 * normalsAt;
    const uint64_t offsetsAt = connectivityAt + 8 + 24 * triangles;
    const std::string head = "<?xml version=\"1.0\"?>\n";
    const std::string body =
        "<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\" "
        "header_type=\"UInt64\">\n"
        "  <PolyData>\n"
        "    <Piece NumberOfPoints=\"" + std::to_string(vertices) +
        "\" NumberOfVerts=\"0\" NumberOfLines=\"0\" NumberOfStrips=\"0\" NumberOfPolys=\"" +
        std::to_string(triangles) + "\">\n"
        "      <PointData Normals=\"Normals\">\n" +
        dataArray("Float32", "Normals", 3, normalsAt) +
        "      </PointData>\n"
        "      <Points>\n" +
        dataArray("Float32", "Points", 3, 0) +
        "      </Points>\n"
        "      <Polys>\n" +
        dataArray("Int64", "connectivity", 1, connectivityAt) +
        dataArray("Int64", "offsets", 1, offsetsAt) +
        "      </Polys>\n"
        "    </Piece>\n"
        "  </PolyData>\n"
        "  <AppendedData encoding=\"raw\">\n"
        "   _";
    const std::string open = "<!-- vdiso isosurface ", close = " -->\n";
    const size_t padding = kHeaderBytes - head.size() - body.size() - open.size() - close.size();
    return head + open + std::string(padding, '.') + close + body;
}

class VtpWriter final : public MeshFormatWriter {
public:
    VtpWriter(const std::string& path, bool overwrite)
        : mOut(path, overwrite), mNormals(path, ".normals"), mConnectivity(path, ".connectivity") {
        mWriter.put(vtpHeader(0, 0));
        putRaw(mWriter, uint64_t(0));  // the points' byte count, written by finish()
    }

    void append(const TriangleMesh& part) override {
        mWriter.put(part.positions.data(), part.positions.size() * sizeof(glm::vec3));
        mNormals.put(part.normals.data(), part.normals.size() * sizeof(glm::vec3));
        mWide.assign(part.indices.begin(), part.indices.end());
        mConnectivity.put(mWide.data(), mWide.size() * sizeof(int64_t));
        mVertices += part.positions.size();
        mTriangles += part.triangleCount();
    }

    void finish() override {
        putRaw(mWriter, uint64_t(12 * mVertices));
        mNormals.copyTo(mWriter);
        putRaw(mWriter, uint64_t(24 * mTriangles));
        mConnectivity.copyTo(mWriter);
        putRaw(mWriter, uint64_t(8 * mTriangles));
        for (uint64_t t = 1; t <= mTriangles; ++t) putRaw(mWriter, int64_t(3 * t));
        mWriter.put("\n  </AppendedData>\n</VTKFile>\n");
        mWriter.flush();
        const std::string header = vtpHeader(mVertices, mTriangles);
        mOut.writeAt(header.data(), header.size(), 0);
        const uint64_t pointBytes = 12 * mVertices;
        mOut.writeAt(&pointBytes, sizeof pointBytes, header.size());
        mOut.commit();
    }

private:
    AtomicOutputFile mOut;  // header and points, then the rest appended by finish()
    BufferedAppender mWriter{mOut};
    SideFile mNormals, mConnectivity;
    std::vector<int64_t> mWide;  // a piece's indices as Int64
    uint64_t mVertices = 0, mTriangles = 0;
};

}  // namespace

std::unique_ptr<MeshFormatWriter> makeVtpWriter(const std::string& path, bool overwrite) {
    return std::make_unique<VtpWriter>(path, overwrite);
}

}  // namespace vdiso
