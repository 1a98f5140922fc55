// The small per-frame overlay (a corner of the page), server errors flashed in it, and a
// banner, always shown, when the connection is lost.

const ERROR_SHOWN_MS = 6000;

function megabytes(bytes) {
  return `${(bytes / 2 ** 20).toFixed(bytes < 2 ** 20 ? 2 : 1)} MB`;
}

function milliseconds(ms) {
  return ms === null ? '-' : `${Math.round(ms)} ms`;
}

function count(n) {
  return n === null ? '-' : n.toLocaleString('en-US');
}

export class Overlay {
  constructor(statsElement, errorElement, bannerElement) {
    this.statsElement = statsElement;
    this.errorElement = errorElement;
    this.bannerElement = bannerElement;
    this.errorTimer = null;
  }

  // stats: a frame's stats (frames.js); cache: the ChunkCache.
  showFrame(stats, cache) {
    const lines = [
      `frame ${stats.frame} ${stats.status}${stats.final === false ? ' (coarse, refining)' : ''}` +
        (stats.lodError ? `  lod error ${stats.lodError} px` : ''),
      `triangles ${count(stats.triangles)}  points ${count(stats.points)}`,
      `received ${megabytes(stats.bytes)}  (${count(stats.chunks)} chunks, ${count(stats.refs)} refs)`,
      `first geometry ${milliseconds(stats.firstGeometryMs)}  complete ${milliseconds(stats.completeMs)}`,
      `bricks read from disk ${count(stats.bricksRead)}`,
      `cache ${megabytes(cache.liveBytes)} of ${megabytes(cache.budgetBytes)}`,
    ];
    if (stats.missingRefs > 0) lines.push(`missing refs ${count(stats.missingRefs)}`);
    this.statsElement.textContent = lines.join('\n');
  }

  flashError(message) {
    this.errorElement.textContent = message;
    this.errorElement.hidden = false;
    clearTimeout(this.errorTimer);
    this.errorTimer = setTimeout(() => (this.errorElement.hidden = true), ERROR_SHOWN_MS);
  }

  showBanner(message) {
    this.bannerElement.textContent = message;
    this.bannerElement.hidden = false;
  }
}
