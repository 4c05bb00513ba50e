// The mesh tree as a GLB from `shatter export` holds it (meshtree/export.hpp):
// glTF node i is tree node i, its extras say depth, leaf range, volume, centroid
// and triangle counts, and the scene's extras list the bonds. This module reads
// that into plain records and answers the questions the controls ask: which
// nodes show the solid cut at depth K, where each goes when exploded, which
// bonds cross between the shown nodes.

import * as THREE from 'three';

/** True when a loaded glTF scene is a shatter mesh tree (its nodes carry tree_node extras). */
export function isMeshTree(gltf) {
  let found = false;
  gltf.scene.traverse((object) => {
    if (object.userData && Number.isInteger(object.userData.tree_node)) found = true;
  });
  return found;
}

/**
 * The tree nodes of a loaded mesh tree, each {index, depth, firstLeaf, leafCount, isLeaf, volume, centroid (Vector3),
 * triangles, capTriangles, extras, object (Group of its primitive meshes, or null when the file has no mesh for it)},
 * in node order; and the bonds from the scene extras. The primitive meshes are moved out of the glTF hierarchy into
 * one flat group per node, because three.js hides the children of a hidden object and the levels of a tree nest.
 * A file whose extras do not describe a tree (nodes missing or twice, counts that are no whole numbers, leaf ranges
 * that do not cut the leaves into pieces at every depth, bonds to leaves it does not have) is refused with an Error
 * that names the node or bond, before anything is moved: the controls would otherwise draw a piece twice or not at all.
 */
export function readMeshTree(gltf) {
  const byIndex = new Map();
  gltf.scene.traverse((object) => {
    const extras = object.userData;
    if (!extras || !Number.isInteger(extras.tree_node)) return;
    if (byIndex.has(extras.tree_node)) throw new Error(`tree node ${extras.tree_node} is in the file twice`);
    byIndex.set(extras.tree_node, { object3d: object, extras });
  });
  const count = byIndex.size;
  const nodes = [];
  for (let i = 0; i < count; ++i) {
    const entry = byIndex.get(i);
    if (!entry) throw new Error(`the file's tree nodes are not numbered 0 to ${count - 1}: node ${i} is missing`);
    const e = entry.extras;
    const isLeaf = Number.isInteger(e.leaf);
    const leafCount = wholeNumber(e, 'leaf_count', `tree node ${i}`, 1);
    if (isLeaf && leafCount !== 1) throw new Error(`tree node ${i} is a leaf but its leaf_count is ${leafCount}, not 1`);
    nodes.push({
      index: i,
      depth: wholeNumber(e, 'depth', `tree node ${i}`),
      firstLeaf: wholeNumber(e, 'first_leaf', `tree node ${i}`),
      leafCount,
      isLeaf,
      volume: e.volume,
      centroid: e.centroid === undefined ? null : vector3(e.centroid, `tree node ${i}: centroid`),
      triangles: e.triangles,
      capTriangles: e.cap_triangles,
      extras: e,
      object3d: entry.object3d,
      object: null,
    });
  }
  if (nodes.length && (nodes[0].depth !== 0 || nodes[0].firstLeaf !== 0)) {
    throw new Error(`tree node 0 is not the root: depth ${nodes[0].depth}, first leaf ${nodes[0].firstLeaf}`);
  }
  const maxDepth = nodes.reduce((m, n) => Math.max(m, n.depth), 0);
  const leafCount = nodes.length ? nodes[0].leafCount : 0;
  const sceneExtras = gltf.scene.userData || {};
  if (sceneExtras.bonds !== undefined && !Array.isArray(sceneExtras.bonds)) {
    throw new Error(`the scene's bonds are not a list: ${JSON.stringify(sceneExtras.bonds)}`);
  }
  const bonds = (sceneExtras.bonds || []).map((b, i) => readBond(b, `bond ${i}`, leafCount));
  const tree = { nodes, bonds, group: null, maxDepth, leafCount, version: sceneExtras.shatter_version || '' };
  checkLeafRanges(tree);

  const group = new THREE.Group();
  group.name = 'fragments';
  for (const node of nodes) {
    const meshes = ownMeshes(node.object3d);
    delete node.object3d;
    if (meshes.length === 0) continue;
    const holder = new THREE.Group();
    holder.name = node.isLeaf ? `leaf ${node.firstLeaf}` : `node ${node.index}`;
    holder.userData.treeNode = node.index;
    for (const mesh of meshes) {
      // A single-primitive node is the mesh itself: its child nodes hang below it and must not follow it.
      for (const child of [...mesh.children]) {
        if (Number.isInteger(child.userData.tree_node)) mesh.remove(child);
      }
      mesh.removeFromParent();
      mesh.position.set(0, 0, 0);
      mesh.quaternion.identity();
      mesh.scale.set(1, 1, 1);
      mesh.userData.treeNode = node.index;
      holder.add(mesh);
    }
    node.object = holder;
    group.add(holder);
  }
  for (const node of nodes) {
    // A file written before centroids were exported: the box centre stands in.
    if (!node.centroid) {
      node.centroid = node.object ? new THREE.Box3().setFromObject(node.object).getCenter(new THREE.Vector3())
        : new THREE.Vector3();
    }
  }
  tree.group = group;
  return tree;
}

