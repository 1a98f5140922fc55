// A CHUNK's meshoptimizer-encoded payload into the typed arrays the GPU draws from.
//
// A vertex on the wire is 8 bytes: u16 x, y, z in the chunk's box, then i8 u, v (octahedral
// normal). Read as a Uint16Array, that is 4 numbers per vertex: x, y, z and the normal's two
// bytes as one u16 (u | v << 8 on a little-endian host). The shaders (scene.js) take the
// position as normalized u16 and unpack the normal from that fourth number, so the decoded
// bytes reach the GPU without any conversion:
//   - points stay interleaved, the decoder's output used as the vertex buffer directly;
//   - triangle vertices are split into position (3 x u16) and normal (1 x u16) arrays, because
//     THREE.BatchedMesh (where they go, see scene.js) copies plain attributes only.
//
// Every count is checked against the bytes that hold it (protocol.js: checkChunkSection) before
// anything is sized from it, here too and not only in decodeServerMessage, because the decoder
// sizes its output (in its WebAssembly memory, which never shrinks) from the count alone. What
// the decoder throws comes out as an Error naming the section.
import { MeshoptDecoder } from 'meshoptimizer/decoder';
import { VERTEX_BYTES, checkChunkSection, minIndexBytes, minVertexBytes } from './protocol.js';

export const decoderReady = MeshoptDecoder.ready;

function decodeWith(what, decode) {
  try {
    decode();
  } catch (error) {
    throw new Error(`CHUNK ${what} do not decode: ${error?.message || error}`);
  }
}

function decodeVertices(data, count, what) {
  checkChunkSection(what, count, data.length, minVertexBytes);
  const vertices = new Uint16Array(4 * count);
  if (count === 0) return vertices;
  // The decoder copies bytes into its target, so the target must be a byte view.
  decodeWith(what, () => MeshoptDecoder.decodeVertexBuffer(new Uint8Array(vertices.buffer), count, VERTEX_BYTES, data));
  return vertices;
}

// Triangles of a chunk: { positions: Uint16Array(3n), normals: Uint16Array(n), indices: Uint32Array(3t) }.
export function decodeTriangles(chunk) {
  const { vertexCount, triangleCount } = chunk;
  checkChunkSection('triangles', triangleCount, chunk.indexData.length, minIndexBytes);
  const vertices = decodeVertices(chunk.vertexData, vertexCount, 'vertices');
  const positions = new Uint16Array(3 * vertexCount);
  const normals = new Uint16Array(vertexCount);
  for (let v = 0, p = 0, q = 0; v < vertexCount; ++v, p += 3, q += 4) {
    positions[p] = vertices[q];
    positions[p + 1] = vertices[q + 1];
    positions[p + 2] = vertices[q + 2];
    normals[v] = vertices[q + 3];
  }
  const indices = new Uint32Array(3 * triangleCount);
  if (triangleCount > 0) {
    decodeWith('triangles', () => MeshoptDecoder.decodeIndexBuffer(new Uint8Array(indices.buffer), 3 * triangleCount, 4, chunk.indexData));
  }
  // In a BatchedMesh an index past the chunk's vertices would silently draw another chunk's.
  for (let i = 0; i < indices.length; ++i) {
    if (indices[i] >= vertexCount) throw new Error(`CHUNK index ${indices[i]} beyond its ${vertexCount} vertices`);
  }
  return { positions, normals, indices };
}

// Points of a chunk, interleaved as on the wire: Uint16Array(4n).
export function decodePoints(chunk) {
  return decodeVertices(chunk.pointData, chunk.pointCount, 'points');
}
