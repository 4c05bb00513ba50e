// Properties of fragmentColour (viewer/src/viewer.js): every piece its own
// colour, the same on every load, and neighbours in the numbering far apart in
// hue, at any number of pieces.

import assert from 'node:assert/strict';
import { test } from 'node:test';

import { loadViewerModules } from './viewer-modules.mjs';

const { THREE, fragmentColour } = await loadViewerModules();
const hueOf = (colour) => colour.getHSL({}).h;
const hueDistance = (a, b) => Math.min(Math.abs(a - b), 1 - Math.abs(a - b));

test('fragmentColour is the same colour for the same fragment every time', () => {
  for (let i = 0; i < 200; ++i) assert.equal(fragmentColour(i).getHex(), fragmentColour(i).getHex(), `fragment ${i}`);
});

test('fragmentColour gives the first 64 fragments 64 different 8-bit colours, all of one saturation and lightness', () => {
  const seen = new Map();
  for (let i = 0; i < 64; ++i) {
    const colour = fragmentColour(i);
    assert.ok(colour instanceof THREE.Color);
    const hex = colour.getHexString();
    assert.ok(!seen.has(hex), `fragments ${seen.get(hex)} and ${i} are both #${hex}`);
    seen.set(hex, i);
    const { s, l } = colour.getHSL({});
    assert.ok(Math.abs(s - 0.55) < 1e-6 && Math.abs(l - 0.58) < 1e-6, `fragment ${i}: saturation ${s}, lightness ${l}`);
  }
});

test('fragmentColour spreads the hues of any first n fragments at least 0.3/n apart, consecutive ones 0.3', () => {
  const hues = Array.from({ length: 256 }, (_, i) => hueOf(fragmentColour(i)));
  for (let n = 2; n <= hues.length; ++n) {
    const sorted = hues.slice(0, n).sort((a, b) => a - b);
    const gaps = sorted.map((h, i) => (i + 1 < n ? sorted[i + 1] - h : 1 + sorted[0] - h));
    const smallest = Math.min(...gaps);
    assert.ok(smallest >= 0.3 / n, `the first ${n} hues come within ${smallest} of each other`);
  }
  for (let i = 0; i + 1 < hues.length; ++i) {
    assert.ok(hueDistance(hues[i], hues[i + 1]) >= 0.3, `fragments ${i} and ${i + 1}: hues ${hues[i]}, ${hues[i + 1]}`);
  }
});
