// The page's decoders of the server's binary messages (src/protocol.js: CHUNK and REFS;
// src/decode.js: a CHUNK's meshoptimizer-coded sections) on valid messages, made with
// meshoptimizer's own encoder, and on hostile ones: random bytes, every truncation, bit flips,
// random and huge header counts. Each message either decodes to arrays of the sizes its counts
// say, or throws an Error (that class, not a TypeError or RangeError) with a message; and no
// typed array is ever asked for that is more than the message's bytes could justify.
//
//   node --test test/*.test.js                 (from web/; ctest runs it as WebViewer.Decoders)
//   VDISO_FUZZ_SEED=1234 node --test test/*.test.js   (replays the random cases of a run)
import { before, test } from 'node:test';
import assert from 'node:assert/strict';
import { MeshoptEncoder } from 'meshoptimizer/encoder';
import { MeshoptDecoder } from 'meshoptimizer/decoder';
import {
  CHUNK_FLAG_CACHEABLE,
  CHUNK_HEADER_BYTES,
  CHUNK_MAX_COUNT,
  MessageType,
  PROTOCOL_VERSION,
  REFS_HEADER_BYTES,
  TRANSIENT_BRICK,
  decodeServerMessage,
  minIndexBytes,
  minVertexBytes,
} from '../src/protocol.js';
import { decodePoints, decodeTriangles, decoderReady } from '../src/decode.js';

const LE = true;
const SEED = Number(process.env.VDISO_FUZZ_SEED) || (Date.now() % 0x7fffffff) + 1;

// mulberry32: a small seeded PRNG, so that a failing case comes back with the same seed.
function prng(seed) {
  let a = seed >>> 0;
  const next = () => {
    a = (a + 0x6d2b79f5) >>> 0;
    let t = a;
    t = Math.imul(t ^ (t >>> 15), t | 1);
    t ^= t + Math.imul(t ^ (t >>> 7), t | 61);
    return ((t ^ (t >>> 14)) >>> 0) / 4294967296;
  };
  next.int = (n) => Math.floor(next() * n); // 0..n-1
  next.u32 = () => Math.floor(next() * 4294967296);
  return next;
}

// --- valid messages, made with meshoptimizer's encoder ---------------------------------------

const bytesOf = (typed) => new Uint8Array(typed.buffer, typed.byteOffset, typed.byteLength);

// Encoded vertices (Uint16Array of 4 per vertex); format 0 as the server's libmeshoptimizer
// 0.18 writes, 1 as newer ones do.
function encodeVertices(vertices, format) {
  const count = vertices.length / 4;
  if (count === 0) return new Uint8Array(0);
  return MeshoptEncoder.encodeVertexBufferLevel(bytesOf(vertices), count, 8, 2, format);
}

function encodeIndices(indices) {
  if (indices.length === 0) return new Uint8Array(0);
  return MeshoptEncoder.encodeIndexBuffer(bytesOf(indices), indices.length, 4);
}

// A CHUNK message: the header of docs/protocol.md with the counts given, then the sections.
function chunkMessage({ vertexData, indexData, pointData, vertexCount, triangleCount, pointCount, brick = 7, frame = 3 }) {
  const buffer = new ArrayBuffer(CHUNK_HEADER_BYTES + vertexData.length + indexData.length + pointData.length);
  const view = new DataView(buffer);
  view.setUint8(0, MessageType.CHUNK);
  view.setUint8(1, PROTOCOL_VERSION);
  view.setUint16(2, brick === TRANSIENT_BRICK ? 0 : CHUNK_FLAG_CACHEABLE, LE);
  view.setUint32(4, frame, LE);
  view.setUint32(8, 0, LE);
  view.setUint32(12, brick, LE);
  view.setFloat64(16, 40.5, LE);
  [0, 0, 0, 1, 2, 3].forEach((x, i) => view.setFloat32(24 + 4 * i, x, LE));
  view.setUint32(48, vertexCount, LE);
  view.setUint32(52, triangleCount, LE);
  view.setUint32(56, pointCount, LE);
  view.setUint32(60, vertexData.length, LE);
  view.setUint32(64, indexData.length, LE);
  view.setUint32(68, pointData.length, LE);
  const bytes = new Uint8Array(buffer);
  bytes.set(vertexData, CHUNK_HEADER_BYTES);
  bytes.set(indexData, CHUNK_HEADER_BYTES + vertexData.length);
  bytes.set(pointData, CHUNK_HEADER_BYTES + vertexData.length + indexData.length);
  return buffer;
}

