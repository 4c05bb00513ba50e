// The 3D view: renderer, camera, lights and orbit controls, the loaded model,
// the colouring, explode, depth, bond overlay and picking. It renders on demand
// (after a change, while the orbit controls move or a replay plays), so an idle
// page costs nothing.

import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';

import { bondsOfNode, crossingBonds, drawableDepths, explodeOffset, isMeshTree, nodesAtDepth, readMeshTree }
  from './tree.js';
import { Replay } from './replay.js';
import { ReplayFraming, fitDistance } from './framing.js';
import { besideOffset } from './original.js';

const INTERIOR = 'interior';
const EXTERIOR = 'exterior';
const BOND_COLOUR = 0x36c3ff;
// Where the camera looks from when it is first placed: above and to the front right.
const DEFAULT_VIEW_DIRECTION = new THREE.Vector3(0.9, 0.6, 1.2).normalize();

/** A distinct, stable colour for fragment `i` (golden-ratio hues). */
export function fragmentColour(i) {
  const hue = (i * 0.6180339887498949 + 0.08) % 1;
  return new THREE.Color().setHSL(hue, 0.55, 0.58);
}

export class Viewer {
  constructor(container) {
    this.container = container;
    this.renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
    this.renderer.setPixelRatio(Math.min(window.devicePixelRatio || 1, 2));
    this.renderer.setClearColor(0x15171c);
    container.appendChild(this.renderer.domElement);
    this.scene = new THREE.Scene();
    this.camera = new THREE.PerspectiveCamera(40, 1, 0.01, 1000);
    this.controls = new OrbitControls(this.camera, this.renderer.domElement);
    this.controls.addEventListener('change', () => this.requestRender());
    this.scene.add(new THREE.HemisphereLight(0xffffff, 0x3a3a48, 1.6));
    this.sun = new THREE.DirectionalLight(0xffffff, 2.2);
    this.scene.add(this.sun);
    this.scene.add(this.sun.target);
    this.fill = new THREE.DirectionalLight(0xffffff, 0.6);
    this.scene.add(this.fill);

    this.kind = 'none';  // 'tree', 'recording' or 'glb'
    this.root = null;    // what was loaded, in the scene
    this.tree = null;    // readMeshTree result for a mesh tree
    this.replay = null;
    this.framing = null;       // ReplayFraming of a recording
    this.followBodies = true;  // the camera follows a recording's live bodies (the "Follow bodies" switch)
    this.depth = 0;
    this.explode = 0;
    this.showBonds = false;
    this.colourFragments = true;
    this.interiorMaterial = true;
    this.selected = null;  // tree node index, or Object3D of a recording body
    this.bondMesh = null;
    this.original = null;  // with `view --original`: the input drawn beside the tree's root (original.js)
    this.renderCount = 0;

    this.lastFrame = performance.now();
    this.needsRender = true;
    const resize = () => this.resize();
    window.addEventListener('resize', resize);
    resize();
    this.renderer.setAnimationLoop(() => this.frame());
  }

  resize() {
    const w = this.container.clientWidth || window.innerWidth;
    const h = this.container.clientHeight || window.innerHeight;
    this.renderer.setSize(w, h, false);
    this.camera.aspect = w / Math.max(h, 1);
    this.camera.updateProjectionMatrix();
    this.requestRender();
  }

  requestRender() { this.needsRender = true; }

  frame() {
    const now = performance.now();
    const dt = (now - this.lastFrame) / 1000;
    this.lastFrame = now;
    if (this.replay && this.replay.playing) {
      this.replay.advance(dt);
      this.needsRender = true;
    }
    if (!this.needsRender) return;
    this.needsRender = false;
    this.renderer.render(this.scene, this.camera);
    ++this.renderCount;
  }

  /** Parses GLB bytes (ArrayBuffer) into a glTF result; rejects with the loader's message. */
  static parse(buffer) {
    return new Promise((resolve, reject) => {
      new GLTFLoader().parse(buffer, '', resolve, (error) => reject(error instanceof Error ? error
        : new Error(String(error && error.message ? error.message : error))));
    });
  }

  /** Shows a loaded glTF result, replacing what was shown. */
  show(gltf) {
    this.clear();
    if (gltf.animations && gltf.animations.length > 0) {
      this.kind = 'recording';
      this.root = gltf.scene;
      this.replay = new Replay(gltf.scene, gltf.animations[0]);
      this.framing = new ReplayFraming(this.replay, gltf.scene);
      this.replay.onChange = () => {
        this.followReplay();
        this.requestRender();
      };
    } else if (isMeshTree(gltf)) {
      this.kind = 'tree';
      this.tree = readMeshTree(gltf);
      this.root = this.tree.group;
      this.depths = drawableDepths(this.tree);
      this.depth = this.depths.length ? this.depths[this.depths.length - 1] : 0;
    } else {
      this.kind = 'glb';
      this.root = gltf.scene;
    }
    this.prepareMaterials();
    this.scene.add(this.root);
    if (this.kind === 'tree') this.applyTree();
    this.frameCamera();
    this.requestRender();
  }

