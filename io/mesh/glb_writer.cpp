#include "io/mesh/glb_writer.h"

#include <algorithm>
#include <array>
#include <limits>
#include <vector>

#include <glm/common.hpp>
#include <meshoptimizer.h>
#include <nlohmann/json.hpp>

#include "io/error.h"
#include "io/mesh/mesh_output.h"

namespace vdiso {

namespace {

using Json = nlohmann::ordered_json;

constexpr uint32_t kMagic = 0x46546C67;      // "glTF"
constexpr uint32_t kJsonChunk = 0x4E4F534A;  // "JSON"
constexpr uint32_t kBinChunk = 0x004E4942;   // "BIN\0"
constexpr int kFloat = 5126, kUnsignedInt = 5125;
constexpr int kArrayBuffer = 34962, kElementArrayBuffer = 34963;
constexpr int kTriangles = 4;
constexpr const char* kMeshopt = "EXT_meshopt_compression";
// More than the JSON takes, so that a mesh refused as too large is refused while it streams.
constexpr uint64_t kJsonBound = 4096;

uint64_t padded4(uint64_t n) { return (n + 3) & ~uint64_t(3); }

// One buffer view: a stream of `count` elements of `stride` bytes, from its side file.
struct Stream {
    SideFile* file;
    uint64_t count;
    uint32_t stride;
    bool indices;
    std::vector<unsigned char> packed;  // compressed: the encoded bytes
    uint64_t offset = 0;                // in the BIN chunk
    uint64_t bytes() const { return count * stride; }
};

class GlbWriter final : public MeshFormatWriter {
public:
    GlbWriter(const std::string& path, bool overwrite, bool compress)
        : mOut(path, overwrite), mPositions(path, ".positions"), mNormals(path, ".normals"),
          mIndices(path, ".indices"), mCompress(compress) {}

    void append(const TriangleMesh& part) override {
        const uint64_t vertices = mVertices + part.positions.size();
        const uint64_t indices = mIndexCount + part.indices.size();
        if (vertices * 24 + indices * 4 + kJsonBound > std::numeric_limits<uint32_t>::max())
            throwIoError(mOut.path(), "mesh larger than 4 GiB, the most a GLB holds");
        mPositions.put(part.positions.data(), part.positions.size() * sizeof(glm::vec3));
        mNormals.put(part.normals.data(), part.normals.size() * sizeof(glm::vec3));
        mIndices.put(part.indices.data(), part.indices.size() * sizeof(uint32_t));
        for (const glm::vec3& p : part.positions) {
            mMin = glm::min(mMin, p);
            mMax = glm::max(mMax, p);
        }
        mVertices = vertices;
        mIndexCount = indices;
    }

    void finish() override {
        std::array<Stream, 3> streams = {Stream{&mPositions, mVertices, 12, false, {}, 0},
                                         Stream{&mNormals, mVertices, 12, false, {}, 0},
                                         Stream{&mIndices, mIndexCount, 4, true, {}, 0}};
        const bool empty = mIndexCount == 0;
        uint64_t binBytes = 0;
        if (!empty)
            for (Stream& s : streams) {
                if (mCompress) encode(s);
                s.offset = binBytes;
                binBytes += padded4(mCompress ? s.packed.size() : s.bytes());
            }
        std::string json = describe(streams, binBytes).dump();
        json.resize(padded4(json.size()), ' ');
        const uint64_t total = 12 + 8 + json.size() + (empty ? 0 : 8 + binBytes);
        if (total > std::numeric_limits<uint32_t>::max())
            throwIoError(mOut.path(), "mesh larger than 4 GiB, the most a GLB holds");

        const uint32_t header[5] = {kMagic, 2, uint32_t(total), uint32_t(json.size()), kJsonChunk};
        mWriter.put(header, sizeof header);
        mWriter.put(json);
        if (!empty) {
            const uint32_t bin[2] = {uint32_t(binBytes), kBinChunk};
            mWriter.put(bin, sizeof bin);
            for (Stream& s : streams) {
                if (!mCompress) {
                    s.file->copyTo(mWriter);
                    continue;
                }
                mWriter.put(s.packed.data(), s.packed.size());
                const unsigned char zeros[3] = {};
                mWriter.put(zeros, padded4(s.packed.size()) - s.packed.size());
            }
        }
        mWriter.flush();
        mOut.commit();
    }

private:
    // Reads the stream back whole and encodes it with meshoptimizer's codec for its kind.
    void encode(Stream& s) const {
        size_t n = 0;
        if (s.indices) {
            std::vector<uint32_t> indices(s.count);
            s.file->read(indices.data(), s.bytes(), 0);
            s.packed.resize(meshopt_encodeIndexBufferBound(indices.size(), mVertices));
            n = meshopt_encodeIndexBuffer(s.packed.data(), s.packed.size(), indices.data(),
                                          indices.size());
        } else {
            std::vector<unsigned char> raw(s.bytes());
            s.file->read(raw.data(), raw.size(), 0);
            s.packed.resize(meshopt_encodeVertexBufferBound(s.count, s.stride));
            n = meshopt_encodeVertexBuffer(s.packed.data(), s.packed.size(), raw.data(), s.count,
                                           s.stride);
        }
        if (n == 0) throwIoError(mOut.path(), "meshoptimizer could not encode the mesh");
        s.packed.resize(n);
        s.packed.shrink_to_fit();
    }

