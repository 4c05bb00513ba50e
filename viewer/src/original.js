// The original input of a repaired tree (`shatter view TREE --original MESH`, issue 21): the server's answer to
// GET api/original read and checked, placed beside the tree's root, and drawn as it is, its defects highlighted:
// open (boundary) edges and non-manifold edges as tubes, self-intersecting triangles in their own colour and
// outlined by tubes of it.

import * as THREE from 'three';

export const ORIGINAL_COLOURS = {
  surface: 0x8d939e,
  boundary: 0xffc83d,
  nonManifold: 0xff4fd8,
  selfIntersecting: 0xff3b30,
};

function whole(values, what, limit) {
  if (!Array.isArray(values)) throw new Error(`the original's ${what} is not a list`);
  const out = new Uint32Array(values.length);
  for (let i = 0; i < values.length; ++i) {
    const v = values[i];
    if (!Number.isInteger(v) || v < 0 || v >= limit) throw new Error(`the original's ${what}[${i}] = ${v} is out of range`);
    out[i] = v;
  }
  return out;
}

/**
 * Reads the answer of GET api/original (cli/view_original.hpp, original_json) into typed arrays: positions
 * (Float64Array, 3 per vertex), indices (Uint32Array, 3 per triangle), boundaryEdges and nonManifoldEdges
 * (Uint32Array, 2 vertex indices per edge), selfIntersecting (triangle indices), and the texts as they came.
 * Throws an Error naming the first thing wrong: a list of the wrong length, a coordinate that is no finite number,
 * an index out of range.
 */
export function readOriginal(answer) {
  if (!answer || typeof answer !== 'object') throw new Error('the original is not a JSON object');
  const { positions } = answer;
  if (!Array.isArray(positions) || positions.length % 3 !== 0 || positions.length === 0) {
    throw new Error('the original\'s positions are not a non-empty list of x, y, z');
  }
  if (!positions.every(Number.isFinite)) throw new Error('the original has a coordinate that is no finite number');
  const vertices = positions.length / 3;
  const indices = whole(answer.indices, 'indices', vertices);
  if (indices.length % 3 !== 0 || indices.length === 0) throw new Error('the original\'s indices are not triangles');
  const triangles = indices.length / 3;
  const boundaryEdges = whole(answer.boundary_edges, 'boundary_edges', vertices);
  const nonManifoldEdges = whole(answer.non_manifold_edges, 'non_manifold_edges', vertices);
  if (boundaryEdges.length % 2 !== 0 || nonManifoldEdges.length % 2 !== 0) {
    throw new Error('the original\'s edge lists are not pairs of vertices');
  }
  const selfIntersecting = whole(answer.self_intersecting_triangles, 'self_intersecting_triangles', triangles);
  const repair = answer.repair ?? null;
  return {
    file: String(answer.file ?? ''),
    positions: Float64Array.from(positions),
    indices,
    vertices,
    triangles,
    boundaryEdges,
    nonManifoldEdges,
    selfIntersecting,
    validation: String(answer.validation ?? ''),
    defects: Array.isArray(answer.defects) ? answer.defects : [],
    readWarnings: Array.isArray(answer.read_warnings) ? answer.read_warnings.map(String) : [],
    repair: repair && {
      changes: (repair.changes || []).map(String),
      notDone: (repair.not_done || []).map(String),
      trianglesBefore: repair.triangles_before,
      trianglesAfter: repair.triangles_after,
    },
  };
}

/** The box {min: [x, y, z], max: [x, y, z]} of the original's vertices. */
export function boxOf(positions) {
  const min = [Infinity, Infinity, Infinity];
  const max = [-Infinity, -Infinity, -Infinity];
  for (let i = 0; i < positions.length; i += 3) {
    for (let k = 0; k < 3; ++k) {
      min[k] = Math.min(min[k], positions[i + k]);
      max[k] = Math.max(max[k], positions[i + k]);
    }
  }
  return { min, max };
}

/**
 * The translation [dx, 0, 0] that puts a box `original` beside (to the left along x of) the box `root`, with a gap
 * of a quarter of the larger of the two boxes' largest sides between them, so neither hides the other. Only x moves:
 * the two keep their heights and depths, so the same parts line up.
 */
export function besideOffset(root, original) {
  const side = (box) => Math.max(box.max[0] - box.min[0], box.max[1] - box.min[1], box.max[2] - box.min[2]);
  const gap = 0.25 * Math.max(side(root), side(original)) || 1;
  return [root.min[0] - gap - original.max[0], 0, 0];
}

