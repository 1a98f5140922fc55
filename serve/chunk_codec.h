// Geometry on the wire: one CHUNK message from a brick's triangles and points, and back.
//
// Positions are quantized to 16 bits per axis inside the chunk's box (the bounds of what it
// holds), normals to octahedral 2 x 8 bits, so a vertex is 8 bytes; triangles are put in
// vertex-cache order and vertices in first-use order (meshoptimizer), then both go through
// meshoptimizer's vertex and index codecs (docs/protocol.md, CHUNK). With 16-bit positions
// a 32-cell brick's vertices land within 1/2000 of a cell of where they were.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "core/mesh.h"
#include "serve/protocol.h"

namespace vdiso::serve {

// The CHUNK message for `mesh` (vertices numbered from mesh.firstVertex, indices referring to
// those only) and `points`. `header` gives flags, frame, store, brick and iso; the box, counts
// and sizes are filled in. Thread-safe (no shared state).
std::vector<uint8_t> encodeChunk(ChunkHeader header, const TriangleMesh& mesh, const PointSet& points);

// A decoded CHUNK: positions and normals as the client reconstructs them.
struct DecodedChunk {
    ChunkHeader header;
    TriangleMesh mesh;  // firstVertex 0
    PointSet points;
};

// Decodes a CHUNK message. Throws ProtocolError when it is malformed.
DecodedChunk decodeChunk(std::span<const uint8_t> message);

// The octahedral code of a unit normal, and back (exposed for tests).
void encodeOctahedral(const glm::vec3& normal, int8_t& u, int8_t& v);
glm::vec3 decodeOctahedral(int8_t u, int8_t v);

}  // namespace vdiso::serve
