// Properties of viewer/src/tree.js over synthetic mesh trees of every shape
// (synthetic.mjs): each property is checked on every tree, so one that holds
// only for a balanced tree or for node indices in depth-first order fails here.

import assert from 'node:assert/strict';
import { describe, test } from 'node:test';

import { MESH_SELECTIONS, encodePlainGlb, encodeTreeGlb, parseGlb, randomSource, sampleTrees } from './synthetic.mjs';
import { loadViewerModules } from './viewer-modules.mjs';

const SEED = 20261202;
const viewer = await loadViewerModules();

// Each sample tree with each mesh selection, parsed and read by readMeshTree: [{tree (the generated truth), gltf,
// read, primitives, label}].
const samples = [];
{
  const random = randomSource(SEED);
  for (const tree of sampleTrees(SEED)) {
    for (const meshes of MESH_SELECTIONS) {
      const { glb, primitives } = encodeTreeGlb(tree, { random, meshes });
      const gltf = await parseGlb(viewer.GLTFLoader, glb);
      samples.push({ tree, gltf, read: viewer.readMeshTree(gltf), primitives, label: `${tree.label}, meshes ${meshes}` });
    }
  }
}

const leafRange = (node) => Array.from({ length: node.leafCount }, (_, i) => node.firstLeaf + i);
const holds = (node, leaf) => leaf >= node.firstLeaf && leaf < node.firstLeaf + node.leafCount;

describe('isMeshTree', () => {
  test('is true for every exported tree', async () => {
    const random = randomSource(SEED + 1);
    for (const tree of sampleTrees(SEED + 1)) {
      for (const meshes of MESH_SELECTIONS) {
        const gltf = await parseGlb(viewer.GLTFLoader, encodeTreeGlb(tree, { random, meshes }).glb);
        assert.equal(viewer.isMeshTree(gltf), true, `${tree.label}, meshes ${meshes}`);
      }
    }
  });

  test('is false for a glTF without tree_node extras, or with tree_node not a whole number', async () => {
    for (const count of [1, 3]) {
      assert.equal(viewer.isMeshTree(await parseGlb(viewer.GLTFLoader, encodePlainGlb(count))), false, `${count} meshes`);
    }
    const random = randomSource(SEED + 2);
    const [tree] = sampleTrees(SEED + 2, 2).slice(1);
    for (const bad of ['0', 0.5, null]) {
      const { glb } = encodeTreeGlb(tree, { random, edit: (json) => json.nodes.forEach((n) => { n.extras.tree_node = bad; }) });
      assert.equal(viewer.isMeshTree(await parseGlb(viewer.GLTFLoader, glb)), false, `tree_node ${JSON.stringify(bad)}`);
    }
  });
});