// extras[field] as a whole number of at least `min`, or an Error naming `owner` and the field.
function wholeNumber(extras, field, owner, min = 0) {
  const value = extras[field];
  if (!Number.isInteger(value) || value < min) {
    throw new Error(`${owner}: ${field} is ${JSON.stringify(value)}, not a whole number${min > 0 ? ` of at least ${min}` : ''}`);
  }
  return value;
}

function vector3(value, what) {
  if (!Array.isArray(value) || value.length !== 3 || !value.every(Number.isFinite)) {
    throw new Error(`${what} is ${JSON.stringify(value)}, not three numbers`);
  }
  return new THREE.Vector3(...value);
}

function readBond(b, what, leafCount) {
  if (!b || typeof b !== 'object') throw new Error(`${what} is ${JSON.stringify(b)}, not an object`);
  const first = wholeNumber(b, 'first', what);
  const second = wholeNumber(b, 'second', what);
  if (first >= leafCount || second >= leafCount || first === second) {
    throw new Error(`${what} joins leaves ${first} and ${second}: it must join two different leaves of the ${leafCount}`);
  }
  if (!Number.isFinite(b.area) || b.area < 0) throw new Error(`${what}: area is ${JSON.stringify(b.area)}, not a number ≥ 0`);
  return {
    first, second, cutNode: b.cut_node, area: b.area,
    centroid: vector3(b.centroid, `${what}: centroid`), normal: vector3(b.normal, `${what}: normal`),
  };
}

// At every depth the shown nodes must hold each leaf exactly once (a partition of the leaves), which is what the
// depth slider, the explode and the bond overlay assume.
function checkLeafRanges(tree) {
  for (let depth = 0; depth <= tree.maxDepth; ++depth) {
    const holder = new Array(tree.leafCount).fill(-1);
    for (const node of nodesAtDepth(tree, depth)) {
      const end = node.firstLeaf + node.leafCount;
      if (end > tree.leafCount) {
        throw new Error(`tree node ${node.index} holds leaves ${node.firstLeaf} to ${end - 1}, but the tree has ${tree.leafCount}`);
      }
      for (let leaf = node.firstLeaf; leaf < end; ++leaf) {
        if (holder[leaf] >= 0) throw new Error(`at depth ${depth}, leaf ${leaf} is in tree nodes ${holder[leaf]} and ${node.index}`);
        holder[leaf] = node.index;
      }
    }
    const hole = holder.indexOf(-1);
    if (hole >= 0) throw new Error(`at depth ${depth}, no tree node holds leaf ${hole}`);
  }
}

// The meshes that draw a glTF node itself (one per primitive), not those of its child nodes.
function ownMeshes(object3d) {
  if (object3d.isMesh) return [object3d];
  return object3d.children.filter((child) => child.isMesh && !Number.isInteger(child.userData.tree_node));
}

/**
 * The nodes that show the solid cut at depth K, in node order: those at depth K and the leaves above it, as
 * `shatter export --nodes depth:K` selects them (meshtree/export.hpp). Their leaf ranges partition the leaves.
 */
export function nodesAtDepth(tree, depth) {
  return tree.nodes.filter((n) => n.depth === depth || (n.isLeaf && n.depth < depth));
}

/** The depths whose every node has a mesh in the file: all of them for `--nodes all`, only the deepest for leaves. */
export function drawableDepths(tree) {
  const depths = [];
  for (let k = 0; k <= tree.maxDepth; ++k) {
    if (nodesAtDepth(tree, k).every((n) => n.object)) depths.push(k);
  }
  return depths;
}

/**
 * Where a node is moved by the explode amount `amount` (0 = assembled): away from the root's centroid along its own
 * centroid's direction, by `amount` times its centroid's distance, so every centroid's distance from the root's
 * grows with the amount.
 */
export function explodeOffset(tree, node, amount) {
  return node.centroid.clone().sub(tree.nodes[0].centroid).multiplyScalar(amount);
}

/**
 * The bonds between the shown nodes: a bond joins two leaves; it is drawn when they belong to different shown
 * nodes, from one node's centroid through the bond's centroid to the other's. Returns [{bond, a, b}] with a and b
 * the shown node records.
 */
export function crossingBonds(tree, shown) {
  const ownerOfLeaf = new Array(tree.leafCount);
  for (const node of shown) {
    for (let l = node.firstLeaf; l < node.firstLeaf + node.leafCount; ++l) ownerOfLeaf[l] = node;
  }
  const result = [];
  for (const bond of tree.bonds) {
    const a = ownerOfLeaf[bond.first];
    const b = ownerOfLeaf[bond.second];
    if (a && b && a !== b) result.push({ bond, a, b });
  }
  return result;
}

/**
 * The bonds that cross a node's boundary: one leaf inside its leaf range, the other outside, as
 * `shatter info --nodes` lists them: [{leaf (inside), other (outside), area}], in the file's bond order.
 */
export function bondsOfNode(tree, node) {
  const inside = (leaf) => leaf >= node.firstLeaf && leaf < node.firstLeaf + node.leafCount;
  const result = [];
  for (const bond of tree.bonds) {
    const firstIn = inside(bond.first);
    if (firstIn === inside(bond.second)) continue;
    result.push(firstIn ? { leaf: bond.first, other: bond.second, area: bond.area }
      : { leaf: bond.second, other: bond.first, area: bond.area });
  }
  return result;
}
