// The remote-viewing protocol's binary messages (docs/protocol.md, version 1): their layouts,
// sizes and byte order, shared by the server and its tests.
//
// Every number is little-endian. Client messages are parsed with every field validated; a
// message that fails throws ProtocolError with a sentence naming the message and the field,
// which the session sends back as an error message (the connection stays up).
#pragma once

#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "core/camera.h"

namespace vdiso::serve {

constexpr uint8_t kProtocolVersion = 1;
constexpr size_t kMaxClientMessageBytes = size_t(1) << 20;
constexpr uint32_t kMaxEvictCount = 65536;
constexpr uint32_t kNoBrick = 0xFFFFFFFFu;
constexpr uint32_t kMaxSeq = 0xFFFFFFFEu;  // a VIEW's seq (0xFFFFFFFF marks control messages)

enum class MessageType : uint8_t { View = 1, Evict = 2, HandOver = 3, Chunk = 16, Refs = 17 };

class ProtocolError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

// VIEW: the camera and isovalue a client wants drawn. 112 bytes.
struct ViewMessage {
    uint32_t seq = 0;
    uint32_t store = 0;
    uint32_t width = 0, height = 0;
    glm::dvec3 eye{0.0}, target{0.0}, up{0.0};
    double fovYDegrees = 30.0;
    double iso = 0.0;
};
constexpr size_t kViewMessageBytes = 112;

// EVICT: chunks (store, iso, brick) the client dropped. 24 + 4 * bricks.size() bytes.
struct EvictMessage {
    uint32_t seq = 0;
    uint32_t store = 0;
    double iso = 0.0;
    std::vector<uint32_t> bricks;
};
constexpr size_t kEvictHeaderBytes = 24;

// HANDOVER (follow mode): the leader gives control to one of its followers, named by its
// session id (8 hex digits), or to its first follower (`to` empty: eight zero bytes). 12 bytes.
struct HandOverMessage {
    std::string to;
};
constexpr size_t kHandOverMessageBytes = 12;
constexpr size_t kSessionIdChars = 8;

// The type of a client message (its first byte), after checking its size, type byte, version
// and reserved bytes. Throws ProtocolError.
MessageType clientMessageType(std::span<const uint8_t> message);

// Parse a VIEW or an EVICT, validating every field that does not depend on the store (the
// camera as core/camera.h's cameraProblem checks it, a finite iso, seq, sizes). Throws
// ProtocolError.
ViewMessage parseView(std::span<const uint8_t> message);
EvictMessage parseEvict(std::span<const uint8_t> message);
// A HANDOVER's `to`: 8 lower-case hex digits, or 8 zero bytes. Throws ProtocolError.
HandOverMessage parseHandOver(std::span<const uint8_t> message);

// A VIEW for `camera` (its clip planes are not sent: the server fits them to the volume), and
// the camera a VIEW describes, without clip planes.
ViewMessage viewMessage(const Camera& camera, uint32_t seq, uint32_t store, double iso);
Camera cameraOf(const ViewMessage& view);

// The client side, for tests and benchmarks.
std::vector<uint8_t> encodeView(const ViewMessage& view);
std::vector<uint8_t> encodeEvict(const EvictMessage& evict);
std::vector<uint8_t> encodeHandOver(const HandOverMessage& handOver);

// CHUNK's fixed part, before its payload (vertexBytes + indexBytes + pointBytes). 72 bytes.
struct ChunkHeader {
    uint16_t flags = 0;  // kChunkCacheable
    uint32_t frame = 0;
    uint32_t store = 0;
    uint32_t brick = kNoBrick;
    double iso = 0.0;
    glm::vec3 boxMin{0.0f}, boxMax{0.0f};
    uint32_t vertexCount = 0, triangleCount = 0, pointCount = 0;
    uint32_t vertexBytes = 0, indexBytes = 0, pointBytes = 0;
};
constexpr size_t kChunkHeaderBytes = 72;
constexpr uint16_t kChunkCacheable = 1;

// REFS: cacheable chunks of the frame's store and iso that the client holds already.
constexpr size_t kRefsHeaderBytes = 12;

void writeChunkHeader(const ChunkHeader& header, uint8_t* out);
// Reads a CHUNK's header and checks that the payload sizes add up. Throws ProtocolError.
ChunkHeader readChunkHeader(std::span<const uint8_t> message);

std::vector<uint8_t> encodeRefs(uint32_t frame, std::span<const uint32_t> bricks);
// The frame and the bricks of a REFS. Throws ProtocolError.
std::vector<uint32_t> decodeRefs(std::span<const uint8_t> message, uint32_t& frame);

}  // namespace vdiso::serve