describe('readMeshTree', () => {
  test('gives one record per tree node, in index order, with the extras the file holds', () => {
    for (const { tree, read, label } of samples) {
      assert.equal(read.nodes.length, tree.nodes.length, label);
      assert.equal(read.leafCount, tree.leafCount, label);
      assert.equal(read.maxDepth, tree.maxDepth, label);
      assert.equal(read.version, 'unit-test', label);
      for (const [i, node] of tree.nodes.entries()) {
        const r = read.nodes[i];
        const what = `${label}, node ${i}`;
        assert.equal(r.index, i, what);
        assert.deepEqual([r.depth, r.firstLeaf, r.leafCount, r.isLeaf, r.volume, r.triangles, r.capTriangles],
          [node.depth, node.firstLeaf, node.leafCount, node.isLeaf, node.volume, node.triangles, node.capTriangles], what);
        assert.deepEqual(r.centroid.toArray(), node.centroid, what);
      }
      assert.deepEqual(read.bonds.map((b) => [b.first, b.second, b.cutNode, b.area, b.centroid.toArray(), b.normal.toArray()]),
        tree.bonds.map((b) => [b.first, b.second, b.cutNode, b.area, b.centroid, b.normal]), label);
    }
  });

  test('gives each node with a mesh a flat group of exactly its own primitives, untransformed', () => {
    for (const { tree, read, primitives, label } of samples) {
      assert.equal(read.group.children.length, primitives.size, label);
      for (const r of read.nodes) {
        const what = `${label}, node ${r.index}`;
        if (!primitives.has(r.index)) {
          assert.equal(r.object, null, what);
          continue;
        }
        assert.equal(r.object.parent, read.group, what);
        assert.equal(r.object.userData.treeNode, r.index, what);
        assert.equal(r.object.children.length, primitives.get(r.index), `${what}: its primitives`);
        r.object.traverse((o) => {
          // No other tree node's object may hang below: hiding this node would hide it too.
          assert.ok(o === r.object || o.isMesh, `${what}: ${o.type} below the node`);
          assert.ok(!Number.isInteger(o.userData.tree_node) || o.userData.tree_node === r.index, `${what}: a child node kept`);
          if (o.isMesh) {
            assert.equal(o.userData.treeNode, r.index, what);
            assert.deepEqual([...o.position.toArray(), ...o.quaternion.toArray(), ...o.scale.toArray()],
              [0, 0, 0, 0, 0, 0, 1, 1, 1, 1], `${what}: the mesh's own transform`);
          }
        });
        // The octahedron the file holds for the node is centred on its centroid.
        const box = new viewer.THREE.Box3().setFromObject(r.object);
        assert.deepEqual(box.getCenter(new viewer.THREE.Vector3()).toArray(), tree.nodes[r.index].centroid, what);
      }
    }
  });

  test('takes the mesh box centre as the centroid of a file without centroids', async () => {
    const random = randomSource(SEED + 3);
    for (const tree of sampleTrees(SEED + 3, 10)) {
      const { glb, primitives } = encodeTreeGlb(tree, { random, meshes: 'some', withCentroids: false });
      const read = viewer.readMeshTree(await parseGlb(viewer.GLTFLoader, glb));
      for (const r of read.nodes) {
        const expected = primitives.has(r.index) ? tree.nodes[r.index].centroid : [0, 0, 0];
        assert.deepEqual(r.centroid.toArray(), expected, `${tree.label}, node ${r.index}`);
      }
    }
  });

  // Each malformation: a change to the glTF JSON and the message the refusal must carry.
  const malformations = [
    ['a node missing from the numbering', (json) => { json.nodes.at(-1).extras.tree_node = json.nodes.length + 5; },
      /not numbered 0 to \d+: node \d+ is missing/],
    ['a node index twice', (json) => { json.nodes.at(-1).extras.tree_node = 1; }, /tree node 1 is in the file twice/],
    ['a depth that is text', (json) => { json.nodes[1].extras.depth = 'deep'; }, /tree node 1: depth is "deep", not a whole number/],
    ['no first_leaf', (json) => { delete json.nodes[1].extras.first_leaf; }, /tree node 1: first_leaf is undefined/],
    ['a leaf_count of 0', (json) => { json.nodes[0].extras.leaf_count = 0; }, /tree node 0: leaf_count is 0, not a whole number of at least 1/],
    ['a centroid of two numbers', (json) => { json.nodes[1].extras.centroid = [1, 2]; }, /tree node 1: centroid is \[1,2\], not three numbers/],
    ['a leaf holding two leaves', (json) => {
      const leaf = json.nodes.find((n) => Number.isInteger(n.extras.leaf));
      leaf.extras.leaf_count = 2;
    }, /is a leaf but its leaf_count is 2, not 1/],
    ['overlapping leaf ranges', (json) => {
      const leaf = json.nodes.find((n) => Number.isInteger(n.extras.leaf) && n.extras.first_leaf > 0);
      leaf.extras.first_leaf -= 1;
      leaf.extras.leaf -= 1;
    }, /at depth \d+, leaf \d+ is in tree nodes \d+ and \d+/],
    ['a leaf range past the last leaf', (json) => {
      const leaf = json.nodes.find((n) => Number.isInteger(n.extras.leaf) && n.extras.first_leaf === json.nodes[0].extras.leaf_count - 1);
      leaf.extras.first_leaf += 1;
      leaf.extras.leaf += 1;
    }, /holds leaves \d+ to \d+, but the tree has \d+/],
    ['a root that is not at depth 0', (json) => { json.nodes.forEach((n) => { n.extras.depth += 1; }); }, /tree node 0 is not the root/],
    ['bonds that are not a list', (json) => { json.scenes[0].extras.bonds = { first: 0 }; }, /the scene's bonds are not a list/],
    ['a bond to a leaf the tree has not', (json) => { json.scenes[0].extras.bonds[0].second = 10000; }, /bond 0 joins leaves \d+ and 10000/],
    ['a bond from a leaf to itself', (json) => {
      const bond = json.scenes[0].extras.bonds[0];
      bond.second = bond.first;
    }, /bond 0 joins leaves (\d+) and \1: it must join two different leaves/],
    ['a bond without a normal', (json) => { delete json.scenes[0].extras.bonds.at(-1).normal; }, /bond \d+: normal is undefined, not three numbers/],
    ['a bond with a negative area', (json) => { json.scenes[0].extras.bonds[0].area = -1; }, /bond 0: area is -1/],
  ];

  for (const [what, edit, message] of malformations) {
    test(`refuses ${what}, saying so`, async () => {
      const random = randomSource(SEED + 4);
      // Trees with bonds and more than one level, so every malformation applies.
      const trees = sampleTrees(SEED + 4, 15).filter((t) => t.bonds.length > 0 && t.maxDepth > 0);
      assert.ok(trees.length >= 5);
      for (const tree of trees) {
        const { glb } = encodeTreeGlb(tree, { random, edit });
        const gltf = await parseGlb(viewer.GLTFLoader, glb);
        assert.throws(() => viewer.readMeshTree(gltf), message, tree.label);
      }
    });
  }
});

describe('nodesAtDepth', () => {
  test('at every depth, the shown nodes hold every leaf exactly once, in node order', () => {
    for (const { tree, read, label } of samples) {
      for (let depth = 0; depth <= read.maxDepth + 1; ++depth) {
        const shown = viewer.nodesAtDepth(read, depth);
        const leaves = shown.flatMap(leafRange).sort((a, b) => a - b);
        assert.deepEqual(leaves, leafRange(tree.nodes[0]), `${label}, depth ${depth}`);
        assert.deepEqual(shown.map((n) => n.index), [...shown.map((n) => n.index)].sort((a, b) => a - b), `${label}, depth ${depth}`);
        for (const n of shown) {
          assert.ok(n.depth === depth || (n.isLeaf && n.depth < depth), `${label}, depth ${depth}: node ${n.index} at ${n.depth}`);
        }
      }
    }
  });

  test('shows the root alone at depth 0 and every leaf at the deepest level', () => {
    for (const { read, label } of samples) {
      assert.deepEqual(viewer.nodesAtDepth(read, 0).map((n) => n.index), [0], label);
      const deepest = viewer.nodesAtDepth(read, read.maxDepth);
      assert.equal(deepest.length, read.leafCount, label);
      assert.ok(deepest.every((n) => n.isLeaf), label);
    }
  });

  test('never shows fewer pieces one level deeper', () => {
    for (const { read, label } of samples) {
      for (let depth = 1; depth <= read.maxDepth; ++depth) {
        assert.ok(viewer.nodesAtDepth(read, depth).length > viewer.nodesAtDepth(read, depth - 1).length, `${label}, depth ${depth}`);
      }
    }
  });
});

describe('drawableDepths', () => {
  test('is the depths whose shown nodes all have a mesh in the file', () => {
    for (const { read, primitives, label } of samples) {
      const expected = [];
      for (let k = 0; k <= read.maxDepth; ++k) {
        if (viewer.nodesAtDepth(read, k).every((n) => primitives.has(n.index))) expected.push(k);
      }
      assert.deepEqual(viewer.drawableDepths(read), expected, label);
    }
  });

  test('is every depth for a file with every node, and includes the deepest for a file with the leaves', () => {
    for (const { read, label } of samples.filter((s) => s.label.endsWith('meshes all'))) {
      assert.deepEqual(viewer.drawableDepths(read), Array.from({ length: read.maxDepth + 1 }, (_, k) => k), label);
    }
    for (const { read, label } of samples.filter((s) => s.label.endsWith('meshes leaves'))) {
      const depths = viewer.drawableDepths(read);
      assert.equal(depths.at(-1), read.maxDepth, label);
      // Only the levels made of leaves alone: an inner node has no mesh in such a file.
      for (const k of depths) assert.ok(viewer.nodesAtDepth(read, k).every((n) => n.isLeaf), `${label}, depth ${k}`);
    }
  });
});

describe('explodeOffset', () => {
  const amounts = [0, 0.1, 0.25, 0.5, 1, 2];
  test('is zero at amount 0 and for the root at any amount', () => {
    for (const { read, label } of samples) {
      const isZero = (v) => v.toArray().every((x) => x === 0);
      for (const node of read.nodes) assert.ok(isZero(viewer.explodeOffset(read, node, 0)), `${label}, node ${node.index}`);
      for (const a of amounts) assert.ok(isZero(viewer.explodeOffset(read, read.nodes[0], a)), `${label}, amount ${a}`);
    }
  });

  test('grows linearly with the amount, along the node centroid\'s direction from the root centroid', () => {
    for (const { read, label } of samples) {
      const root = read.nodes[0].centroid;
      for (const node of read.nodes) {
        const away = node.centroid.clone().sub(root);
        for (const a of amounts) {
          const offset = viewer.explodeOffset(read, node, a);
          const what = `${label}, node ${node.index}, amount ${a}`;
          for (const k of ['x', 'y', 'z']) assert.ok(Math.abs(offset[k] - a * away[k]) <= 1e-12 * (1 + Math.abs(away[k])), what);
          // Moved by the offset, the centroid is (1 + a) times as far from the root's.
          const distance = node.centroid.clone().add(offset).distanceTo(root);
          assert.ok(Math.abs(distance - (1 + a) * away.length()) <= 1e-9 * (1 + away.length()), what);
        }
      }
    }
  });

  test('leaves the node\'s centroid as it was', () => {
    for (const { read, label } of samples) {
      const before = read.nodes.map((n) => n.centroid.toArray());
      for (const node of read.nodes) viewer.explodeOffset(read, node, 0.7).multiplyScalar(3);
      assert.deepEqual(read.nodes.map((n) => n.centroid.toArray()), before, label);
    }
  });
});

describe('crossingBonds', () => {
  test('at every depth, is exactly the bonds between two different shown nodes, in the file\'s order', () => {
    for (const { read, label } of samples) {
      for (let depth = 0; depth <= read.maxDepth; ++depth) {
        const shown = viewer.nodesAtDepth(read, depth);
        const owner = (leaf) => shown.find((n) => holds(n, leaf));
        const expected = read.bonds.filter((b) => owner(b.first) !== owner(b.second));
        const crossing = viewer.crossingBonds(read, shown);
        const what = `${label}, depth ${depth}`;
        assert.deepEqual(crossing.map((c) => c.bond), expected, what);
        for (const { bond, a, b } of crossing) {
          assert.notEqual(a, b, what);
          assert.equal(a, owner(bond.first), what);
          assert.equal(b, owner(bond.second), what);
        }
      }
    }
  });

  test('is empty with the root shown and every bond with the leaves shown', () => {
    for (const { read, label } of samples) {
      assert.deepEqual(viewer.crossingBonds(read, viewer.nodesAtDepth(read, 0)), [], label);
      assert.equal(viewer.crossingBonds(read, viewer.nodesAtDepth(read, read.maxDepth)).length, read.bonds.length, label);
    }
  });

  test('leaves out the bonds to a leaf no shown node holds', () => {
    const random = randomSource(SEED + 5);
    for (const { read, label } of samples) {
      const leaves = viewer.nodesAtDepth(read, read.maxDepth);
      const shown = leaves.filter(() => random.next() < 0.5);
      const isShown = (leaf) => shown.some((n) => holds(n, leaf));
      assert.deepEqual(viewer.crossingBonds(read, shown).map((c) => c.bond),
        read.bonds.filter((b) => isShown(b.first) && isShown(b.second)), label);
    }
  });
});

describe('bondsOfNode', () => {
  test('is the bonds with exactly one leaf inside the node, inside leaf first, in the file\'s order', () => {
    for (const { read, label } of samples) {
      for (const node of read.nodes) {
        const expected = read.bonds.filter((b) => holds(node, b.first) !== holds(node, b.second)).map((b) => (holds(node, b.first)
          ? { leaf: b.first, other: b.second, area: b.area } : { leaf: b.second, other: b.first, area: b.area }));
        assert.deepEqual(viewer.bondsOfNode(read, node), expected, `${label}, node ${node.index}`);
      }
      assert.deepEqual(viewer.bondsOfNode(read, read.nodes[0]), [], `${label}: the root has no bond to anything outside`);
    }
  });

  test('over the nodes shown at a depth, counts each crossing bond twice', () => {
    for (const { read, label } of samples) {
      for (let depth = 0; depth <= read.maxDepth; ++depth) {
        const shown = viewer.nodesAtDepth(read, depth);
        const ends = shown.reduce((sum, n) => sum + viewer.bondsOfNode(read, n).length, 0);
        assert.equal(ends, 2 * viewer.crossingBonds(read, shown).length, `${label}, depth ${depth}`);
      }
    }
  });
});
