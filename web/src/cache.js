// The client's chunk cache: cacheable chunks kept by what they hold, (store, iso, brick), under
// a byte budget, least recently used first out, with the EVICT handshake of docs/protocol.md.
//
// An evicted chunk is not freed at once: until the server answers {"type":"evicted"} a REFS
// it sent before seeing the EVICT may still name the chunk, and the chunk is then taken back.
import { EVICT_MAX_BRICKS } from './protocol.js';

// The iso is the f64 the server sent; its shortest decimal form names it exactly.
const LOW_WATER = 0.9;

export function chunkKey(store, iso, brick) {
  return `${store}:${iso}:${brick}`;
}

export class ChunkCache {
  // release(entry) frees an entry's GPU data once the server has confirmed its eviction.
  constructor(budgetBytes, release) {
    this.budgetBytes = budgetBytes;
    this.release = release;
    this.live = new Map(); // key -> entry, least recently used first
    this.liveBytes = 0;
    this.evicting = new Map(); // key -> entry sent in an EVICT not answered yet
    this.evictingBytes = 0;
    this.evictionsBySeq = new Map(); // EVICT seq -> its entries
    this.nextEvictSeq = 1;
  }

  // The entry under `key`, taken back if it was being evicted; undefined if not held.
  get(key) {
    const live = this.live.get(key);
    if (live) return live;
    const evicting = this.evicting.get(key);
    if (!evicting) return undefined;
    this.evicting.delete(key);
    this.evictingBytes -= evicting.bytes;
    evicting.evictSeq = 0; // its EVICT's answer must no longer free it
    this.add(evicting);
    return evicting;
  }

  // entry: { key, store, iso, brick, bytes, ... }; becomes the most recently used.
  add(entry) {
    this.live.set(entry.key, entry);
    this.liveBytes += entry.bytes;
  }

  touch(entry) {
    this.live.delete(entry.key);
    this.live.set(entry.key, entry);
  }

  // Evicts least recently used entries not in `inUse` (a Set of entries) until the live bytes
  // are 10% under the budget, so that evictions go out in batches rather than one message
  // per chunk that arrives. Returns the EVICT messages to send: [{ seq, store, iso, bricks }], one
  // per (store, iso) and at most EVICT_MAX_BRICKS bricks each.
  evictOverBudget(inUse) {
    if (this.liveBytes <= this.budgetBytes) return [];
    const goal = LOW_WATER * this.budgetBytes;
    const groups = new Map();
    for (const entry of this.live.values()) {
      if (this.liveBytes <= goal) break;
      if (inUse.has(entry)) continue;
      this.live.delete(entry.key);
      this.liveBytes -= entry.bytes;
      this.evicting.set(entry.key, entry);
      this.evictingBytes += entry.bytes;
      const groupKey = `${entry.store}:${entry.iso}`;
      if (!groups.has(groupKey)) groups.set(groupKey, []);
      groups.get(groupKey).push(entry);
    }
    const messages = [];
    for (const entries of groups.values()) {
      for (let first = 0; first < entries.length; first += EVICT_MAX_BRICKS) {
        const batch = entries.slice(first, first + EVICT_MAX_BRICKS);
        const seq = this.nextEvictSeq++;
        for (const entry of batch) entry.evictSeq = seq;
        this.evictionsBySeq.set(seq, batch);
        messages.push({ seq, store: batch[0].store, iso: batch[0].iso, bricks: batch.map((e) => e.brick) });
      }
    }
    return messages;
  }

  // The server's {"type":"evicted","seq":seq}: frees that EVICT's entries not taken back since.
  evicted(seq) {
    const batch = this.evictionsBySeq.get(seq);
    if (!batch) throw new Error(`"evicted" answers EVICT ${seq}, which was never sent or was answered already`);
    this.evictionsBySeq.delete(seq);
    for (const entry of batch) {
      if (entry.evictSeq !== seq) continue;
      this.evicting.delete(entry.key);
      this.evictingBytes -= entry.bytes;
      this.release(entry);
    }
  }
}
