// The page's entry point: connects to `vdiso serve`, sends the camera and isovalue whenever
// they change (at most once per displayed frame), draws the frames as they stream in, and
// exposes window.vdisoViewer, the page's scriptable interface (documented in the README).
//
// URL parameters: token (access), store (by name), iso, eye, target, up (x,y,z in world
// units), fov (vertical, degrees), cacheMb (client cache budget), overlay=0 (hide overlays),
// follow=ID (show session ID's frames: follow mode, docs/protocol.md).
import { ChunkCache } from './cache.js';
import { CameraController, presetCamera } from './camera.js';
import { Connection, webSocketUrl } from './connection.js';
import { decoderReady } from './decode.js';
import { Follow } from './follow.js';
import { FrameAssembler } from './frames.js';
import { Overlay } from './overlay.js';
import { Panel } from './panel.js';
import {
  MessageType, PROTOCOL_VERSION, VIEWPORT_MAX, VIEWPORT_MIN, decodeServerMessage, encodeEvict, encodeHandOver, encodeView,
} from './protocol.js';
import { SurfaceScene, fitClipPlanes } from './scene.js';

const DEFAULT_CACHE_MB = 512;

function parseVec3(params, name) {
  const text = params.get(name);
  if (text === null) return undefined;
  const value = text.split(',').map(Number);
  if (value.length !== 3 || !value.every(Number.isFinite)) throw new Error(`URL parameter ${name}=${text} is not x,y,z`);
  return value;
}

function parseNumber(params, name) {
  const text = params.get(name);
  if (text === null) return undefined;
  const value = Number(text);
  if (text.trim() === '' || !Number.isFinite(value)) throw new Error(`URL parameter ${name}=${text} is not a number`);
  return value;
}

const clampViewport = (n) => Math.min(Math.max(n, VIEWPORT_MIN), VIEWPORT_MAX);

class Viewer {
  constructor(params) {
    this.params = params;
    const canvas = document.getElementById('view');
    this.scene = new SurfaceScene(canvas);
    this.cameraController = new CameraController(this.scene.camera, canvas, () => this.viewChanged());
    const cacheMb = parseNumber(params, 'cacheMb') ?? DEFAULT_CACHE_MB;
    if (!(cacheMb > 0)) throw new Error(`URL parameter cacheMb=${cacheMb} must be positive`);
    this.cache = new ChunkCache(cacheMb * 2 ** 20, (entry) => this.frames.releaseEntry(entry));
    this.frames = new FrameAssembler(this.scene, this.cache, (messages) => this.sendEvictions(messages));
    this.overlay = new Overlay(
      document.getElementById('stats'),
      document.getElementById('error'),
      document.getElementById('banner'),
    );
    this.panel = new Panel(
      {
        store: document.getElementById('store'),
        storeRow: document.getElementById('store-row'),
        slider: document.getElementById('iso-slider'),
        isoInput: document.getElementById('iso-value'),
        histogram: document.getElementById('histogram'),
        presets: document.getElementById('presets'),
      },
      {
        store: (index) => this.selectStore(index),
        iso: (value) => this.setIso(value),
        preset: (name) => this.applyPreset(name),
      },
    );
    this.follow = new Follow(
      {
        state: document.getElementById('follow-state'),
        link: document.getElementById('follow-link'),
        copy: document.getElementById('copy-link'),
        handOver: document.getElementById('hand-over'),
      },
      params.get('follow'),
      () => this.handOver(),
    );
    document.body.classList.toggle('no-overlay', params.get('overlay') === '0');
    window.addEventListener('keydown', (event) => {
      if (event.key === 'o' && !event.target.closest('input, select')) document.body.classList.toggle('no-overlay');
    });
    window.addEventListener('resize', () => {
      if (this.scene.resize()) this.viewChanged();
      this.needsRender = true; // resizing the canvas, even to its size, clears it
    });

    this.stores = [];
    this.storeIndex = -1;
    this.iso = NaN;
    this.seq = 0; // the newest VIEW sent
    this.sentAt = new Map(); // VIEW seq -> performance.now() when sent
    this.viewDirty = false;
    this.needsRender = true;
    this.drawnFrame = null; // the complete frame drawn by the last render
    this.waiters = []; // frameComplete() calls not answered yet: { resolve, reject }
    this.closed = false;
    this.ready = new Promise((resolve, reject) => (this.readyHandlers = { resolve, reject }));
    this.roleChanged();
  }

  async start() {
    await decoderReady;
    this.connection = new Connection(webSocketUrl(window.location, this.params.get('follow')), {
      text: (text) => this.guard(() => this.onText(JSON.parse(text))),
      binary: (buffer) => this.guard(() => this.onBinary(buffer)),
      close: (event) => this.onClose(event),
    });
    const tick = () => {
      requestAnimationFrame(tick);
      this.tick();
    };
    requestAnimationFrame(tick);
  }

  // A message that cannot be handled is reported; the connection and the page go on.
  guard(handle) {
    try {
      handle();
    } catch (error) {
      this.reportError(error.message);
    }
  }

