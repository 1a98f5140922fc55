// Frames as they stream in (docs/protocol.md, "A frame"): which chunks make each frame, and
// which are drawn meanwhile.
//
// Drawn at any time: the last complete frame, the newest superseded one (valid surface, just
// not all of it) and the frame streaming in, each new chunk as it arrives, so the near
// surface shows first. A frame ending complete replaces them all: exactly its chunks are
// drawn. A frame of another store or isovalue hides the others as soon as its first geometry
// arrives, so two isosurfaces are never mixed.
import { chunkKey } from './cache.js';
import { decodePoints, decodeTriangles } from './decode.js';

// GPU bytes of a chunk as drawn: 6 + 2 bytes a triangle vertex (scene.js), 4 an index, 8 a point.
function gpuBytes(chunk) {
  return 8 * chunk.vertexCount + 12 * chunk.triangleCount + 8 * chunk.pointCount;
}

class Frame {
  constructor({ frame, store, iso }, sentAt) {
    this.seq = frame;
    this.store = store;
    this.iso = iso;
    this.sentAt = sentAt; // performance.now() when its VIEW went out
    this.firstGeometryAt = null;
    this.endedAt = null;
    this.end = null; // the frameEnd message
    this.chunks = new Set(); // cache entries named by its CHUNKs and REFS
    this.transients = []; // entries of its transient chunks, freed with the frame
    this.bytes = 0; // binary bytes received for it
    this.chunkMessages = 0;
    this.refs = 0;
    this.missingRefs = 0;
  }

  *entries() {
    yield* this.chunks;
    yield* this.transients;
  }

  get status() {
    return this.end ? this.end.status : 'streaming';
  }

  sameSurface(other) {
    return other.store === this.store && other.iso === this.iso;
  }

  // What frameComplete() resolves with and the overlay shows.
  stats() {
    let triangles = 0;
    let points = 0;
    for (const entry of this.entries()) {
      triangles += entry.triangleCount;
      points += entry.pointCount;
    }
    const since = (t) => (t === null || this.sentAt === undefined ? null : Math.round(10 * (t - this.sentAt)) / 10);
    const end = this.end ?? {};
    return {
      frame: this.seq,
      status: this.status,
      // Levels of detail: the coarse frame of a VIEW comes first (final false), the final after.
      lodError: end.lodError ?? null,
      final: end.final ?? true,
      store: this.store,
      iso: this.iso,
      triangles,
      points,
      bytes: this.bytes,
      firstGeometryMs: since(this.firstGeometryAt),
      completeMs: since(this.endedAt),
      chunks: this.chunkMessages,
      refs: this.refs,
      missingRefs: this.missingRefs,
      bricksRead: end.bricksRead ?? null,
      bricksVisited: end.bricksVisited ?? null,
      serverMs: end.serverMs ?? null,
      serverFirstChunkMs: end.firstChunkMs ?? null,
      serverTriangles: end.triangles ?? null,
      serverPoints: end.points ?? null,
      serverBytes: end.bytes ?? null,
    };
  }
}

export class FrameAssembler {
  // scene: SurfaceScene; cache: ChunkCache; sendEvictions(messages) sends EVICTs;
  // now() is the clock that VIEW send times are taken with.
  constructor(scene, cache, sendEvictions, now = () => performance.now()) {
    this.scene = scene;
    this.cache = cache;
    this.sendEvictions = sendEvictions;
    this.now = now;
    this.complete = null; // the last frame that ended complete, if still drawn
    this.partial = null; // the newest superseded frame, drawn until a frame completes
    this.streaming = null;
    this.visible = new Set(); // entries drawn now; the cache never evicts these
  }

  begin(message, sentAt) {
    const unended = this.streaming;
    this.streaming = new Frame(message, sentAt);
    if (unended) {
      // A protocol error, but the new frame is still drawn right: the old one counts as superseded.
      this.partial = unended;
      this.updateVisibility();
      throw new Error(`frameBegin ${message.frame} while frame ${unended.seq} had not ended`);
    }
  }

