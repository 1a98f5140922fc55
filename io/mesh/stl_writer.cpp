#include "io/mesh/stl_writer.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

#include <glm/geometric.hpp>

#include "io/error.h"
#include "io/mesh/mesh_output.h"

namespace vdiso {

namespace {

constexpr size_t kTextBytes = 80;

// A vertex as the side file keeps it.
struct VertexRecord {
    glm::vec3 position, normal;
};
static_assert(sizeof(VertexRecord) == 24);

// The unit normal of triangle (a, b, c) counter-clockwise, else of the vertex normals' mean,
// else zero (the STL convention for "none").
glm::vec3 facetNormal(const VertexRecord& a, const VertexRecord& b, const VertexRecord& c) {
    const glm::dvec3 pa(a.position), pb(b.position), pc(c.position);
    const glm::dvec3 cross = glm::cross(pb - pa, pc - pa);
    const double length = glm::length(cross);
    if (length > 0 && std::isfinite(length)) return glm::vec3(cross / length);
    const glm::dvec3 mean = glm::dvec3(a.normal) + glm::dvec3(b.normal) + glm::dvec3(c.normal);
    const double meanLength = glm::length(mean);
    if (meanLength > 0 && std::isfinite(meanLength)) return glm::vec3(mean / meanLength);
    return glm::vec3(0.0f);
}

// Triangle v's record: its facet normal, its corners, a zero attribute.
void encodeTriangle(const VertexRecord (&v)[3], unsigned char* record) {
    const glm::vec3 n = facetNormal(v[0], v[1], v[2]);
    std::memcpy(record, &n, 12);
    for (int k = 0; k < 3; ++k) std::memcpy(record + 12 + 12 * k, &v[k].position, 12);
    record[48] = record[49] = 0;
}

class StlWriter final : public MeshFormatWriter {
public:
    StlWriter(const std::string& path, bool overwrite)
        : mOut(path, overwrite), mEarlier(path, ".vertices") {
        const auto header = stlHeader(0);  // the count, written by finish()
        mWriter.put(header.data(), header.size());
    }

    void append(const TriangleMesh& part) override {
        if (mTriangles + part.triangleCount() > std::numeric_limits<uint32_t>::max())
            throwIoError(mOut.path(), "more than 4294967295 triangles: too many for STL");
        readEarlierVertices(part);
        for (size_t t = 0; t < part.triangleCount(); ++t) {
            const VertexRecord v[3] = {vertex(part, part.indices[3 * t]),
                                       vertex(part, part.indices[3 * t + 1]),
                                       vertex(part, part.indices[3 * t + 2])};
            unsigned char record[kStlTriangleBytes];
            encodeTriangle(v, record);
            mWriter.put(record, sizeof record);
        }
        for (size_t i = 0; i < part.positions.size(); ++i) {
            const VertexRecord r{part.positions[i], part.normals[i]};
            mEarlier.put(&r, sizeof r);
        }
        mTriangles += part.triangleCount();
    }

    void finish() override {
        mWriter.flush();
        const auto count = uint32_t(mTriangles);
        mOut.writeAt(&count, sizeof count, kTextBytes);
        mOut.commit();
    }

private:
    // Reads the vertices of earlier pieces that `part`'s triangles use into mEarlierVertices
    // (sorted by number), a run of nearby ones in one read.
    void readEarlierVertices(const TriangleMesh& part) {
        mEarlierNumbers.clear();
        for (uint32_t i : part.indices)
            if (i < part.firstVertex) mEarlierNumbers.push_back(i);
        std::sort(mEarlierNumbers.begin(), mEarlierNumbers.end());
        mEarlierNumbers.erase(std::unique(mEarlierNumbers.begin(), mEarlierNumbers.end()),
                              mEarlierNumbers.end());
        mEarlierVertices.resize(mEarlierNumbers.size());
        constexpr uint32_t kRun = 256;  // vertices read at once rather than seeking past them
        std::vector<VertexRecord> run;
        for (size_t k = 0; k < mEarlierNumbers.size();) {
            const uint32_t first = mEarlierNumbers[k];
            size_t end = k + 1;
            while (end < mEarlierNumbers.size() && mEarlierNumbers[end] - first < kRun) ++end;
            run.resize(mEarlierNumbers[end - 1] - first + 1);
            mEarlier.read(run.data(), run.size() * sizeof(VertexRecord),
                          uint64_t(first) * sizeof(VertexRecord));
            for (; k < end; ++k) mEarlierVertices[k] = run[mEarlierNumbers[k] - first];
        }
    }

    VertexRecord vertex(const TriangleMesh& part, uint32_t number) const {
        if (number >= part.firstVertex) {
            const size_t i = number - part.firstVertex;
            return {part.positions[i], part.normals[i]};
        }
        const auto at = std::lower_bound(mEarlierNumbers.begin(), mEarlierNumbers.end(), number);
        return mEarlierVertices[size_t(at - mEarlierNumbers.begin())];
    }

    AtomicOutputFile mOut;
    BufferedAppender mWriter{mOut};
    SideFile mEarlier;  // every appended vertex, VertexRecord each
    std::vector<uint32_t> mEarlierNumbers;
    std::vector<VertexRecord> mEarlierVertices;
    uint64_t mTriangles = 0;
};

}  // namespace

std::array<unsigned char, kStlHeaderBytes> stlHeader(uint32_t triangles) {
    std::array<unsigned char, kStlHeaderBytes> header{};
    // Not starting with "solid": some readers take such a file for ASCII STL.
    const char text[] = "vdiso isosurface (binary STL)";
    std::memcpy(header.data(), text, sizeof text - 1);
    std::memcpy(header.data() + kTextBytes, &triangles, sizeof triangles);
    return header;
}

std::vector<unsigned char> stlTriangleRecords(const TriangleMesh& part) {
    std::vector<unsigned char> bytes(part.triangleCount() * kStlTriangleBytes);
    for (size_t t = 0; t < part.triangleCount(); ++t) {
        VertexRecord v[3];
        for (int k = 0; k < 3; ++k) {
            const uint32_t i = part.indices[3 * t + size_t(k)];
            v[k] = {part.positions[i], part.normals[i]};
        }
        encodeTriangle(v, bytes.data() + t * kStlTriangleBytes);
    }
    return bytes;
}

std::unique_ptr<MeshFormatWriter> makeStlWriter(const std::string& path, bool overwrite) {
    return std::make_unique<StlWriter>(path, overwrite);
}

}  // namespace vdiso