  reportError(message) {
    console.error(`vdiso viewer: ${message}`);
    this.overlay.flashError(message);
  }

  onText(message) {
    switch (message.type) {
      case 'hello':
        return this.onHello(message);
      case 'frameBegin':
        if (this.follow.following) this.showLeadersView(message);
        this.frames.begin(message, this.sentAt.get(message.frame));
        for (const seq of this.sentAt.keys()) if (seq < message.frame) this.sentAt.delete(seq);
        return;
      case 'role':
        this.follow.role(message);
        return this.roleChanged(message.seq);
      case 'frameEnd':
        return this.onFrameEnd(this.frames.end(message));
      case 'evicted':
        return this.cache.evicted(message.seq);
      case 'error':
        if (this.follow.waiting && message.message.startsWith('follow:')) {
          this.follow.refused();
          this.roleChanged();
        }
        // A refused VIEW (named by its seq) gets no frame: whoever waits for it hears why.
        if (message.seq === this.seq) {
          for (const waiter of this.waiters.splice(0)) waiter.reject(new Error(`server: ${message.message}`));
        }
        return this.reportError(`server: ${message.message}`);
      default:
        throw new Error(`unknown message type '${message.type}'`);
    }
  }

  onBinary(buffer) {
    const message = decodeServerMessage(buffer);
    if (message.type === MessageType.CHUNK) this.frames.chunk(message);
    else this.frames.refs(message);
    this.needsRender = true;
  }

  onHello(hello) {
    if (hello.version !== PROTOCOL_VERSION) throw new Error(`server speaks protocol ${hello.version}, this page ${PROTOCOL_VERSION}`);
    if (!Array.isArray(hello.stores) || hello.stores.length === 0) throw new Error('the server offers no store');
    this.stores = hello.stores;
    this.panel.setStores(this.stores);
    this.follow.hello(hello.session);
    try {
      const name = this.params.get('store');
      const index = name === null ? 0 : this.stores.findIndex((store) => store.name === name);
      if (index < 0) throw new Error(`no store named '${name}' (the server has ${this.stores.map((s) => s.name).join(', ')})`);
      const eye = parseVec3(this.params, 'eye');
      const target = parseVec3(this.params, 'target');
      const up = parseVec3(this.params, 'up');
      const fov = parseNumber(this.params, 'fov');
      this.selectStore(index, { eye, target, up, fov }, parseNumber(this.params, 'iso'));
      this.readyHandlers.resolve({ stores: this.stores.map(({ name, boundsMin, boundsMax, valueMin, valueMax, iso }) => ({ name, boundsMin, boundsMax, valueMin, valueMax, iso })) });
    } catch (error) {
      this.readyHandlers.reject(error);
      throw error;
    }
  }

  // Shows store `index`: its default isovalue (or `iso`) and its normal preset, where `camera`
  // does not say otherwise.
  selectStore(index, camera = {}, iso = undefined) {
    const store = this.stores[index];
    this.storeIndex = index;
    this.panel.setStore(index, store);
    const preset = presetCamera('normal', store.boundsMin, store.boundsMax, this.scene.camera.aspect, store.facing);
    this.cameraController.set({
      eye: camera.eye ?? preset.eye,
      target: camera.target ?? preset.target,
      up: camera.up ?? preset.up,
      fov: camera.fov ?? preset.fov,
    });
    this.setIso(iso ?? store.iso);
  }

  applyPreset(name) {
    if (this.storeIndex < 0) return;
    const store = this.stores[this.storeIndex];
    this.cameraController.set(presetCamera(name, store.boundsMin, store.boundsMax, this.scene.camera.aspect, store.facing));
  }

  // For the scripting interface: the store (and so the camera and isovalue) is chosen at hello.
  requireReady() {
    if (this.storeIndex < 0) throw new Error('the viewer is not ready yet: await vdisoViewer.ready first');
  }

  setIso(value) {
    this.requireReady();
    const store = this.stores[this.storeIndex];
    if (!(value >= store.valueMin && value <= store.valueMax)) {
      throw new Error(`isovalue ${value} is outside the store's range [${store.valueMin}, ${store.valueMax}]`);
    }
    this.iso = value;
    this.panel.setIso(value);
    this.viewDirty = true;
  }

  viewChanged() {
    if (this.storeIndex >= 0) {
      const store = this.stores[this.storeIndex];
      fitClipPlanes(this.scene.camera, this.cameraController.target(), store.boundsMin, store.boundsMax);
    }
    this.viewDirty = true;
    this.needsRender = true;
  }

  sendView() {
    const size = this.scene.drawingBufferSize();
    const camera = this.cameraController.get();
    this.seq += 1;
    this.connection.send(
      encodeView({
        seq: this.seq,
        store: this.storeIndex,
        width: clampViewport(size.x),
        height: clampViewport(size.y),
        ...camera,
        iso: this.iso,
      }),
    );
    this.sentAt.set(this.seq, performance.now());
    this.viewDirty = false;
  }