  chunk(chunk) {
    const frame = this.frameOf(chunk, 'CHUNK');
    if (chunk.store !== frame.store || chunk.iso !== frame.iso) {
      throw new Error(`CHUNK of store ${chunk.store} iso ${chunk.iso} in frame ${frame.seq} of store ${frame.store} iso ${frame.iso}`);
    }
    frame.bytes += chunk.byteLength;
    frame.chunkMessages += 1;
    this.noteGeometry(frame);
    let entry;
    if (chunk.cacheable) {
      const key = chunkKey(chunk.store, chunk.iso, chunk.brick);
      // The server may send again what it was told is evicted while the client took it back.
      entry = this.cache.get(key);
      if (entry) this.cache.touch(entry);
      else this.cache.add((entry = this.createEntry(key, chunk)));
      frame.chunks.add(entry);
    } else {
      entry = this.createEntry(null, chunk);
      frame.transients.push(entry);
    }
    this.show(entry);
    this.sendEvictions(this.cache.evictOverBudget(this.visible));
  }

  refs(refs) {
    const frame = this.frameOf(refs, 'REFS');
    frame.bytes += refs.byteLength;
    frame.refs += refs.bricks.length;
    this.noteGeometry(frame);
    for (const brick of refs.bricks) {
      const entry = this.cache.get(chunkKey(frame.store, frame.iso, brick));
      if (!entry) {
        frame.missingRefs += 1;
        continue;
      }
      this.cache.touch(entry);
      frame.chunks.add(entry);
      this.show(entry);
    }
  }

  // Returns the frame that ended.
  end(message) {
    const frame = this.streaming;
    if (!frame || frame.seq !== message.frame) {
      throw new Error(`frameEnd ${message.frame} for a frame that is not streaming (${frame ? frame.seq : 'none'})`);
    }
    frame.end = message;
    frame.endedAt = this.now();
    this.streaming = null;
    if (message.status === 'complete') {
      this.complete = frame;
      this.partial = null;
    } else {
      this.partial = frame;
    }
    this.updateVisibility();
    return frame;
  }

  frameOf(message, what) {
    const frame = this.streaming;
    if (!frame || frame.seq !== message.frame) {
      throw new Error(`${what} for frame ${message.frame} outside it (streaming: ${frame ? frame.seq : 'none'})`);
    }
    return frame;
  }

  noteGeometry(frame) {
    if (frame.firstGeometryAt !== null) return;
    frame.firstGeometryAt = this.now();
    let changed = false;
    if (this.complete && !this.complete.sameSurface(frame)) {
      this.complete = null;
      changed = true;
    }
    if (this.partial && !this.partial.sameSurface(frame)) {
      this.partial = null;
      changed = true;
    }
    if (changed) this.updateVisibility();
  }

  createEntry(key, chunk) {
    const entry = {
      key,
      store: chunk.store,
      iso: chunk.iso,
      brick: chunk.brick,
      triangleCount: chunk.triangleCount,
      pointCount: chunk.pointCount,
      bytes: gpuBytes(chunk),
      triangles: null,
      points: null,
      visible: true,
      evictSeq: 0,
    };
    if (chunk.triangleCount > 0) {
      entry.triangles = this.scene.triangles.add(decodeTriangles(chunk), chunk.boxMin, chunk.boxMax);
    }
    if (chunk.pointCount > 0) {
      entry.points = this.scene.addPoints(decodePoints(chunk), chunk.boxMin, chunk.boxMax);
    }
    return entry;
  }

  releaseEntry(entry) {
    if (entry.triangles) this.scene.triangles.remove(entry.triangles);
    if (entry.points) this.scene.removePoints(entry.points);
  }

  setVisible(entry, visible) {
    if (entry.visible === visible) return;
    entry.visible = visible;
    if (entry.triangles) this.scene.triangles.setVisible(entry.triangles, visible);
    if (entry.points) entry.points.visible = visible;
  }

  show(entry) {
    this.setVisible(entry, true);
    this.visible.add(entry);
  }

  // Draws exactly the entries of the frames still drawn; frees the transients of the others.
  updateVisibility() {
    const drawn = new Set();
    for (const frame of [this.complete, this.partial, this.streaming]) {
      if (frame) for (const entry of frame.entries()) drawn.add(entry);
    }
    for (const entry of this.visible) {
      if (drawn.has(entry)) continue;
      if (entry.key === null) this.releaseEntry(entry);
      else this.setVisible(entry, false);
    }
    for (const entry of drawn) this.setVisible(entry, true);
    this.visible = drawn;
  }
}