// A random surface-like chunk: n vertices, t triangles over them (every vertex used), p points.
function randomGeometry(random, { n, t, p, smooth = true }) {
  const vertices = new Uint16Array(4 * n);
  const points = new Uint16Array(4 * p);
  for (const array of [vertices, points]) {
    for (let i = 0; i < array.length; ++i) {
      // Neighbouring values close together, as on a surface, or anything at all.
      array[i] = smooth && i >= 4 ? (array[i - 4] + random.int(64)) & 0xffff : random.int(65536);
    }
  }
  const indices = new Uint32Array(3 * t);
  for (let i = 0; i < indices.length; ++i) indices[i] = i < n ? i : random.int(n);
  return { vertices, indices, points };
}

function validChunk(geometry, format = 0, brick = 7) {
  const { vertices, indices, points } = geometry;
  return chunkMessage({
    vertexData: encodeVertices(vertices, format),
    indexData: encodeIndices(indices),
    pointData: encodeVertices(points, format),
    vertexCount: vertices.length / 4,
    triangleCount: indices.length / 3,
    pointCount: points.length / 4,
    brick,
  });
}

function refsMessage(frame, bricks, count = bricks.length) {
  const buffer = new ArrayBuffer(REFS_HEADER_BYTES + 4 * bricks.length);
  const view = new DataView(buffer);
  view.setUint8(0, MessageType.REFS);
  view.setUint8(1, PROTOCOL_VERSION);
  view.setUint32(4, frame, LE);
  view.setUint32(8, count, LE);
  bricks.forEach((brick, i) => view.setUint32(REFS_HEADER_BYTES + 4 * i, brick, LE));
  return buffer;
}

// The index codec keeps each triangle's winding but may rotate its corners: triangles compare
// as their least rotation.
function canonicalTriangles(indices) {
  const out = [];
  for (let i = 0; i < indices.length; i += 3) {
    const [a, b, c] = indices.slice(i, i + 3);
    // The least of the three rotations, compared whole: a random triangle may repeat its least
    // index ([23, 267, 23]), and the index codec may hand it back turned ([23, 23, 267]).
    const rotations = [[a, b, c], [b, c, a], [c, a, b]];
    const least = rotations.reduce((l, r) => (r[0] < l[0] || (r[0] === l[0] && (r[1] < l[1] || (r[1] === l[1] && r[2] < l[2]))) ? r : l));
    out.push(least.join(','));
  }
  return out;
}

// --- what every message must do ---------------------------------------------------------------

// The page's whole path for a binary message: what viewer.js and frames.js call, in that order.
function decodeAll(buffer) {
  const message = decodeServerMessage(buffer);
  if (message.type === MessageType.REFS) return { message };
  return { message, triangles: decodeTriangles(message), points: decodePoints(message) };
}

// Each allocation of a typed array of a given length (not the views decode.js makes of one),
// and each call into meshoptimizer's decoder, whose output buffer it sizes from the count.
const allocations = [];
function watchAllocations() {
  for (const name of ['Uint8Array', 'Uint16Array', 'Uint32Array']) {
    const original = globalThis[name];
    globalThis[name] = new Proxy(original, {
      construct(target, args) {
        if (typeof args[0] === 'number') allocations.push({ what: name, bytes: args[0] * target.BYTES_PER_ELEMENT });
        return Reflect.construct(target, args);
      },
    });
  }
  for (const name of ['decodeVertexBuffer', 'decodeIndexBuffer']) {
    const original = MeshoptDecoder[name];
    MeshoptDecoder[name] = (target, count, size, source) => {
      allocations.push({ what: name, bytes: count * size });
      return original(target, count, size, source);
    };
  }
}

