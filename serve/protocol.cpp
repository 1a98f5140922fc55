#include "serve/protocol.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>

#include <glm/geometric.hpp>

namespace vdiso::serve {

namespace {

static_assert(std::endian::native == std::endian::little,
              "the protocol is little-endian; a big-endian host needs byte swaps here");

template <class T>
T load(const uint8_t* p) {
    T value;
    std::memcpy(&value, p, sizeof value);
    return value;
}

template <class T>
void store(uint8_t* p, T value) {
    std::memcpy(p, &value, sizeof value);
}

glm::dvec3 loadVec(const uint8_t* p) {
    return {load<double>(p), load<double>(p + 8), load<double>(p + 16)};
}

void storeVec(uint8_t* p, const glm::dvec3& v) {
    for (int k = 0; k < 3; ++k) store(p + 8 * k, v[k]);
}

void writeHeader(uint8_t* p, MessageType type, uint16_t flags = 0) {
    p[0] = uint8_t(type);
    p[1] = kProtocolVersion;
    store<uint16_t>(p + 2, flags);
}

}  // namespace

MessageType clientMessageType(std::span<const uint8_t> message) {
    if (message.size() > kMaxClientMessageBytes)
        throw ProtocolError("message of " + std::to_string(message.size()) +
                            " bytes is above the limit of " +
                            std::to_string(kMaxClientMessageBytes));
    if (message.size() < 4)
        throw ProtocolError("message of " + std::to_string(message.size()) +
                            " bytes is shorter than a header (4 bytes)");
    const uint8_t type = message[0];
    if (type != uint8_t(MessageType::View) && type != uint8_t(MessageType::Evict) &&
        type != uint8_t(MessageType::HandOver))
        throw ProtocolError("unknown message type " + std::to_string(type) +
                            " (a client sends VIEW = 1, EVICT = 2 or HANDOVER = 3)");
    if (message[1] != kProtocolVersion)
        throw ProtocolError("message version " + std::to_string(message[1]) +
                            " is not the server's (" + std::to_string(kProtocolVersion) + ")");
    if (message[2] != 0 || message[3] != 0) throw ProtocolError("reserved header bytes are not zero");
    return MessageType(type);
}

ViewMessage parseView(std::span<const uint8_t> message) {
    if (clientMessageType(message) != MessageType::View) throw ProtocolError("not a VIEW message");
    if (message.size() != kViewMessageBytes)
        throw ProtocolError("VIEW of " + std::to_string(message.size()) + " bytes, expected " +
                            std::to_string(kViewMessageBytes));
    const uint8_t* p = message.data();
    ViewMessage v;
    v.seq = load<uint32_t>(p + 4);
    v.store = load<uint32_t>(p + 8);
    v.width = load<uint32_t>(p + 12);
    v.height = load<uint32_t>(p + 16);
    if (load<uint32_t>(p + 20) != 0) throw ProtocolError("VIEW: reserved field is not zero");
    v.eye = loadVec(p + 24);
    v.target = loadVec(p + 48);
    v.up = loadVec(p + 72);
    v.fovYDegrees = load<double>(p + 96);
    v.iso = load<double>(p + 104) + 0.0;  // -0 is 0: isovalues key cached chunks
    if (v.seq > kMaxSeq) throw ProtocolError("VIEW: seq must be at most " + std::to_string(kMaxSeq));
    if (!std::isfinite(v.iso)) throw ProtocolError("VIEW: iso must be a finite number");
    // The camera as every front end checks one (core/camera.h).
    if (const std::string problem = cameraProblem(cameraOf(v)); !problem.empty())
        throw ProtocolError("VIEW: " + problem);
    return v;
}

EvictMessage parseEvict(std::span<const uint8_t> message) {
    if (clientMessageType(message) != MessageType::Evict) throw ProtocolError("not an EVICT message");
    if (message.size() < kEvictHeaderBytes)
        throw ProtocolError("EVICT of " + std::to_string(message.size()) +
                            " bytes is shorter than its header (24 bytes)");
    const uint8_t* p = message.data();
    EvictMessage e;
    e.seq = load<uint32_t>(p + 4);
    e.store = load<uint32_t>(p + 8);
    const uint32_t count = load<uint32_t>(p + 12);
    e.iso = load<double>(p + 16) + 0.0;
    if (count > kMaxEvictCount)
        throw ProtocolError("EVICT: count " + std::to_string(count) + " is above " +
                            std::to_string(kMaxEvictCount));
    if (message.size() != kEvictHeaderBytes + 4 * size_t(count))
        throw ProtocolError("EVICT of " + std::to_string(message.size()) + " bytes does not hold " +
                            std::to_string(count) + " bricks");
    if (!std::isfinite(e.iso)) throw ProtocolError("EVICT: iso must be a finite number");
    e.bricks.resize(count);
    if (count) std::memcpy(e.bricks.data(), p + kEvictHeaderBytes, 4 * size_t(count));
    return e;
}

HandOverMessage parseHandOver(std::span<const uint8_t> message) {
    if (clientMessageType(message) != MessageType::HandOver) throw ProtocolError("not a HANDOVER message");
    if (message.size() != kHandOverMessageBytes)
        throw ProtocolError("HANDOVER of " + std::to_string(message.size()) + " bytes, expected " +
                            std::to_string(kHandOverMessageBytes));
    const std::span<const uint8_t> to = message.subspan(4, kSessionIdChars);
    HandOverMessage h;
    if (std::all_of(to.begin(), to.end(), [](uint8_t c) { return c == 0; })) return h;
    for (const uint8_t c : to)
        if (!((c >= '0' && c <= '9') || (c >= 'a' && c <= 'f')))
            throw ProtocolError("HANDOVER: the session id must be 8 lower-case hex digits (or 8 zero bytes)");
    h.to.assign(to.begin(), to.end());
    return h;
}

std::vector<uint8_t> encodeHandOver(const HandOverMessage& handOver) {
    std::vector<uint8_t> m(kHandOverMessageBytes, 0);
    m[0] = uint8_t(MessageType::HandOver);
    m[1] = kProtocolVersion;
    std::copy_n(handOver.to.begin(), std::min(handOver.to.size(), kSessionIdChars), m.begin() + 4);
    return m;
}

ViewMessage viewMessage(const Camera& camera, uint32_t seq, uint32_t store, double iso) {
    ViewMessage v;
    v.seq = seq;
    v.store = store;
    v.width = uint32_t(camera.width);
    v.height = uint32_t(camera.height);
    v.eye = camera.eye;
    v.target = camera.target;
    v.up = camera.up;
    v.fovYDegrees = camera.fovYDegrees;
    v.iso = iso;
    return v;
}

Camera cameraOf(const ViewMessage& view) {
    Camera camera;
    camera.eye = view.eye;
    camera.target = view.target;
    camera.up = view.up;
    camera.fovYDegrees = view.fovYDegrees;
    camera.width = int(view.width);
    camera.height = int(view.height);
    return camera;
}

std::vector<uint8_t> encodeView(const ViewMessage& v) {
    std::vector<uint8_t> out(kViewMessageBytes, 0);
    uint8_t* p = out.data();
    writeHeader(p, MessageType::View);
    store(p + 4, v.seq);
    store(p + 8, v.store);
    store(p + 12, v.width);
    store(p + 16, v.height);
    storeVec(p + 24, v.eye);
    storeVec(p + 48, v.target);
    storeVec(p + 72, v.up);
    store(p + 96, v.fovYDegrees);
    store(p + 104, v.iso);
    return out;
}

std::vector<uint8_t> encodeEvict(const EvictMessage& e) {
    std::vector<uint8_t> out(kEvictHeaderBytes + 4 * e.bricks.size(), 0);
    uint8_t* p = out.data();
    writeHeader(p, MessageType::Evict);
    store(p + 4, e.seq);
    store(p + 8, e.store);
    store(p + 12, uint32_t(e.bricks.size()));
    store(p + 16, e.iso);
    if (!e.bricks.empty()) std::memcpy(p + kEvictHeaderBytes, e.bricks.data(), 4 * e.bricks.size());
    return out;
}

void writeChunkHeader(const ChunkHeader& h, uint8_t* p) {
    writeHeader(p, MessageType::Chunk, h.flags);
    store(p + 4, h.frame);
    store(p + 8, h.store);
    store(p + 12, h.brick);
    store(p + 16, h.iso);
    for (int k = 0; k < 3; ++k) {
        store(p + 24 + 4 * k, h.boxMin[k]);
        store(p + 36 + 4 * k, h.boxMax[k]);
    }
    store(p + 48, h.vertexCount);
    store(p + 52, h.triangleCount);
    store(p + 56, h.pointCount);
    store(p + 60, h.vertexBytes);
    store(p + 64, h.indexBytes);
    store(p + 68, h.pointBytes);
}

ChunkHeader readChunkHeader(std::span<const uint8_t> m) {
    if (m.size() < kChunkHeaderBytes || m[0] != uint8_t(MessageType::Chunk) || m[1] != kProtocolVersion)
        throw ProtocolError("not a CHUNK message of version 1");
    const uint8_t* p = m.data();
    ChunkHeader h;
    h.flags = load<uint16_t>(p + 2);
    h.frame = load<uint32_t>(p + 4);
    h.store = load<uint32_t>(p + 8);
    h.brick = load<uint32_t>(p + 12);
    h.iso = load<double>(p + 16);
    for (int k = 0; k < 3; ++k) {
        h.boxMin[k] = load<float>(p + 24 + 4 * k);
        h.boxMax[k] = load<float>(p + 36 + 4 * k);
    }
    h.vertexCount = load<uint32_t>(p + 48);
    h.triangleCount = load<uint32_t>(p + 52);
    h.pointCount = load<uint32_t>(p + 56);
    h.vertexBytes = load<uint32_t>(p + 60);
    h.indexBytes = load<uint32_t>(p + 64);
    h.pointBytes = load<uint32_t>(p + 68);
    if (uint64_t(h.vertexBytes) + h.indexBytes + h.pointBytes != m.size() - kChunkHeaderBytes)
        throw ProtocolError("CHUNK: payload sizes do not add up to the message");
    return h;
}

std::vector<uint8_t> encodeRefs(uint32_t frame, std::span<const uint32_t> bricks) {
    std::vector<uint8_t> out(kRefsHeaderBytes + 4 * bricks.size());
    uint8_t* p = out.data();
    writeHeader(p, MessageType::Refs);
    store(p + 4, frame);
    store(p + 8, uint32_t(bricks.size()));
    if (!bricks.empty()) std::memcpy(p + kRefsHeaderBytes, bricks.data(), 4 * bricks.size());
    return out;
}

std::vector<uint32_t> decodeRefs(std::span<const uint8_t> m, uint32_t& frame) {
    if (m.size() < kRefsHeaderBytes || m[0] != uint8_t(MessageType::Refs))
        throw ProtocolError("not a REFS message");
    frame = load<uint32_t>(m.data() + 4);
    const uint32_t count = load<uint32_t>(m.data() + 8);
    if (m.size() != kRefsHeaderBytes + 4 * size_t(count)) throw ProtocolError("REFS: wrong size");
    std::vector<uint32_t> bricks(count);
    if (count) std::memcpy(bricks.data(), m.data() + kRefsHeaderBytes, 4 * size_t(count));
    return bricks;
}

}  // namespace vdiso::serve