  clear() {
    if (this.root) {
      this.scene.remove(this.root);
      this.root.traverse((o) => {
        if (o.geometry) o.geometry.dispose();
      });
    }
    if (this.bondMesh) {
      this.scene.remove(this.bondMesh);
      this.bondMesh.geometry.dispose();
      this.bondMesh = null;
    }
    this.root = null;
    this.tree = null;
    this.replay = null;
    this.framing = null;
    this.selected = null;
    this.exteriorMaterial = null;
  }

  // Every primitive mesh gets its own material slot so colour and interior can be switched per fragment: the
  // fragment is the tree node (mesh tree), the body (recording) or the glTF node (other files).
  prepareMaterials() {
    let serial = 0;
    const owners = new Map();
    this.root.traverse((o) => {
      if (!o.isMesh) return;
      let key;
      if (this.kind === 'tree') key = o.userData.treeNode;
      else if (this.kind === 'recording') key = bodyOf(o) ? bodyOf(o).uuid : o.uuid;
      else key = o.parent && !o.parent.isScene ? o.parent.uuid : o.uuid;
      if (!owners.has(key)) owners.set(key, this.kind === 'tree' ? key : serial++);
      const colourIndex = owners.get(key);
      const original = o.material;
      const interior = original.name === INTERIOR;
      if (original.name === EXTERIOR && !this.exteriorMaterial) this.exteriorMaterial = original;
      o.userData.interior = interior;
      o.userData.originalMaterial = original;
      // A recording's floor is no fragment: it keeps its own material.
      o.userData.colourMaterial = this.kind === 'recording' && !bodyOf(o) ? original
        : new THREE.MeshStandardMaterial({ color: fragmentColour(colourIndex), roughness: 0.65, metalness: 0 });
    });
    this.applyMaterials();
  }

  // Each mesh's material from the switches: its fragment colour or the file's own material, caps in the file's
  // interior material or like the rest of the fragment; the selected fragment glows.
  applyMaterials() {
    if (!this.root) return;
    this.root.traverse((o) => {
      if (!o.isMesh || !o.userData.originalMaterial) return;
      const { interior, originalMaterial, colourMaterial } = o.userData;
      let material;
      if (interior && this.interiorMaterial) material = originalMaterial;
      else if (this.colourFragments) material = colourMaterial;
      else material = interior ? (this.exteriorMaterial || originalMaterial) : originalMaterial;
      if (this.isSelected(o)) {
        const glowing = o.userData.glowing || (o.userData.glowing = new Map());
        if (!glowing.has(material.uuid)) {
          const copy = material.clone();
          if (copy.emissive) {
            copy.emissive.setHex(0xff8800);
            copy.emissiveIntensity = 0.5;
          }
          glowing.set(material.uuid, copy);
        }
        material = glowing.get(material.uuid);
      }
      o.material = material;
    });
    this.requestRender();
  }

  isSelected(mesh) {
    if (this.selected === null) return false;
    if (this.kind === 'tree') return mesh.userData.treeNode === this.selected;
    if (this.kind === 'recording') return bodyOf(mesh) === this.selected;
    return mesh === this.selected;
  }

  setColourFragments(on) { this.colourFragments = on; this.applyMaterials(); }
  setInteriorMaterial(on) { this.interiorMaterial = on; this.applyMaterials(); }

  // --- mesh tree controls ------------------------------------------------------

  /** The tree nodes shown now (solid cut at the current depth), as records. */
  shownNodes() { return this.tree ? nodesAtDepth(this.tree, this.depth) : []; }

  setDepth(depth) {
    this.depth = depth;
    if (this.selected !== null && this.kind === 'tree' && !this.shownNodes().some((n) => n.index === this.selected)) {
      this.selected = null;
    }
    this.applyTree();
  }

  setExplode(amount) { this.explode = amount; this.applyTree(); }
  setShowBonds(on) { this.showBonds = on; this.applyTree(); }

  applyTree() {
    if (!this.tree) return;
    const shown = new Set(this.shownNodes().map((n) => n.index));
    for (const node of this.tree.nodes) {
      if (!node.object) continue;
      node.object.visible = shown.has(node.index);
      node.object.position.copy(explodeOffset(this.tree, node, this.explode));
      node.object.updateMatrixWorld(true);
    }
    this.updateBonds();
    this.applyMaterials();
  }

