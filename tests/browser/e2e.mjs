#!/usr/bin/env node
// The viewer end to end: Debian's chromium, headless, WebGL on SwiftShader, driven by
// puppeteer-core (installed in web/node_modules by `npm ci` there), against a running
// `vdiso serve`.
//
//   node tests/browser/e2e.mjs --url URL --camera CAM.json --size 800x800 --out SHOT.png
//                              [--iso V] [--store NAME] [--orbit N] [--timeout S] [--page PAGE.png]
//                              [--follow-out FOLLOWER.png]
//
// Opens URL (the one the server printed, with its token) at the camera of CAM.json
// ({"eye":[x,y,z],"target":[x,y,z],"up":[x,y,z],"fov":30}) with the overlay hidden, waits
// for window.vdisoViewer.frameComplete(), screenshots the canvas alone to SHOT.png and prints
// the frame's stats as one JSON line (--page: also the whole page with its overlays). With --orbit N it then turns the camera about its up
// axis through the target in N equal steps (as `vdiso extract --path orbit` does about +z),
// printing one JSON line of stats per frame ("step": 0..N-1; step 0 is CAM.json itself).
// With --follow-out, a second page opens the first one's follow link (follow mode): its first
// frame (screenshot to FOLLOWER.png) and the one after the leader turns must be the leader's;
// then the leader hands over control, and the follower's next view must reach the first page.
// Exits non-zero on a page error, a console error, a failed request or the timeout
// (60 s by default, for the whole run).
import fs from 'node:fs';
import { createRequire } from 'node:module';

const require = createRequire(new URL('../../web/package.json', import.meta.url));
const puppeteer = require('puppeteer-core');

const CHROMIUM = process.env.CHROMIUM ?? '/usr/bin/chromium';
const CHROMIUM_ARGS = [
  // WebGL2 in software, the same on every machine; without the "unsafe" flag chromium
  // refuses SwiftShader for WebGL.
  '--use-angle=swiftshader',
  '--enable-unsafe-swiftshader',
  '--ignore-gpu-blocklist',
  // The machine has no network beyond loopback: keep chromium from trying.
  '--disable-background-networking',
  '--disable-component-update',
  '--disable-sync',
  '--disable-quic',
  '--no-first-run',
  // Root has no usable sandbox here (CI and developer machines run as root).
  ...(process.getuid?.() === 0 ? ['--no-sandbox'] : []),
];

function usage(message) {
  console.error(`e2e: ${message}`);
  console.error('usage: node tests/browser/e2e.mjs --url URL --camera CAM.json --size WxH --out SHOT.png [--iso V] [--store NAME] [--orbit N] [--timeout S]');
  process.exit(2);
}

function parseArgs(argv) {
  const options = { timeout: '60' };
  for (let i = 0; i < argv.length; i += 2) {
    if (!argv[i].startsWith('--') || argv[i + 1] === undefined) usage(`bad argument '${argv[i]}'`);
    options[argv[i].slice(2)] = argv[i + 1];
  }
  for (const required of ['url', 'camera', 'size']) if (!options[required]) usage(`--${required} is required`);
  if (!options.out && !options.orbit) usage('--out is required (or --orbit N)');
  const size = /^(\d+)x(\d+)$/.exec(options.size);
  if (!size) usage(`--size ${options.size} is not WxH`);
  options.width = Number(size[1]);
  options.height = Number(size[2]);
  options.orbit = options.orbit === undefined ? 0 : Number(options.orbit);
  if (!Number.isInteger(options.orbit) || options.orbit < 0) usage('--orbit takes a whole number of frames');
  options.timeout = Number(options.timeout);
  return options;
}

function readCamera(file) {
  const camera = JSON.parse(fs.readFileSync(file, 'utf8'));
  for (const key of ['eye', 'target', 'up']) {
    if (!Array.isArray(camera[key]) || camera[key].length !== 3) throw new Error(`${file}: "${key}" must be [x, y, z]`);
  }
  if (typeof camera.fov !== 'number') throw new Error(`${file}: "fov" must be a number (degrees)`);
  return { eye: camera.eye, target: camera.target, up: camera.up, fov: camera.fov };
}

function pageUrl(options, camera) {
  const url = new URL(options.url);
  url.searchParams.set('overlay', '0');
  for (const key of ['eye', 'target', 'up']) url.searchParams.set(key, camera[key].join(','));
  url.searchParams.set('fov', String(camera.fov));
  if (options.iso !== undefined) url.searchParams.set('iso', options.iso);
  if (options.store !== undefined) url.searchParams.set('store', options.store);
  return url.href;
}

// The camera turned by `angle` radians about its up axis through its target (Rodrigues).
function turned(camera, angle) {
  const { eye, target, up } = camera;
  const length = Math.hypot(...up);
  const k = up.map((c) => c / length);
  const v = eye.map((c, i) => c - target[i]);
  const cos = Math.cos(angle);
  const sin = Math.sin(angle);
  const kDotV = k[0] * v[0] + k[1] * v[1] + k[2] * v[2];
  const kCrossV = [k[1] * v[2] - k[2] * v[1], k[2] * v[0] - k[0] * v[2], k[0] * v[1] - k[1] * v[0]];
  const rotated = v.map((c, i) => c * cos + kCrossV[i] * sin + k[i] * kDotV * (1 - cos));
  return { ...camera, eye: rotated.map((c, i) => c + target[i]) };
}

