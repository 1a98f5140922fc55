// The page's copies of the library's limits (src/protocol.js) against their one home in C++:
// the viewport sides a VIEW may ask for are core/camera.h's kMinImageSide and kMaxImageSide.
//   node --test test/*.test.js                 (from web/; ctest runs it as WebViewer.Decoders)
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { readFileSync } from 'node:fs';
import { VIEWPORT_MAX, VIEWPORT_MIN } from '../src/protocol.js';

test("the viewport's sides are the camera's image sides (core/camera.h)", () => {
  const header = readFileSync(new URL('../../core/camera.h', import.meta.url), 'utf8');
  const found = header.match(/constexpr int kMinImageSide = (\d+), kMaxImageSide = (\d+);/);
  assert.ok(found, 'core/camera.h no longer says kMinImageSide and kMaxImageSide as this test reads them');
  assert.equal(VIEWPORT_MIN, Number(found[1]));
  assert.equal(VIEWPORT_MAX, Number(found[2]));
});