// What a message of `bytes` can justify: 128 vertices per byte of vertex codec (protocol.js:
// minVertexBytes), 8 bytes each decoded. Every section is shorter than the message, so no one
// array may take more than 1024 times the message.
const MAX_BYTES_PER_MESSAGE_BYTE = 1024;
// Not a speed bound: a hang detector for one message of at most a few kilobytes (a decoder
// looping on a bogus count). The work a message can cause is bounded by the allocations check
// below; 250 ms here failed beside the sanitized suite on 2 busy cores (a truncated CHUNK: 372 ms).
const MAX_MS_PER_MESSAGE = 5000;

// Decodes `buffer` and checks the property; `label` says which case it was, for the failure.
// Returns whether the message decoded.
function check(buffer, label) {
  const where = `${label} (VDISO_FUZZ_SEED=${SEED})`;
  allocations.length = 0;
  const start = performance.now();
  let result;
  try {
    result = decodeAll(buffer);
  } catch (error) {
    assert.equal(Object.getPrototypeOf(error), Error.prototype, `${where}: threw ${error?.constructor?.name}: ${error?.message}`);
    assert.ok(typeof error.message === 'string' && error.message.length > 0, `${where}: an Error without a message`);
  }
  const ms = performance.now() - start;
  assert.ok(ms < MAX_MS_PER_MESSAGE, `${where}: took ${ms.toFixed(0)} ms`);
  for (const { what, bytes } of allocations) {
    assert.ok(
      bytes <= MAX_BYTES_PER_MESSAGE_BYTE * buffer.byteLength,
      `${where}: ${what} of ${bytes} bytes for a message of ${buffer.byteLength}`,
    );
  }
  if (!result) return false;
  const { message, triangles, points } = result;
  if (message.type === MessageType.REFS) {
    assert.equal(message.bricks.length, (buffer.byteLength - REFS_HEADER_BYTES) / 4, where);
    return true;
  }
  assert.equal(triangles.positions.length, 3 * message.vertexCount, where);
  assert.equal(triangles.normals.length, message.vertexCount, where);
  assert.equal(triangles.indices.length, 3 * message.triangleCount, where);
  assert.ok(triangles.indices.every((i) => i < message.vertexCount), where);
  assert.equal(points.length, 4 * message.pointCount, where);
  return true;
}

// Throws the Error that `check` allows, with a message matching `pattern`.
function refuses(buffer, pattern) {
  assert.throws(() => decodeAll(buffer), (error) => Object.getPrototypeOf(error) === Error.prototype && pattern.test(error.message));
}

// --- the tests --------------------------------------------------------------------------------

before(async () => {
  await Promise.all([MeshoptEncoder.ready, decoderReady]);
  watchAllocations();
});

test('valid CHUNKs round-trip exactly (vertex codec formats 0 and 1)', () => {
  const random = prng(SEED);
  const shapes = [
    { n: 3, t: 1, p: 0 },
    { n: 0, t: 0, p: 1 },
    { n: 300, t: 500, p: 0 },
    { n: 0, t: 0, p: 257 },
    { n: 1000, t: 1900, p: 700 },
    { n: 5000, t: 9000, p: 40, smooth: false },
  ];
  for (const format of [0, 1]) {
    for (const shape of shapes) {
      const geometry = randomGeometry(random, shape);
      const brick = shape.p > 100 ? TRANSIENT_BRICK : 12;
      const buffer = validChunk(geometry, format, brick);
      const chunk = decodeServerMessage(buffer);
      const label = `format ${format}, ${JSON.stringify(shape)} (VDISO_FUZZ_SEED=${SEED})`;
      assert.equal(chunk.type, MessageType.CHUNK);
      assert.equal(chunk.brick, brick);
      assert.equal(chunk.cacheable, brick !== TRANSIENT_BRICK);
      assert.deepEqual([chunk.vertexCount, chunk.triangleCount, chunk.pointCount], [shape.n, shape.t, shape.p]);
      assert.deepEqual(chunk.boxMax, [1, 2, 3]);
      const { positions, normals, indices } = decodeTriangles(chunk);
      for (let v = 0; v < shape.n; ++v) {
        assert.deepEqual([...positions.slice(3 * v, 3 * v + 3), normals[v]], [...geometry.vertices.slice(4 * v, 4 * v + 4)], label);
      }
      assert.deepEqual(canonicalTriangles(indices), canonicalTriangles(geometry.indices), label);
      assert.deepEqual(decodePoints(chunk), geometry.points, label);
      assert.ok(check(buffer, label));
    }
  }
});