// A page of the viewer at `url`, ready (its hello handled); any error on it fails the run.
async function openViewer(browser, options, url, failure) {
  const page = await browser.newPage();
  page.on('pageerror', (error) => failure(`page error: ${error.message}`));
  page.on('console', (message) => {
    if (message.type() === 'error') failure(`console error: ${message.text()} (${message.location()?.url ?? 'page'})`);
  });
  page.on('requestfailed', (request) => failure(`request failed: ${request.url()} (${request.failure()?.errorText})`));
  await page.setViewport({ width: options.width, height: options.height, deviceScaleFactor: 1 });
  const response = await page.goto(url, { waitUntil: 'load' });
  if (!response.ok()) throw new Error(`${url} answered HTTP ${response.status()}`);
  await page.waitForFunction(() => window.vdisoViewer !== undefined);
  await page.evaluate(() => window.vdisoViewer.ready.then(() => undefined));
  return page;
}

// Waits until `page` shows a complete, final frame numbered `frame` or later; its stats.
async function frameFrom(page, frame) {
  await page.waitForFunction((n) => window.vdisoViewer.frameComplete().then((s) => s.frame >= n), { polling: 50 }, frame);
  return page.evaluate(() => window.vdisoViewer.frameComplete());
}

// The same frame on two pages: its number (each page's triangles may differ a little, as what
// each holds already differs: a brick sent whole marks more of the pyramid than its visible
// part; the screenshots are compared instead).
function sameFrame(what, seen, shown) {
  if (seen.frame !== shown.frame || seen.status !== 'complete') {
    throw new Error(`${what}: frame ${seen.frame} (${seen.status}), the other page's ${shown.frame}`);
  }
}

// Follow mode between two pages: the follower sees the leader's frames; after the hand-over
// the first page sees the follower's.
// The follower runs in a browser of its own, as another person's would: a page in a
// background tab of one browser draws nothing (no animation frames).
async function follow(options, failure, page, camera, first) {
  const link = await page.evaluate(() => window.vdisoViewer.followLink());
  const browser = await launch();
  try {
    await followIn(browser, options, failure, page, camera, first, link);
  } finally {
    await browser.close();
  }
}

async function followIn(browser, options, failure, page, camera, first, link) {
  const follower = await openViewer(browser, options, link, failure);
  const seen = await frameFrom(follower, first.frame);
  sameFrame('the follower\'s first frame', seen, first);
  await (await follower.$('#view')).screenshot({ path: options['follow-out'], captureBeyondViewport: false });
  const moved = await page.evaluate(async (cam) => {
    window.vdisoViewer.setCamera(cam);
    return window.vdisoViewer.frameComplete();
  }, turned(camera, 0.4));
  sameFrame('the follower after the leader turned', await frameFrom(follower, moved.frame), moved);
  await page.evaluate(() => window.vdisoViewer.handOver());
  await follower.waitForFunction(() => !window.vdisoViewer.role().following, { polling: 50 });
  await page.waitForFunction(() => window.vdisoViewer.role().following, { polling: 50 });
  const led = await follower.evaluate(async (cam) => {
    window.vdisoViewer.setCamera(cam);
    return window.vdisoViewer.frameComplete();
  }, camera);
  sameFrame('the first page after the hand-over', await frameFrom(page, led.frame), led);
  const roles = await page.evaluate(() => window.vdisoViewer.role());
  console.log(JSON.stringify({ follow: { followerFirstFrame: seen.frame, afterTurn: moved.frame, afterHandOver: led.frame, roles } }));
}

async function run(options, browser, failure) {
  const camera = readCamera(options.camera);
  const page = await openViewer(browser, options, pageUrl(options, camera), failure);
  const first = await page.evaluate(() => window.vdisoViewer.frameComplete());
  if (options.out) {
    const canvas = await page.$('#view');
    // Capturing beyond the viewport would resize the page for a moment: a new VIEW, a new frame.
    await canvas.screenshot({ path: options.out, captureBeyondViewport: false });
  }
  if (options.page) {
    // The whole page with its overlays, as a person sees it (docs/viewer.png).
    await page.evaluate(() => document.body.classList.remove('no-overlay'));
    await new Promise((resolve) => setTimeout(resolve, 200));  // a few frames drawn
    await page.screenshot({ path: options.page, captureBeyondViewport: false });
  }
  if (options['follow-out']) await follow(options, failure, page, camera, first);
  if (options.orbit === 0) {
    console.log(JSON.stringify(first));
    return;
  }
  console.log(JSON.stringify({ step: 0, ...first }));
  for (let step = 1; step < options.orbit; ++step) {
    const next = turned(camera, (2 * Math.PI * step) / options.orbit);
    const stats = await page.evaluate(async (cam) => {
      window.vdisoViewer.setCamera(cam);
      return window.vdisoViewer.frameComplete();
    }, next);
    console.log(JSON.stringify({ step, ...stats }));
  }
}

function launch() {
  return puppeteer.launch({ executablePath: CHROMIUM, headless: true, args: CHROMIUM_ARGS });
}

async function main() {
  const options = parseArgs(process.argv.slice(2));
  const browser = await launch();
  let fail;
  const failed = new Promise((_, reject) => (fail = (message) => reject(new Error(message))));
  failed.catch(() => {}); // also fails the race below; an error after the run has nothing to fail
  const timer = setTimeout(() => fail(`timed out after ${options.timeout} s`), options.timeout * 1000);
  try {
    await Promise.race([run(options, browser, fail), failed]);
  } finally {
    clearTimeout(timer);
    await browser.close();
  }
}

main().then(
  () => process.exit(0),
  (error) => {
    console.error(`e2e: ${error.message}`);
    process.exit(1);
  },
);
