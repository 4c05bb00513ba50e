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
 */
export function readMeshTree(gltf) {
  const byIndex = new Map();
  gltf.scene.traverse((object) => {
    const extras = object.userData;
    if (!extras || !Number.isInteger(extras.tree_node)) return;
    byIndex.set(extras.tree_node, { object3d: object, extras });
  });
  const count = byIndex.size;
  const nodes = [];
  for (let i = 0; i < count; ++i) {
    const entry = byIndex.get(i);
    if (!entry) throw new Error(`the file's tree nodes are not numbered 0 to ${count - 1}: node ${i} is missing`);
    const e = entry.extras;
    const centroid = Array.isArray(e.centroid) ? new THREE.Vector3(...e.centroid) : null;
    nodes.push({
      index: i,
      depth: e.depth,
      firstLeaf: e.first_leaf,
      leafCount: e.leaf_count,
      isLeaf: Number.isInteger(e.leaf),
      volume: e.volume,
      centroid,
      triangles: e.triangles,
      capTriangles: e.cap_triangles,
      extras: e,
      meshes: ownMeshes(entry.object3d),
      object: null,
    });
  }
  const group = new THREE.Group();
  group.name = 'fragments';
  for (const node of nodes) {
    if (node.meshes.length === 0) continue;
    const holder = new THREE.Group();
    holder.name = node.isLeaf ? `leaf ${node.firstLeaf}` : `node ${node.index}`;
    holder.userData.treeNode = node.index;
    for (const mesh of node.meshes) {
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
  const sceneExtras = gltf.scene.userData || {};
  const bonds = Array.isArray(sceneExtras.bonds) ? sceneExtras.bonds.map((b) => ({
    first: b.first, second: b.second, cutNode: b.cut_node, area: b.area,
    centroid: new THREE.Vector3(...b.centroid), normal: new THREE.Vector3(...b.normal),
  })) : [];
  const maxDepth = nodes.reduce((m, n) => Math.max(m, n.depth), 0);
  const leafCount = nodes.length ? nodes[0].leafCount : 0;
  return { nodes, bonds, group, maxDepth, leafCount, version: sceneExtras.shatter_version || '' };
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