    Json describe(const std::array<Stream, 3>& streams, uint64_t binBytes) const {
        Json gltf;
        gltf["asset"] = {{"version", "2.0"}, {"generator", "vdiso"}};
        if (mCompress && mIndexCount > 0) {
            gltf["extensionsUsed"] = Json::array({kMeshopt});
            gltf["extensionsRequired"] = Json::array({kMeshopt});
        }
        gltf["scene"] = 0;
        gltf["scenes"] = Json::array({Json{{"nodes", Json::array({0})}}});
        if (mIndexCount == 0) {
            gltf["nodes"] = Json::array({Json::object()});
            return gltf;
        }
        gltf["nodes"] = Json::array({Json{{"mesh", 0}}});
        Json primitive = {{"attributes", {{"POSITION", 0}, {"NORMAL", 1}}}, {"indices", 2},
                          {"mode", kTriangles}};
        gltf["meshes"] = Json::array({Json{{"primitives", Json::array({primitive})}}});
        Json position = {{"bufferView", 0}, {"componentType", kFloat}, {"count", mVertices},
                         {"type", "VEC3"}};
        position["min"] = {mMin.x, mMin.y, mMin.z};
        position["max"] = {mMax.x, mMax.y, mMax.z};
        gltf["accessors"] = Json::array(
            {position,
             Json{{"bufferView", 1}, {"componentType", kFloat}, {"count", mVertices}, {"type", "VEC3"}},
             Json{{"bufferView", 2}, {"componentType", kUnsignedInt}, {"count", mIndexCount},
                  {"type", "SCALAR"}}});
        Json views = Json::array();
        uint64_t rawOffset = 0;
        for (const Stream& s : streams) {
            Json view = {{"buffer", mCompress ? 1 : 0},
                         {"byteOffset", mCompress ? rawOffset : s.offset},
                         {"byteLength", s.bytes()}};
            if (mCompress && !s.indices) view["byteStride"] = s.stride;
            view["target"] = s.indices ? kElementArrayBuffer : kArrayBuffer;
            if (mCompress)
                view["extensions"][kMeshopt] = {{"buffer", 0},
                                                {"byteOffset", s.offset},
                                                {"byteLength", s.packed.size()},
                                                {"byteStride", s.stride},
                                                {"count", s.count},
                                                {"mode", s.indices ? "TRIANGLES" : "ATTRIBUTES"}};
            views.push_back(view);
            rawOffset += s.bytes();
        }
        gltf["bufferViews"] = views;
        gltf["buffers"] = Json::array({Json{{"byteLength", binBytes}}});
        if (mCompress)  // the views' decoded size, with no data: the extension decodes them
            gltf["buffers"].push_back(
                Json{{"byteLength", rawOffset}, {"extensions", {{kMeshopt, {{"fallback", true}}}}}});
        return gltf;
    }

    AtomicOutputFile mOut;
    BufferedAppender mWriter{mOut};
    SideFile mPositions, mNormals, mIndices;
    bool mCompress;
    uint64_t mVertices = 0, mIndexCount = 0;
    glm::vec3 mMin{std::numeric_limits<float>::max()}, mMax{-std::numeric_limits<float>::max()};
};

}  // namespace

std::unique_ptr<MeshFormatWriter> makeGlbWriter(const std::string& path, bool overwrite,
                                                bool compress) {
    return std::make_unique<GlbWriter>(path, overwrite, compress);
}

}  // namespace vdiso