  // The bond overlay: for each bond between two shown nodes, a segment from one node's (exploded) centroid through
  // the bond's centroid to the other's, its radius growing with the square root of the bond's area. Drawn over the
  // fragments (no depth test), since bonds lie inside the solid.
  updateBonds() {
    if (this.bondMesh) {
      this.scene.remove(this.bondMesh);
      this.bondMesh.geometry.dispose();
      this.bondMesh = null;
    }
    if (!this.showBonds || !this.tree) return;
    const segments = crossingBonds(this.tree, this.shownNodes());
    if (segments.length === 0) return;
    const size = this.tree.nodes[0].object ? new THREE.Box3().setFromObject(this.tree.group).getSize(new THREE.Vector3()).length()
      : 1;
    const maxArea = segments.reduce((m, s) => Math.max(m, s.bond.area), 0) || 1;
    const geometry = new THREE.CylinderGeometry(1, 1, 1, 8, 1, false);
    const material = new THREE.MeshBasicMaterial({ color: BOND_COLOUR, depthTest: false, transparent: true, opacity: 0.9 });
    const mesh = new THREE.InstancedMesh(geometry, material, 2 * segments.length);
    mesh.renderOrder = 10;
    mesh.name = 'bonds';
    mesh.userData.bondCount = segments.length;
    const up = new THREE.Vector3(0, 1, 0);
    const matrix = new THREE.Matrix4();
    const q = new THREE.Quaternion();
    let i = 0;
    const place = (from, to, radius) => {
      const d = to.clone().sub(from);
      const length = Math.max(d.length(), 1e-12);
      q.setFromUnitVectors(up, d.clone().divideScalar(length));
      matrix.compose(from.clone().add(to).multiplyScalar(0.5), q, new THREE.Vector3(radius, length, radius));
      mesh.setMatrixAt(i++, matrix);
    };
    for (const { bond, a, b } of segments) {
      const offsetA = explodeOffset(this.tree, a, this.explode);
      const offsetB = explodeOffset(this.tree, b, this.explode);
      const pa = a.centroid.clone().add(offsetA);
      const pb = b.centroid.clone().add(offsetB);
      const pm = bond.centroid.clone().add(offsetA.clone().add(offsetB).multiplyScalar(0.5));
      const radius = size * (0.0008 + 0.004 * Math.sqrt(bond.area / maxArea));
      place(pa, pm, radius);
      place(pm, pb, radius);
    }
    mesh.instanceMatrix.needsUpdate = true;
    this.bondMesh = mesh;
    this.scene.add(mesh);
  }

  // --- the original input (view --original) ------------------------------------------

  /** Adds the original input (an originalObject, hidden) to the scene; it stays across trees the editor loads. */
  setOriginal(object) {
    if (this.original) this.scene.remove(this.original);
    this.original = object;
    this.scene.add(object);
  }

  /** Shows the original beside the tree's root (to its left) and frames both, or hides it and frames the tree. */
  setShowOriginal(on) {
    if (!this.original) return;
    if (on && this.tree && this.tree.nodes[0] && this.tree.nodes[0].object) {
      const rootBox = new THREE.Box3().setFromObject(this.tree.nodes[0].object);
      const box = { min: rootBox.min.toArray(), max: rootBox.max.toArray() };
      this.original.position.fromArray(besideOffset(box, this.original.userData.box));
    }
    this.original.visible = on;
    this.original.updateMatrixWorld(true);
    this.frameCamera();
  }

  // --- picking -----------------------------------------------------------------

  /** The fragment under the canvas pixel (x, y) (CSS pixels from its top left), or null. */
  pickAt(x, y) {
    if (!this.root) return null;
    const rect = this.renderer.domElement.getBoundingClientRect();
    const ndc = new THREE.Vector2((x / rect.width) * 2 - 1, -(y / rect.height) * 2 + 1);
    const raycaster = new THREE.Raycaster();
    raycaster.setFromCamera(ndc, this.camera);
    this.root.updateMatrixWorld(true);
    const hits = raycaster.intersectObject(this.root, true).filter((h) => h.object.isMesh && isShown(h.object));
    if (hits.length === 0) return null;
    const object = hits[0].object;
    if (this.kind === 'tree') return object.userData.treeNode;
    if (this.kind === 'recording') return bodyOf(object) || object;
    return object;
  }

  select(target) {
    this.selected = target;
    this.applyMaterials();
  }

  /** The bonds crossing a tree node's boundary, as `shatter info --nodes` lists them. */
  bondsOf(index) { return bondsOfNode(this.tree, this.tree.nodes[index]); }

  // --- camera ------------------------------------------------------------------

