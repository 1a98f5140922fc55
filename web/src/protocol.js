// The binary messages of docs/protocol.md (version 1), mirroring serve/protocol.h.
// Every number is little-endian; DataView is told so explicitly. Decoded payloads are views
// into the WebSocket's ArrayBuffer, never copies.

export const PROTOCOL_VERSION = 1;

export const MessageType = Object.freeze({
  VIEW: 1,
  EVICT: 2,
  HANDOVER: 3,
  CHUNK: 16,
  REFS: 17,
});

export const VIEW_BYTES = 112;
// A VIEW's viewport sides: what the server takes (core/camera.h kMinImageSide, kMaxImageSide).
export const VIEWPORT_MIN = 16;
export const VIEWPORT_MAX = 8192;
export const EVICT_HEADER_BYTES = 24;
export const HANDOVER_BYTES = 12;
const SESSION_ID = /^[0-9a-f]{8}$/;
export const EVICT_MAX_BRICKS = 65536;
export const CHUNK_HEADER_BYTES = 72;
export const REFS_HEADER_BYTES = 12;
export const CHUNK_FLAG_CACHEABLE = 1;
export const TRANSIENT_BRICK = 0xffffffff;
// Triangle vertices and points alike: u16 x, y, z in the chunk's box, then i8 u, v (octahedral normal).
export const VERTEX_BYTES = 8;
// The most vertices, triangles or points one CHUNK may hold. The server's chunks are one brick's
// surface (32^3 cells by default, at most 5 triangles each: 163840) or a transient batch of
// about 32768 vertices and points; 2^24 is far above both, and still what a page can decode (a
// count costs at most 16 bytes of typed arrays, so 256 MiB per section) rather than what a
// hostile header asks for.
export const CHUNK_MAX_COUNT = 1 << 24;

// The fewest bytes in which meshoptimizer's codecs can hold `count` items: a section shorter
// than that is refused before anything is allocated for its count, since the decoder (like
// decode.js) sizes its output from the count and looks at the bytes only afterwards. Both bounds
// are the decoder's own (meshoptimizer 1.3, src/vertexcodec.cpp and src/indexcodec.cpp), so every
// section it accepts passes them, and its encoder reaches them.
//
// Vertex codec, 8-byte vertices (the decoder reads formats 0 and 1, refusing others): a header
// byte, a tail (the first vertex; in format 1 also the channel modes) padded to 24 bytes in
// format 1 (32 in format 0), and between them one block per 256 vertices, each at least 2 bytes
// (format 1's two control bytes with every byte channel coded as zero; a format 0 block takes at
// least 8). So n vertices take at least 25 + 2 * ceil(n / 256) bytes: at most 128 per byte.
export function minVertexBytes(count) {
  return count === 0 ? 0 : 25 + 2 * Math.ceil(count / 256);
}

// Index codec (meshopt_decodeIndexBuffer refuses less): a header byte, one code byte per
// triangle and a 16-byte table, so t triangles take at least 17 + t bytes.
export function minIndexBytes(triangles) {
  return triangles === 0 ? 0 : 17 + triangles;
}

// Throws unless `count` items (at most CHUNK_MAX_COUNT) fit in `bytes` by `minBytes`; an empty
// section has no bytes at all (the server writes none for it).
export function checkChunkSection(what, count, bytes, minBytes) {
  if (count > CHUNK_MAX_COUNT) throw new Error(`CHUNK of ${count} ${what}: at most ${CHUNK_MAX_COUNT}`);
  if (count === 0 && bytes !== 0) throw new Error(`CHUNK of 0 ${what} has ${bytes} bytes of them`);
  const least = minBytes(count);
  if (bytes < least) throw new Error(`CHUNK of ${count} ${what} has ${bytes} bytes of them, less than the ${least} they take`);
}

const LE = true;

function writeHeader(view, type) {
  view.setUint8(0, type);
  view.setUint8(1, PROTOCOL_VERSION);
  view.setUint16(2, 0, LE);
}

function writeVec3(view, offset, v) {
  for (let i = 0; i < 3; ++i) view.setFloat64(offset + 8 * i, v[i], LE);
}

// VIEW: the camera and isovalue the client wants drawn. eye/target/up are arrays of 3 numbers,
// fov the vertical field of view in degrees, width/height the viewport in device pixels.
export function encodeView({ seq, store, width, height, eye, target, up, fov, iso }) {
  const buffer = new ArrayBuffer(VIEW_BYTES);
  const view = new DataView(buffer);
  writeHeader(view, MessageType.VIEW);
  view.setUint32(4, seq, LE);
  view.setUint32(8, store, LE);
  view.setUint32(12, width, LE);
  view.setUint32(16, height, LE);
  view.setUint32(20, 0, LE);
  writeVec3(view, 24, eye);
  writeVec3(view, 48, target);
  writeVec3(view, 72, up);
  view.setFloat64(96, fov, LE);
  view.setFloat64(104, iso, LE);
  return buffer;
}