// A tube along each edge (pairs of vertex indices), radius `radius`, as one instanced mesh: lines are one pixel
// wide in WebGL, too thin to see the defect at a glance.
function edgeTubes(positions, edges, radius, colour, name) {
  const count = edges.length / 2;
  const geometry = new THREE.CylinderGeometry(1, 1, 1, 8, 1, false);
  const material = new THREE.MeshBasicMaterial({ color: colour });
  const mesh = new THREE.InstancedMesh(geometry, material, Math.max(count, 1));
  mesh.count = count;
  mesh.name = name;
  const up = new THREE.Vector3(0, 1, 0);
  const matrix = new THREE.Matrix4();
  const q = new THREE.Quaternion();
  const at = (v) => new THREE.Vector3(positions[3 * v], positions[3 * v + 1], positions[3 * v + 2]);
  for (let i = 0; i < count; ++i) {
    const a = at(edges[2 * i]);
    const b = at(edges[2 * i + 1]);
    const d = b.clone().sub(a);
    const length = Math.max(d.length(), 1e-12);
    q.setFromUnitVectors(up, d.divideScalar(length));
    matrix.compose(a.add(b).multiplyScalar(0.5), q, new THREE.Vector3(radius, length, radius));
    mesh.setMatrixAt(i, matrix);
  }
  mesh.instanceMatrix.needsUpdate = true;
  return mesh;
}

/**
 * The original drawn as it is (a readOriginal result): its triangles both sides lit (an open or inward surface still
 * shows), the self-intersecting ones in their colour and outlined, boundary and non-manifold edges as tubes. A Group named
 * 'original', hidden; the caller places it (besideOffset) and shows it.
 */
export function originalObject(original) {
  const group = new THREE.Group();
  group.name = 'original';
  group.visible = false;
  const positions = new THREE.BufferAttribute(new Float32Array(original.positions), 3);
  const marked = new Set(original.selfIntersecting);
  const plain = [];
  const bad = [];
  for (let t = 0; t < original.triangles; ++t) {
    (marked.has(t) ? bad : plain).push(original.indices[3 * t], original.indices[3 * t + 1], original.indices[3 * t + 2]);
  }
  const surface = (indices, colour, name) => {
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute('position', positions);
    geometry.setIndex(indices);
    geometry.computeVertexNormals();
    const material = new THREE.MeshStandardMaterial({ color: colour, roughness: 0.7, metalness: 0, side: THREE.DoubleSide,
      flatShading: true, polygonOffset: true, polygonOffsetFactor: 1, polygonOffsetUnits: 1 });
    const mesh = new THREE.Mesh(geometry, material);
    mesh.name = name;
    return mesh;
  };
  if (plain.length) group.add(surface(plain, ORIGINAL_COLOURS.surface, 'original-surface'));
  if (bad.length) group.add(surface(bad, ORIGINAL_COLOURS.selfIntersecting, 'original-self-intersecting'));
  const box = boxOf(original.positions);
  const diagonal = Math.hypot(box.max[0] - box.min[0], box.max[1] - box.min[1], box.max[2] - box.min[2]) || 1;
  const radius = 0.005 * diagonal;
  if (original.boundaryEdges.length) {
    group.add(edgeTubes(original.positions, original.boundaryEdges, radius, ORIGINAL_COLOURS.boundary, 'original-boundary'));
  }
  if (original.nonManifoldEdges.length) {
    group.add(edgeTubes(original.positions, original.nonManifoldEdges, radius, ORIGINAL_COLOURS.nonManifold,
      'original-non-manifold'));
  }
  if (original.selfIntersecting.length) {
    // Crossing triangles are often small slivers: their outlines keep them visible at any size.
    const outline = new Uint32Array(6 * original.selfIntersecting.length);
    original.selfIntersecting.forEach((t, i) => {
      for (let c = 0; c < 3; ++c) {
        outline[6 * i + 2 * c] = original.indices[3 * t + c];
        outline[6 * i + 2 * c + 1] = original.indices[3 * t + (c + 1) % 3];
      }
    });
    group.add(edgeTubes(original.positions, outline, radius, ORIGINAL_COLOURS.selfIntersecting,
      'original-self-intersecting-outline'));
  }
  group.userData.box = box;
  return group;
}