  // Follow mode: the page shows the leader's frames with the leader's camera, store and
  // isovalue, and sends no VIEW; leading (again), it sends its view, numbered after the
  // group's last frame (`seq` of the role message).
  roleChanged(seq = 0) {
    const following = this.follow.following;
    this.cameraController.setEnabled(!following);
    this.panel.setEnabled(!following);
    if (!following) this.seq = Math.max(this.seq, seq);
    if (this.wasFollowing && !following) this.viewDirty = this.storeIndex >= 0;
    this.wasFollowing = following;
  }

  showLeadersView(begin) {
    if (begin.store !== this.storeIndex && this.stores[begin.store]) {
      this.storeIndex = begin.store;
      this.panel.setStore(begin.store, this.stores[begin.store]);
    }
    this.iso = begin.iso;
    this.panel.setIso(begin.iso);
    if (begin.view) this.cameraController.set(begin.view);
    this.seq = begin.frame;
    this.sentAt.set(begin.frame, this.sentAt.get(begin.frame) ?? performance.now());
    this.viewDirty = false;
  }

  handOver(to = undefined) {
    this.connection.send(encodeHandOver(to));
  }

  sendEvictions(messages) {
    for (const message of messages) this.connection.send(encodeEvict(message));
  }

  onFrameEnd(frame) {
    const stats = frame.stats();
    if (stats.missingRefs > 0) {
      this.reportError(`frame ${stats.frame}: REFS named ${stats.missingRefs} chunks this page never had (a server bug)`);
    } else if (stats.status === 'complete' && (stats.triangles !== stats.serverTriangles || stats.points !== stats.serverPoints)) {
      this.reportError(
        `frame ${stats.frame}: drew ${stats.triangles} triangles and ${stats.points} points, the server counts ` +
          `${stats.serverTriangles} and ${stats.serverPoints}`,
      );
    }
    this.needsRender = true;
  }

  onClose(event) {
    this.closed = true;
    const reason = event.reason ? `: ${event.reason}` : '';
    const message = `Connection to the server lost (code ${event.code}${reason}). Reload the page to reconnect.`;
    console.error(`vdiso viewer: ${message}`);
    this.overlay.showBanner(message);
    this.readyHandlers.reject(new Error(message));
    for (const waiter of this.waiters.splice(0)) waiter.reject(new Error(message));
  }

  // Once per displayed frame: send the view if it changed, draw if anything changed (always
  // while a frame streams in), answer frameComplete() once its frame is on screen, and show
  // the stats of what is drawn.
  tick() {
    if (this.viewDirty && this.follow.following) this.viewDirty = false; // the leader's view is drawn
    if (this.viewDirty && this.storeIndex >= 0 && !this.closed) this.sendView();
    const streaming = this.frames.streaming;
    if (this.needsRender || streaming) {
      this.scene.render();
      this.needsRender = false;
      this.drawnFrame = this.frames.complete;
      this.answerWaiters();
      const shown = streaming ?? this.frames.complete ?? this.frames.partial;
      if (shown) this.overlay.showFrame(shown.stats(), this.cache);
    }
  }

  // The frame for the current camera and isovalue, complete and drawn, or null.
  settledFrame() {
    const frame = this.drawnFrame;
    if (this.viewDirty || !frame || frame !== this.frames.complete || frame.seq !== this.seq) return null;
    if (frame.end && frame.end.final === false) return null; // a coarse frame: the final one follows
    return frame;
  }

  answerWaiters() {
    const frame = this.settledFrame();
    if (!frame || this.waiters.length === 0) return;
    const stats = frame.stats();
    for (const waiter of this.waiters.splice(0)) waiter.resolve(stats);
  }

  frameComplete() {
    if (this.closed) return Promise.reject(new Error('the connection to the server is closed'));
    const frame = this.settledFrame();
    if (frame) return Promise.resolve(frame.stats());
    return new Promise((resolve, reject) => this.waiters.push({ resolve, reject }));
  }
}

const viewer = new Viewer(new URLSearchParams(window.location.search));

// The page's public interface: see the README ("Looking from a browser").
window.vdisoViewer = {
  ready: viewer.ready,
  // {eye, target, up, fov}: arrays of 3 numbers in world units, vertical fov in degrees.
  setCamera(camera) {
    viewer.requireReady();
    viewer.cameraController.set(camera);
  },
  getCamera() {
    viewer.requireReady();
    return viewer.cameraController.get();
  },
  setIso: (value) => viewer.setIso(value),
  frameComplete: () => viewer.frameComplete(),
  // Follow mode: { session, leader, followers, following }, the link that follows this page's
  // group, and the hand-over of control (to a follower's session id; none: the first).
  role: () => viewer.follow.snapshot(),
  followLink: () => viewer.follow.link(),
  handOver: (to) => viewer.handOver(to),
};

viewer.start().catch((error) => viewer.reportError(error.message));