  frameCamera() {
    if (!this.root) return;
    this.root.updateMatrixWorld(true);
    const box = new THREE.Box3();
    this.root.traverse((o) => {
      if (o.isMesh && o.name !== 'floor' && !(o.parent && o.parent.name === 'floor') && isShown(o)) box.expandByObject(o);
    });
    if (box.isEmpty()) box.setFromObject(this.root);
    const beside = this.original && this.original.visible;
    if (beside) box.expandByObject(this.original);
    const centre = box.getCenter(new THREE.Vector3());
    // Two objects side by side reach the edges where the panels cover them: a margin keeps both clear.
    const radius = Math.max(box.getSize(new THREE.Vector3()).length() / 2, 1e-6) * (beside ? 1.3 : 1);
    this.placeCamera(centre, radius, DEFAULT_VIEW_DIRECTION);
  }

  // Looks at the sphere (centre, radius) from `direction` (unit, from the centre towards the camera) so it fills the
  // view, with the lights placed around it.
  placeCamera(centre, radius, direction) {
    const distance = fitDistance(radius, this.camera.fov, this.camera.aspect);
    this.camera.position.copy(centre).addScaledVector(direction, distance);
    this.camera.near = distance / 100;
    this.camera.far = distance * 100;
    this.camera.updateProjectionMatrix();
    this.controls.target.copy(centre);
    this.controls.update();
    this.sun.position.copy(centre).add(new THREE.Vector3(1, 2, 1.5).multiplyScalar(radius * 4));
    this.sun.target.position.copy(centre);
    this.fill.position.copy(centre).add(new THREE.Vector3(-1.5, -0.5, -1).multiplyScalar(radius * 4));
    this.requestRender();
  }

  /** Turns following a recording's bodies on (the camera goes to them now) or off (the camera stays where it is). */
  setFollowBodies(on) {
    this.followBodies = on;
    this.followReplay();
  }

  // With following on, frames the bodies alive at the replay's time (framing.js), seen from the direction the user
  // has orbited to: following sets where the camera looks and how far it is, the user still turns it.
  followReplay() {
    if (!this.followBodies || !this.replay || !this.framing || this.framing.empty) return;
    const { centre, radius } = this.framing.at(this.replay.time);
    const direction = this.camera.position.clone().sub(this.controls.target);
    if (direction.lengthSq() === 0) direction.copy(DEFAULT_VIEW_DIRECTION);
    this.placeCamera(centre, radius, direction.normalize());
  }

  /** Where a world point lands on the canvas, in CSS pixels from its top left. */
  toScreen(point) {
    const rect = this.renderer.domElement.getBoundingClientRect();
    const p = point.clone().project(this.camera);
    return { x: (p.x + 1) / 2 * rect.width, y: (1 - p.y) / 2 * rect.height };
  }

  /**
   * A canvas pixel where picking finds `target` (a tree node index), or null: tried at the screen positions of its
   * triangles' centres, nearest the screen centre of the node first.
   */
  pixelOf(target) {
    const node = this.tree.nodes[target];
    if (!node || !node.object || !node.object.visible) return null;
    const candidates = [];
    node.object.updateMatrixWorld(true);
    for (const mesh of node.object.children) {
      const position = mesh.geometry.attributes.position;
      const index = mesh.geometry.index;
      const triangles = index ? index.count / 3 : position.count / 3;
      const step = Math.max(1, Math.floor(triangles / 200));
      for (let t = 0; t < triangles; t += step) {
        const c = new THREE.Vector3();
        for (let k = 0; k < 3; ++k) {
          const v = index ? index.getX(3 * t + k) : 3 * t + k;
          c.add(new THREE.Vector3().fromBufferAttribute(position, v));
        }
        candidates.push(c.divideScalar(3).applyMatrix4(mesh.matrixWorld));
      }
    }
    const rect = this.renderer.domElement.getBoundingClientRect();
    for (const p of candidates) {
      const s = this.toScreen(p);
      if (s.x < 1 || s.y < 1 || s.x > rect.width - 1 || s.y > rect.height - 1) continue;
      if (this.pickAt(s.x, s.y) === target) return s;
    }
    return null;
  }
}

// The recording body a mesh belongs to: the ancestor whose extras name a body.
export function bodyOf(object) {
  for (let o = object; o; o = o.parent) {
    if (o.userData && Number.isInteger(o.userData.body)) return o;
  }
  return null;
}

// Visible all the way up, and not scaled to nothing (a recording hides bodies before their birth by a zero scale).
function isShown(object) {
  for (let o = object; o; o = o.parent) {
    if (!o.visible) return false;
    if (o.scale.x === 0 && o.scale.y === 0 && o.scale.z === 0) return false;
  }
  return true;
}