// EVICT: bricks (of one store and isovalue) the client dropped from its cache.
export function encodeEvict({ seq, store, iso, bricks }) {
  if (bricks.length > EVICT_MAX_BRICKS) throw new RangeError(`EVICT holds at most ${EVICT_MAX_BRICKS} bricks`);
  const buffer = new ArrayBuffer(EVICT_HEADER_BYTES + 4 * bricks.length);
  const view = new DataView(buffer);
  writeHeader(view, MessageType.EVICT);
  view.setUint32(4, seq, LE);
  view.setUint32(8, store, LE);
  view.setUint32(12, bricks.length, LE);
  view.setFloat64(16, iso, LE);
  bricks.forEach((brick, i) => view.setUint32(EVICT_HEADER_BYTES + 4 * i, brick, LE));
  return buffer;
}

// Gives control to follower `to` (a session id), or to the first follower (to undefined).
export function encodeHandOver(to) {
  const buffer = new ArrayBuffer(HANDOVER_BYTES);
  const view = new DataView(buffer);
  writeHeader(view, MessageType.HANDOVER);
  if (to !== undefined) {
    if (!SESSION_ID.test(to)) throw new Error(`session id ${to} is not 8 lower-case hex digits`);
    for (let i = 0; i < 8; i += 1) view.setUint8(4 + i, to.charCodeAt(i));
  }
  return buffer;
}

function readVec3f(view, offset) {
  return [view.getFloat32(offset, LE), view.getFloat32(offset + 4, LE), view.getFloat32(offset + 8, LE)];
}

function decodeChunk(buffer, view) {
  if (buffer.byteLength < CHUNK_HEADER_BYTES) throw new Error(`CHUNK of ${buffer.byteLength} bytes is shorter than its header`);
  const chunk = {
    type: MessageType.CHUNK,
    cacheable: (view.getUint16(2, LE) & CHUNK_FLAG_CACHEABLE) !== 0,
    frame: view.getUint32(4, LE),
    store: view.getUint32(8, LE),
    brick: view.getUint32(12, LE),
    iso: view.getFloat64(16, LE),
    boxMin: readVec3f(view, 24),
    boxMax: readVec3f(view, 36),
    vertexCount: view.getUint32(48, LE),
    triangleCount: view.getUint32(52, LE),
    pointCount: view.getUint32(56, LE),
    byteLength: buffer.byteLength,
  };
  const vertexBytes = view.getUint32(60, LE);
  const indexBytes = view.getUint32(64, LE);
  const pointBytes = view.getUint32(68, LE);
  const expected = CHUNK_HEADER_BYTES + vertexBytes + indexBytes + pointBytes;
  if (expected !== buffer.byteLength) {
    throw new Error(`CHUNK of ${buffer.byteLength} bytes announces ${expected}`);
  }
  if (chunk.cacheable === (chunk.brick === TRANSIENT_BRICK)) {
    throw new Error(`CHUNK brick ${chunk.brick} disagrees with its cacheable flag`);
  }
  // The counts against the sections that hold them, here on arrival (and again in decode.js,
  // next to the allocations), so a malformed chunk never reaches the cache.
  checkChunkSection('vertices', chunk.vertexCount, vertexBytes, minVertexBytes);
  checkChunkSection('triangles', chunk.triangleCount, indexBytes, minIndexBytes);
  checkChunkSection('points', chunk.pointCount, pointBytes, minVertexBytes);
  // The server sends the vertices its triangles use: one without the other is malformed.
  if ((chunk.vertexCount === 0) !== (chunk.triangleCount === 0)) {
    throw new Error(`CHUNK of ${chunk.vertexCount} vertices and ${chunk.triangleCount} triangles`);
  }
  let offset = CHUNK_HEADER_BYTES;
  chunk.vertexData = new Uint8Array(buffer, offset, vertexBytes);
  offset += vertexBytes;
  chunk.indexData = new Uint8Array(buffer, offset, indexBytes);
  offset += indexBytes;
  chunk.pointData = new Uint8Array(buffer, offset, pointBytes);
  return chunk;
}

function decodeRefs(buffer, view) {
  if (buffer.byteLength < REFS_HEADER_BYTES) throw new Error(`REFS of ${buffer.byteLength} bytes is shorter than its header`);
  // The count against the length: the bricks are a view of the message, never a copy, so this
  // also bounds what is made from them.
  const count = view.getUint32(8, LE);
  if (buffer.byteLength !== REFS_HEADER_BYTES + 4 * count) {
    throw new Error(`REFS of ${buffer.byteLength} bytes announces ${count} bricks`);
  }
  return {
    type: MessageType.REFS,
    frame: view.getUint32(4, LE),
    // Offset 12 is 4-byte aligned, so the bricks are read in place (little-endian hosts only,
    // which every browser that runs WebGL2 is).
    bricks: new Uint32Array(buffer, REFS_HEADER_BYTES, count),
    byteLength: buffer.byteLength,
  };
}

// A binary message from the server: a CHUNK or a REFS. Throws on anything malformed.
export function decodeServerMessage(buffer) {
  if (!(buffer instanceof ArrayBuffer)) throw new Error('binary message is not an ArrayBuffer');
  if (buffer.byteLength < 4) throw new Error(`binary message of ${buffer.byteLength} bytes`);
  const view = new DataView(buffer);
  const type = view.getUint8(0);
  const version = view.getUint8(1);
  if (version !== PROTOCOL_VERSION) throw new Error(`binary message of version ${version}, expected ${PROTOCOL_VERSION}`);
  if (type === MessageType.CHUNK) return decodeChunk(buffer, view);
  if (type === MessageType.REFS) return decodeRefs(buffer, view);
  throw new Error(`unknown binary message type ${type}`);
}
