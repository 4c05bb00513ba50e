// Properties of viewer/src/original.js, the page's side of `shatter view --original`: readOriginal over answers
// shaped as the server sends them (cli/view_original.hpp) and broken ones, besideOffset over random boxes, and
// originalObject's drawing of the defects.

import assert from 'node:assert/strict';
import { describe, test } from 'node:test';

import { randomSource } from './synthetic.mjs';
import { loadViewerModules } from './viewer-modules.mjs';

const SEED = 20261203;
const viewer = await loadViewerModules();

// A random open, damaged surface as the server would describe it: a grid of quads with some triangles left out,
// marked boundary edges, a few triangles marked self-intersecting, a few edges marked non-manifold.
function randomAnswer(random) {
  const n = random.int(2, 6);
  const positions = [];
  for (let i = 0; i <= n; ++i) {
    for (let j = 0; j <= n; ++j) positions.push(i + random.next() * 0.1, j, random.next() * 2 - 1);
  }
  const at = (i, j) => i * (n + 1) + j;
  const indices = [];
  for (let i = 0; i < n; ++i) {
    for (let j = 0; j < n; ++j) {
      indices.push(at(i, j), at(i + 1, j), at(i + 1, j + 1));
      if (random.next() < 0.8) indices.push(at(i, j), at(i + 1, j + 1), at(i, j + 1));
    }
  }
  const triangles = indices.length / 3;
  const selfIntersecting = [...new Set(Array.from({ length: random.int(0, 4) }, () => random.int(0, triangles - 1)))]
    .sort((a, b) => a - b);
  return {
    file: 'grid.off', vertices: positions.length / 3, triangles, positions, indices,
    validation: 'open mesh', defects: [],
    boundary_edges: [at(0, 0), at(1, 0), at(0, 0), at(0, 1)],
    non_manifold_edges: random.next() < 0.5 ? [at(1, 1), at(1, 2)] : [],
    self_intersecting_triangles: selfIntersecting,
    degenerate_triangles: 0,
    read_warnings: [],
    repair: { changes: ['filled 1 hole (4 border edges) with 2 new triangles'], not_done: [], vertices_before: 1,
      triangles_before: triangles, vertices_after: 1, triangles_after: triangles + 2 },
  };
}

const samples = [];
{
  const random = randomSource(SEED);
  for (let k = 0; k < 40; ++k) samples.push(randomAnswer(random));
}

describe('readOriginal', () => {
  test('reads every answer into typed arrays holding the same numbers', () => {
    for (const answer of samples) {
      const read = viewer.readOriginal(answer);
      assert.equal(read.vertices, answer.positions.length / 3);
      assert.equal(read.triangles, answer.indices.length / 3);
      assert.deepEqual(Array.from(read.positions), answer.positions);
      assert.deepEqual(Array.from(read.indices), answer.indices);
      assert.deepEqual(Array.from(read.boundaryEdges), answer.boundary_edges);
      assert.deepEqual(Array.from(read.nonManifoldEdges), answer.non_manifold_edges);
      assert.deepEqual(Array.from(read.selfIntersecting), answer.self_intersecting_triangles);
      assert.deepEqual(read.repair.changes, answer.repair.changes);
      assert.equal(read.repair.trianglesAfter, answer.repair.triangles_after);
    }
    assert.equal(viewer.readOriginal({ ...samples[0], repair: null }).repair, null, 'a tree that records no repair');
  });

  test('refuses an answer it cannot draw, naming what is wrong', () => {
    const a = samples[0];
    const broken = [
      [{ ...a, positions: a.positions.slice(1) }, /positions/],
      [{ ...a, positions: [] }, /positions/],
      [{ ...a, positions: [NaN, ...a.positions.slice(1)] }, /finite/],
      [{ ...a, indices: [...a.indices.slice(0, -1), a.vertices] }, /indices\[\d+\] = \d+ is out of range/],
      [{ ...a, indices: a.indices.slice(1) }, /not triangles/],
      [{ ...a, indices: [0.5, 1, 2] }, /out of range/],
      [{ ...a, boundary_edges: [0] }, /pairs/],
      [{ ...a, non_manifold_edges: [0, -1] }, /out of range/],
      [{ ...a, self_intersecting_triangles: [a.indices.length / 3] }, /self_intersecting_triangles/],
      [{ ...a, self_intersecting_triangles: 'all' }, /not a list/],
      [null, /not a JSON object/],
    ];
    for (const [answer, message] of broken) assert.throws(() => viewer.readOriginal(answer), message);
  });
});

describe('besideOffset', () => {
  test('puts the original left of the root, apart, moving only x', () => {
    const random = randomSource(SEED + 1);
    const randomBox = () => {
      const min = [0, 1, 2].map(() => random.next() * 200 - 100);
      return { min, max: min.map((v) => v + random.next() * 50) };
    };
    for (let k = 0; k < 500; ++k) {
      const root = randomBox();
      // The original holds the root's box (a repair keeps the root within its input's box), or is another box.
      const original = k % 2 ? randomBox()
        : { min: root.min.map((v) => v - random.next()), max: root.max.map((v) => v + random.next()) };
      const [dx, dy, dz] = viewer.besideOffset(root, original);
      assert.equal(dy, 0);
      assert.equal(dz, 0);
      assert.ok(original.max[0] + dx < root.min[0], `box ${k}: the moved original reaches the root`);
      const largest = Math.max(...[0, 1, 2].flatMap((i) => [root.max[i] - root.min[i], original.max[i] - original.min[i]]));
      assert.ok(root.min[0] - (original.max[0] + dx) <= 0.25 * largest * (1 + 1e-12) + 1e-9, `box ${k}: too far`);
    }
    // A point: still a gap.
    const point = { min: [1, 2, 3], max: [1, 2, 3] };
    assert.ok(viewer.besideOffset(point, point)[0] < 0);
  });
});

describe('originalObject', () => {
  test('draws every triangle once, the self-intersecting ones apart and outlined, and a tube per marked edge', () => {
    for (const answer of samples) {
      const read = viewer.readOriginal(answer);
      const group = viewer.originalObject(read);
      assert.equal(group.visible, false, 'hidden until the switch shows it');
      const named = (name) => group.getObjectByName(name);
      const count = (mesh) => (mesh ? mesh.geometry.index.count / 3 : 0);
      const marked = count(named('original-self-intersecting'));
      assert.equal(marked, read.selfIntersecting.length);
      assert.equal(count(named('original-surface')) + marked, read.triangles);
      const tubes = (mesh) => (mesh ? mesh.count : 0);
      assert.equal(tubes(named('original-boundary')), read.boundaryEdges.length / 2);
      assert.equal(tubes(named('original-non-manifold')), read.nonManifoldEdges.length / 2);
      assert.equal(tubes(named('original-self-intersecting-outline')), 3 * read.selfIntersecting.length);
      if (named('original-self-intersecting')) {
        assert.equal(named('original-self-intersecting').material.color.getHex(), viewer.ORIGINAL_COLOURS.selfIntersecting);
      }
      assert.deepEqual(group.userData.box, viewer.boxOf(read.positions));
    }
  });
});