test('valid REFS round-trip exactly', () => {
  for (const bricks of [[], [0], [1, 2, 0xfffffffe], Array.from({ length: 1000 }, (_, i) => 3 * i)]) {
    const refs = decodeServerMessage(refsMessage(9, bricks));
    assert.equal(refs.type, MessageType.REFS);
    assert.equal(refs.frame, 9);
    assert.deepEqual([...refs.bricks], bricks);
  }
});

test("the codecs' lower bounds are tight: meshoptimizer's encoder reaches them, never goes below", () => {
  const random = prng(SEED + 1);
  for (const n of [1, 15, 16, 255, 256, 257, 4096, 4097, 70000]) {
    // All-zero vertices are the vertex codec's smallest case (format 1: every channel zero).
    assert.equal(encodeVertices(new Uint16Array(4 * n), 1).length, minVertexBytes(n), `${n} zero vertices`);
    for (const format of [0, 1]) {
      const { vertices } = randomGeometry(random, { n, t: 0, p: 0, smooth: random() < 0.5 });
      assert.ok(encodeVertices(vertices, format).length >= minVertexBytes(n), `${n} vertices, format ${format}`);
    }
  }
  for (const t of [1, 2, 100, 5000]) {
    // A strip of new vertices costs one code byte per triangle, the index codec's smallest case.
    const strip = Uint32Array.from({ length: 3 * t }, (_, i) => i);
    assert.equal(encodeIndices(strip).length, minIndexBytes(t), `${t} triangles`);
    const { indices } = randomGeometry(random, { n: 50, t, p: 0 });
    assert.ok(encodeIndices(indices).length >= minIndexBytes(t), `${t} random triangles`);
  }
});

test('a CHUNK whose counts do not fit its bytes is refused before anything is decoded', () => {
  const random = prng(SEED + 2);
  const geometry = randomGeometry(random, { n: 200, t: 350, p: 90 });
  const sections = {
    vertexData: encodeVertices(geometry.vertices, 1),
    indexData: encodeIndices(geometry.indices),
    pointData: encodeVertices(geometry.points, 1),
  };
  const counts = { vertexCount: 200, triangleCount: 350, pointCount: 90 };
  const withCounts = (over) => chunkMessage({ ...sections, ...counts, ...over });
  assert.ok(check(withCounts({}), 'the valid chunk'));
  // One more item than the section can hold, by each codec's bound; then far more.
  const vertexRoom = 256 * ((sections.vertexData.length - 25) >> 1);
  refuses(withCounts({ vertexCount: vertexRoom + 1 }), /CHUNK of \d+ vertices has \d+ bytes of them, less than/);
  refuses(withCounts({ triangleCount: sections.indexData.length - 16 }), /CHUNK of \d+ triangles has \d+ bytes/);
  refuses(withCounts({ pointCount: 256 * ((sections.pointData.length - 25) >> 1) + 1 }), /CHUNK of \d+ points has/);
  for (const key of Object.keys(counts)) refuses(withCounts({ [key]: 0xffffffff }), /CHUNK of 4294967295 \w+/);
  // Counts the bytes allow pass the checks and reach the codec, which refuses them by an Error.
  refuses(withCounts({ vertexCount: vertexRoom }), /CHUNK vertices do not decode: /);
  refuses(withCounts({ pointCount: 91 }), /CHUNK points do not decode: /);
  refuses(withCounts({ triangleCount: 349 }), /CHUNK triangles do not decode: /);
  // An empty section has no bytes; vertices and triangles go together.
  refuses(withCounts({ pointCount: 0 }), /CHUNK of 0 points has \d+ bytes/);
  refuses(withCounts({ vertexCount: 0 }), /CHUNK of 0 vertices/);
  const noTriangles = chunkMessage({ vertexData: sections.vertexData, indexData: new Uint8Array(0), pointData: new Uint8Array(0), vertexCount: 200, triangleCount: 0, pointCount: 0 });
  refuses(noTriangles, /CHUNK of 200 vertices and 0 triangles/);
  // The cap, however many bytes there are.
  const big = (n) => chunkMessage({ vertexData: new Uint8Array(0), indexData: new Uint8Array(0), pointData: new Uint8Array(minVertexBytes(n)), vertexCount: 0, triangleCount: 0, pointCount: n });
  assert.equal(decodeServerMessage(big(CHUNK_MAX_COUNT)).pointCount, CHUNK_MAX_COUNT);
  refuses(big(CHUNK_MAX_COUNT + 1), new RegExp(`CHUNK of ${CHUNK_MAX_COUNT + 1} points: at most ${CHUNK_MAX_COUNT}`));
});

