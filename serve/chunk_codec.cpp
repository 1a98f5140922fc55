#include "serve/chunk_codec.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <meshoptimizer.h>

namespace vdiso::serve {

namespace {

// The wire's vertex: 8 bytes, a multiple of 4 as meshoptimizer's vertex codec requires.
struct PackedVertex {
    uint16_t x, y, z;
    int8_t u, v;
};
static_assert(sizeof(PackedVertex) == 8);

struct Quantizer {
    glm::vec3 lo, scale;  // q = round((p - lo) * scale)
    Quantizer(const glm::vec3& boxMin, const glm::vec3& boxMax) : lo(boxMin) {
        for (int k = 0; k < 3; ++k) {
            const float extent = boxMax[k] - boxMin[k];
            scale[k] = extent > 0.0f ? 65535.0f / extent : 0.0f;
        }
    }
    PackedVertex pack(const glm::vec3& p, const glm::vec3& n) const {
        PackedVertex out;
        uint16_t* q[3] = {&out.x, &out.y, &out.z};
        for (int k = 0; k < 3; ++k)
            *q[k] = uint16_t(std::clamp(std::lround((p[k] - lo[k]) * scale[k]), 0l, 65535l));
        encodeOctahedral(n, out.u, out.v);
        return out;
    }
};

glm::vec3 unpackPosition(const PackedVertex& q, const glm::vec3& lo, const glm::vec3& hi) {
    const glm::vec3 t = glm::vec3(q.x, q.y, q.z) / 65535.0f;
    return lo + t * (hi - lo);
}

void growBox(glm::vec3& lo, glm::vec3& hi, std::span<const glm::vec3> positions) {
    for (const glm::vec3& p : positions) {
        lo = glm::min(lo, p);
        hi = glm::max(hi, p);
    }
}

std::vector<unsigned char> encodeVertices(const std::vector<PackedVertex>& vertices) {
    std::vector<unsigned char> out(meshopt_encodeVertexBufferBound(vertices.size(), sizeof(PackedVertex)));
    out.resize(meshopt_encodeVertexBuffer(out.data(), out.size(), vertices.data(), vertices.size(),
                                          sizeof(PackedVertex)));
    return out;
}

// The most vertices `bytes` of meshoptimizer's vertex codec can hold. Its densest form spends
// 2 bits of control on each byte channel of a block of up to 256 vertices whose deltas are all
// zero, so a vertex costs at least 1/128 of a byte whatever the codec's version: a count above
// this bound is a lie, refused before anything is sized from it.
constexpr uint64_t kMaxVerticesPerByte = 128;

std::vector<PackedVertex> decodeVertices(const uint8_t* data, size_t bytes, uint32_t count,
                                         const char* what) {
    if (uint64_t(count) > uint64_t(bytes) * kMaxVerticesPerByte)
        throw ProtocolError(std::string("CHUNK: ") + std::to_string(count) + " " + what +
                            " cannot be held in " + std::to_string(bytes) + " bytes");
    std::vector<PackedVertex> out(count);
    if (count == 0 && bytes == 0) return out;
    if (meshopt_decodeVertexBuffer(out.data(), count, sizeof(PackedVertex), data, bytes) != 0)
        throw ProtocolError(std::string("CHUNK: ") + what + " do not decode");
    return out;
}

}  // namespace

void encodeOctahedral(const glm::vec3& normal, int8_t& u, int8_t& v) {
    glm::vec3 n = normal;
    const float l1 = std::abs(n.x) + std::abs(n.y) + std::abs(n.z);
    if (!(l1 > 0.0f) || !std::isfinite(l1)) {
        u = v = 0;  // no direction: (0, 0) decodes to +z
        return;
    }
    n /= l1;
    float a = n.x, b = n.y;
    if (n.z < 0.0f) {
        a = (1.0f - std::abs(n.y)) * (n.x >= 0.0f ? 1.0f : -1.0f);
        b = (1.0f - std::abs(n.x)) * (n.y >= 0.0f ? 1.0f : -1.0f);
    }
    u = int8_t(std::lround(std::clamp(a, -1.0f, 1.0f) * 127.0f));
    v = int8_t(std::lround(std::clamp(b, -1.0f, 1.0f) * 127.0f));
}

glm::vec3 decodeOctahedral(int8_t u, int8_t v) {
    glm::vec3 n(std::max(u / 127.0f, -1.0f), std::max(v / 127.0f, -1.0f), 0.0f);
    n.z = 1.0f - std::abs(n.x) - std::abs(n.y);
    if (n.z < 0.0f) {
        const float x = n.x, y = n.y;
        n.x = (1.0f - std::abs(y)) * (x >= 0.0f ? 1.0f : -1.0f);
        n.y = (1.0f - std::abs(x)) * (y >= 0.0f ? 1.0f : -1.0f);
    }
    return glm::normalize(n);
}

std::vector<uint8_t> encodeChunk(ChunkHeader header, const TriangleMesh& mesh, const PointSet& points) {
    glm::vec3 lo(INFINITY), hi(-INFINITY);
    growBox(lo, hi, mesh.positions);
    growBox(lo, hi, points.positions);
    if (mesh.positions.empty() && points.positions.empty()) lo = hi = glm::vec3(0.0f);
    header.boxMin = lo;
    header.boxMax = hi;
    const Quantizer quantizer(lo, hi);

    // Triangles: local indices in vertex-cache order, vertices in the order they are first
    // used (both help the codecs), then encoded. The FIFO cache optimizer of 16 entries, not
    // meshoptimizer's default one: that one was 30 % of a cold first frame's CPU (ct512's 444
    // whole chunks, 1.16 M triangles: 305-353 ms, 5.27 MB; FIFO 219-225 ms, 5.41 MB; none
    // 183-237 ms, 5.61 MB; FIFO of 8, 32, 64 entries 5.50, 5.61, 5.65 MB: bench/log.md).
    std::vector<uint32_t> indices(mesh.indices.size());
    for (size_t i = 0; i < indices.size(); ++i) indices[i] = mesh.indices[i] - mesh.firstVertex;
    std::vector<PackedVertex> vertices(mesh.positions.size());
    for (size_t i = 0; i < vertices.size(); ++i)
        vertices[i] = quantizer.pack(mesh.positions[i], mesh.normals[i]);
    meshopt_optimizeVertexCacheFifo(indices.data(), indices.data(), indices.size(), vertices.size(), 16);
    std::vector<PackedVertex> ordered(vertices.size());
    ordered.resize(meshopt_optimizeVertexFetch(ordered.data(), indices.data(), indices.size(),
                                               vertices.data(), vertices.size(), sizeof(PackedVertex)));
    const std::vector<unsigned char> vertexData = encodeVertices(ordered);
    std::vector<unsigned char> indexData(meshopt_encodeIndexBufferBound(indices.size(), ordered.size()));
    indexData.resize(meshopt_encodeIndexBuffer(indexData.data(), indexData.size(), indices.data(),
                                               indices.size()));

    std::vector<PackedVertex> dots(points.size());
    for (size_t i = 0; i < dots.size(); ++i) dots[i] = quantizer.pack(points.positions[i], points.normals[i]);
    const std::vector<unsigned char> pointData = dots.empty() ? std::vector<unsigned char>{} : encodeVertices(dots);

    header.vertexCount = uint32_t(ordered.size());
    header.triangleCount = uint32_t(indices.size() / 3);
    header.pointCount = uint32_t(dots.size());
    header.vertexBytes = ordered.empty() ? 0 : uint32_t(vertexData.size());
    header.indexBytes = indices.empty() ? 0 : uint32_t(indexData.size());
    header.pointBytes = uint32_t(pointData.size());
    std::vector<uint8_t> out(kChunkHeaderBytes + header.vertexBytes + header.indexBytes + header.pointBytes);
    writeChunkHeader(header, out.data());
    // Copies only what there is: an empty part may have no buffer at all (memcpy from null is
    // undefined even for 0 bytes).
    uint8_t* p = out.data() + kChunkHeaderBytes;
    auto put = [&](const std::vector<unsigned char>& part, uint32_t bytes) {
        if (bytes) std::memcpy(p, part.data(), bytes);
        p += bytes;
    };
    put(vertexData, header.vertexBytes);
    put(indexData, header.indexBytes);
    put(pointData, header.pointBytes);
    return out;
}

DecodedChunk decodeChunk(std::span<const uint8_t> message) {
    DecodedChunk d;
    d.header = readChunkHeader(message);
    const ChunkHeader& h = d.header;
    const uint8_t* p = message.data() + kChunkHeaderBytes;
    const std::vector<PackedVertex> vertices = decodeVertices(p, h.vertexBytes, h.vertexCount, "vertices");
    // The index codec spends at least one byte on each triangle.
    if (h.triangleCount > h.indexBytes)
        throw ProtocolError("CHUNK: " + std::to_string(h.triangleCount) + " triangles cannot be held in " +
                            std::to_string(h.indexBytes) + " bytes");
    d.mesh.indices.resize(size_t(h.triangleCount) * 3);
    if (h.triangleCount &&
        meshopt_decodeIndexBuffer(d.mesh.indices.data(), d.mesh.indices.size(), sizeof(uint32_t),
                                  p + h.vertexBytes, h.indexBytes) != 0)
        throw ProtocolError("CHUNK: indices do not decode");
    for (const uint32_t i : d.mesh.indices)
        if (i >= h.vertexCount) throw ProtocolError("CHUNK: an index is past the vertices");
    for (const PackedVertex& q : vertices) {
        d.mesh.positions.push_back(unpackPosition(q, h.boxMin, h.boxMax));
        d.mesh.normals.push_back(decodeOctahedral(q.u, q.v));
    }
    const std::vector<PackedVertex> dots =
        decodeVertices(p + h.vertexBytes + h.indexBytes, h.pointBytes, h.pointCount, "points");
    for (const PackedVertex& q : dots) {
        d.points.positions.push_back(unpackPosition(q, h.boxMin, h.boxMax));
        d.points.normals.push_back(decodeOctahedral(q.u, q.v));
    }
    return d;
}

}  // namespace vdiso::serve