test("decode.js checks a chunk's counts itself, whoever made the chunk", () => {
  const random = prng(SEED + 3);
  const { vertices, indices } = randomGeometry(random, { n: 40, t: 60, p: 0 });
  const chunk = decodeServerMessage(validChunk({ vertices, indices, points: new Uint16Array(0) }, 1));
  allocations.length = 0;
  assert.throws(() => decodeTriangles({ ...chunk, vertexCount: 2 ** 31 }), /CHUNK of 2147483648 vertices: at most/);
  assert.throws(() => decodeTriangles({ ...chunk, vertexCount: 1e6 }), /CHUNK of 1000000 vertices has \d+ bytes of them, less than/);
  assert.throws(() => decodeTriangles({ ...chunk, triangleCount: 1e6 }), /CHUNK of 1000000 triangles has/);
  assert.throws(() => decodePoints({ ...chunk, pointCount: 1e6 }), /CHUNK of 1000000 points has 0 bytes/);
  assert.deepEqual(allocations, [], 'nothing allocated for any of them');
  // A corrupt header byte, past every count check: meshoptimizer's own refusal, as an Error.
  const vertexData = chunk.vertexData.slice();
  vertexData[0] = 0;
  assert.throws(() => decodeTriangles({ ...chunk, vertexData }), /^Error: CHUNK vertices do not decode: Malformed buffer data: -1$/);
  assert.throws(() => decodePoints({ ...chunk, pointCount: 1, pointData: chunk.vertexData }), /CHUNK points do not decode: Malformed buffer data: -3/);
});

test('every truncation of a valid CHUNK and REFS is refused by an Error', () => {
  const random = prng(SEED + 4);
  const chunk = validChunk(randomGeometry(random, { n: 120, t: 200, p: 60 }), 0);
  const refs = refsMessage(5, [1, 2, 3, 4, 5, 6]);
  for (const [name, buffer] of [['CHUNK', chunk], ['REFS', refs]]) {
    for (let length = 0; length < buffer.byteLength; ++length) {
      assert.equal(check(buffer.slice(0, length), `${name} cut to ${length} bytes`), false, `${name} cut to ${length} decoded`);
    }
  }
  // Each section cut short with the header's byte count told so: these reach the codec.
  const view = new DataView(chunk);
  const lengths = [60, 64, 68].map((offset) => view.getUint32(offset, LE));
  lengths.forEach((sectionBytes, s) => {
    for (let cut = 1; cut <= sectionBytes; ++cut) {
      const short = new Uint8Array(chunk.byteLength - cut);
      const start = CHUNK_HEADER_BYTES + lengths.slice(0, s).reduce((a, b) => a + b, 0);
      const end = start + sectionBytes;
      short.set(new Uint8Array(chunk, 0, end - cut));
      short.set(new Uint8Array(chunk, end), end - cut);
      new DataView(short.buffer).setUint32(60 + 4 * s, sectionBytes - cut, LE);
      check(short.buffer, `section ${s} cut by ${cut} bytes`);
    }
  });
});

test('random bytes, bit flips and random header counts: decoded to size or refused by an Error', (t) => {
  t.diagnostic(`VDISO_FUZZ_SEED=${SEED}`);
  const random = prng(SEED + 5);
  const pick = (array) => array[random.int(array.length)];
  // Counts near the codecs' bounds, small ones and huge ones.
  const randomCount = (sectionBytes) =>
    pick([
      () => random.int(8),
      () => random.int(256 * Math.max(1, sectionBytes)),
      () => Math.max(0, 128 * (sectionBytes - 25) + random.int(512) - 256),
      () => Math.max(0, sectionBytes - 17 + random.int(5) - 2),
      () => random.u32(),
      () => 0xffffffff - random.int(4),
      () => CHUNK_MAX_COUNT + random.int(3) - 1,
    ])();
  const valid = [];
  for (let i = 0; i < 8; ++i) {
    const n = 1 + random.int(400);
    const geometry = randomGeometry(random, { n, t: 1 + random.int(2 * n), p: random.int(300), smooth: random() < 0.7 });
    valid.push(validChunk(geometry, i % 2, random() < 0.5 ? TRANSIENT_BRICK : random.int(1000)));
  }
  valid.push(refsMessage(1, Array.from({ length: random.int(50) }, () => random.u32())));

  let decoded = 0;
  let cases = 0;
  const run = (buffer, label) => {
    ++cases;
    if (check(buffer, label)) ++decoded;
  };
  // Random bytes: as they come, and with a CHUNK or REFS header that the length agrees with.
  for (let i = 0; i < 4000; ++i) {
    const bytes = Uint8Array.from({ length: random.int(400) }, () => random.int(256));
    if (bytes.length >= 4 && random() < 0.8) {
      bytes[0] = random() < 0.7 ? MessageType.CHUNK : MessageType.REFS;
      bytes[1] = PROTOCOL_VERSION;
    }
    const view = new DataView(bytes.buffer);
    if (bytes[0] === MessageType.REFS && bytes.length >= REFS_HEADER_BYTES && random() < 0.5) {
      view.setUint32(8, (bytes.length - REFS_HEADER_BYTES) >> 2, LE);
    }
    if (bytes[0] === MessageType.CHUNK && bytes.length >= CHUNK_HEADER_BYTES && random() < 0.7) {
      // Split the payload into three sections, with counts from their sizes; sometimes a
      // codec's header byte in front (vertex: 0xa0 | format, index: 0xe1).
      const payload = bytes.length - CHUNK_HEADER_BYTES;
      const a = random.int(payload + 1);
      const b = random.int(payload - a + 1);
      let offset = CHUNK_HEADER_BYTES;
      [a, b, payload - a - b].forEach((size, s) => {
        view.setUint32(60 + 4 * s, size, LE);
        view.setUint32(48 + 4 * s, randomCount(size), LE);
        if (size > 0 && random() < 0.8) bytes[offset] = s === 1 ? 0xe1 : 0xa0 | random.int(2);
        offset += size;
      });
      view.setUint16(2, view.getUint32(12, LE) === TRANSIENT_BRICK ? 0 : CHUNK_FLAG_CACHEABLE, LE);
    }
    run(bytes.buffer, `random message ${i}`);
  }
  // Bit flips of valid messages: header and sections alike.
  for (let i = 0; i < 3000; ++i) {
    const source = pick(valid);
    const bytes = new Uint8Array(source.slice(0));
    for (let f = 1 + random.int(3); f > 0; --f) {
      const at = random() < 0.3 ? random.int(Math.min(bytes.length, CHUNK_HEADER_BYTES)) : random.int(bytes.length);
      bytes[at] ^= 1 << random.int(8);
    }
    run(bytes.buffer, `bit flip ${i} of valid message ${valid.indexOf(source)}`);
  }
  // Random header counts on valid sections.
  for (let i = 0; i < 2000; ++i) {
    const source = pick(valid.slice(0, -1));
    const bytes = new Uint8Array(source.slice(0));
    const view = new DataView(bytes.buffer);
    const s = random.int(3);
    view.setUint32(48 + 4 * s, randomCount(view.getUint32(60 + 4 * s, LE)), LE);
    run(bytes.buffer, `header count ${s} of valid chunk ${valid.indexOf(source)} set to ${view.getUint32(48 + 4 * s, LE)}`);
  }
  // REFS with random counts.
  for (let i = 0; i < 500; ++i) {
    const bricks = Array.from({ length: random.int(20) }, () => random.u32());
    run(refsMessage(i, bricks, random() < 0.2 ? bricks.length : pick([random.int(30), random.u32(), 0xffffffff])), `REFS ${i}`);
  }
  // Most are refused; bit flips of coded values, and REFS, still decode sometimes.
  assert.ok(decoded > 0 && decoded < cases, `${decoded} of ${cases} decoded (VDISO_FUZZ_SEED=${SEED})`);
});
