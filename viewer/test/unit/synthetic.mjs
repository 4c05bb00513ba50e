// Synthetic mesh trees for the unit tests, written as the GLB `shatter export`
// writes (formats/src/export.cpp): glTF node i is tree node i with its extras
// (tree_node, depth, first_leaf, leaf_count, leaf, volume, centroid, triangles,
// cap_triangles), children nested as in the tree, a mesh only on the selected
// nodes (one primitive, or an "exterior" and an "interior" one), and the bonds
// in the scene's extras. They are parsed by three.js's own GLTFLoader, so the
// tests see the objects the page sees: a one-primitive node is the Mesh itself
// with its child nodes below it, a two-primitive node a Group.
//
// Recordings are built the way GLTFLoader shows a `simulate --record` file
// (runtime/recording.hpp): a node per body with its mesh, linear translation
// keys, and a stepped scale channel that shows it from its birth to its death.
//
// Everything is drawn from a seeded generator, so a failure names a seed that
// reproduces it.

/** A seeded generator (mulberry32): next() in [0, 1), int(lo, hi) inclusive, pick, shuffle. */
export function randomSource(seed) {
  let state = seed >>> 0;
  const next = () => {
    state = (state + 0x6d2b79f5) >>> 0;
    let t = state;
    t = Math.imul(t ^ (t >>> 15), t | 1);
    t ^= t + Math.imul(t ^ (t >>> 7), t | 61);
    return ((t ^ (t >>> 14)) >>> 0) / 4294967296;
  };
  const int = (lo, hi) => lo + Math.floor(next() * (hi - lo + 1));
  return {
    next,
    int,
    pick: (array) => array[int(0, array.length - 1)],
    shuffle(array) {
      for (let i = array.length - 1; i > 0; --i) {
        const j = int(0, i);
        [array[i], array[j]] = [array[j], array[i]];
      }
      return array;
    },
  };
}

// How a node's leaves are split among its children; each shape gives other depths and other leaves above the
// deepest level (where nodesAtDepth must take the leaves along).
const SPLITTERS = {
  balanced: (n) => [Math.floor(n / 2), n - Math.floor(n / 2)],
  caterpillar: (n, random) => (random.next() < 0.5 ? [1, n - 1] : [n - 1, 1]),
  wide: (n, random) => {
    const arity = Math.min(n, random.int(2, 4));
    return Array.from({ length: arity }, (_, i) => Math.floor((n * (i + 1)) / arity) - Math.floor((n * i) / arity));
  },
  random: (n, random) => {
    const arity = Math.min(n, random.int(2, 3));
    const cuts = new Set();
    while (cuts.size < arity - 1) cuts.add(random.int(1, n - 1));
    const bounds = [0, ...[...cuts].sort((a, b) => a - b), n];
    return bounds.slice(1).map((b, i) => b - bounds[i]);
  },
};

export const TREE_SHAPES = ['single', ...Object.keys(SPLITTERS)];
export const NUMBERINGS = ['preorder', 'breadth', 'shuffled'];
export const MESH_SELECTIONS = ['all', 'leaves', 'some'];

// Dyadic coordinates (multiples of 1/8, 1/64 for inner nodes) survive float32 and the octahedron's box exactly.
const gridCoordinate = (random) => random.int(-32, 32) / 8;

/**
 * A random mesh tree: {nodes: [{index, depth, firstLeaf, leafCount, isLeaf, children, volume, centroid,
 * triangles, capTriangles}] in index order (root 0), bonds: [{first, second, cutNode, area, centroid, normal}],
 * leafCount, maxDepth, label}. `shape` is one of TREE_SHAPES, `numbering` one of NUMBERINGS.
 */
export function makeTree(random, { shape, leaves, numbering }) {
  const leafCount = shape === 'single' ? 1 : leaves;
  const build = (firstLeaf, count, depth) => {
    const node = { firstLeaf, leafCount: count, depth, children: [] };
    if (count > 1) {
      let first = firstLeaf;
      for (const size of SPLITTERS[shape](count, random)) {
        node.children.push(build(first, size, depth + 1));
        first += size;
      }
    }
    return node;
  };
  const root = build(0, leafCount, 0);

  const order = [];
  if (numbering === 'breadth') {
    for (let queue = [root]; queue.length;) {
      const node = queue.shift();
      order.push(node);
      queue = queue.concat(node.children);
    }
  } else {
    const visit = (node) => { order.push(node); node.children.forEach(visit); };
    visit(root);
    if (numbering === 'shuffled') order.splice(1, order.length - 1, ...random.shuffle(order.slice(1)));
  }
  order.forEach((node, i) => { node.index = i; });

  const fill = (node) => {
    node.isLeaf = node.children.length === 0;
    if (node.isLeaf) {
      node.volume = random.int(1, 16) / 8;
      node.centroid = [gridCoordinate(random), gridCoordinate(random), gridCoordinate(random)];
    } else {
      node.children.forEach(fill);
      node.volume = node.children.reduce((sum, c) => sum + c.volume, 0);
      // The volume-weighted mean, kept on a 1/64 grid so the octahedron drawn around it has it as its box centre.
      node.centroid = [0, 1, 2].map((k) => Math.round(64 * node.children.reduce((sum, c) => sum + c.volume * c.centroid[k], 0)
        / node.volume) / 64 + 0);  // + 0: JSON has no -0
    }
    node.triangles = random.int(4, 400);
    node.capTriangles = random.int(0, node.triangles);
  };
  fill(root);

  const nodes = order.map((node) => ({ ...node, children: node.children.map((c) => c.index) }));
  const leafNodes = nodes.filter((n) => n.isLeaf).sort((a, b) => a.firstLeaf - b.firstLeaf);
  // The node whose cut separated two leaves: the deepest whose range holds both.
  const cutNodeOf = (a, b) => nodes.filter((n) => a >= n.firstLeaf && a < n.firstLeaf + n.leafCount
    && b >= n.firstLeaf && b < n.firstLeaf + n.leafCount).reduce((deepest, n) => (n.depth > deepest.depth ? n : deepest));
  const bonds = [];
  const seen = new Set();
  for (let attempt = 0; leafCount > 1 && attempt < 2 * leafCount; ++attempt) {
    const first = random.int(0, leafCount - 1);
    const second = random.int(0, leafCount - 1);
    const key = `${Math.min(first, second)}-${Math.max(first, second)}`;
    if (first === second || seen.has(key)) continue;
    seen.add(key);
    const axis = random.int(0, 2);
    bonds.push({
      first, second, cutNode: cutNodeOf(first, second).index, area: random.int(1, 64) / 16,
      centroid: leafNodes[first].centroid.map((v, k) => (v + leafNodes[second].centroid[k]) / 2),
      normal: [0, 1, 2].map((k) => (k === axis ? 1 : 0)),
    });
  }
  const maxDepth = nodes.reduce((m, n) => Math.max(m, n.depth), 0);
  return { nodes, bonds, leafCount, maxDepth, label: `${shape} tree, ${leafCount} leaves, ${numbering} numbering` };
}

/** The test trees: every shape and numbering, at several sizes, from `seed`. */
export function sampleTrees(seed, count = 36) {
  const random = randomSource(seed);
  const trees = [];
  for (let i = 0; i < count; ++i) {
    const shape = TREE_SHAPES[i % TREE_SHAPES.length];
    const numbering = NUMBERINGS[Math.floor(i / TREE_SHAPES.length) % NUMBERINGS.length];
    const tree = makeTree(random, { shape, numbering, leaves: random.int(2, 40) });
    tree.label = `seed ${seed}, tree ${i}: ${tree.label}`;
    trees.push(tree);
  }
  return trees;
}

// --- GLB ----------------------------------------------------------------------------------------

// An octahedron around `centre` (half-size 1/4): its bounding box's centre is `centre` exactly.
const OCTAHEDRON_DIRECTIONS = [[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]];
const OCTAHEDRON_FACES = [[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]];

/** The glTF JSON and binary chunk of a GLB with the given meshes (see encodeTreeGlb). */
class GlbWriter {
  constructor() {
    this.json = {
      asset: { version: '2.0', generator: 'shatter viewer unit tests' },
      scene: 0, scenes: [], nodes: [], meshes: [], accessors: [], bufferViews: [], buffers: [],
      materials: [{ name: 'exterior' }, { name: 'interior' }],
    };
    this.chunks = [];
    this.length = 0;
  }

  view(bytes, target) {
    const padding = (4 - (this.length % 4)) % 4;
    if (padding) this.chunks.push(Buffer.alloc(padding));
    this.length += padding;
    this.json.bufferViews.push({ buffer: 0, byteOffset: this.length, byteLength: bytes.length, target });
    this.chunks.push(bytes);
    this.length += bytes.length;
    return this.json.bufferViews.length - 1;
  }

  accessor(definition) {
    this.json.accessors.push(definition);
    return this.json.accessors.length - 1;
  }

  /** A mesh: an octahedron around `centre`, in one primitive or two (exterior and interior faces). */
  octahedron(centre, primitives, name) {
    const positions = new Float32Array(OCTAHEDRON_DIRECTIONS.flatMap((d) => d.map((v, k) => centre[k] + v / 4)));
    const normals = new Float32Array(OCTAHEDRON_DIRECTIONS.flat());
    const position = this.accessor({
      bufferView: this.view(Buffer.from(positions.buffer), 34962), componentType: 5126, count: 6, type: 'VEC3',
      min: centre.map((v) => v - 0.25), max: centre.map((v) => v + 0.25),
    });
    const normal = this.accessor({ bufferView: this.view(Buffer.from(normals.buffer), 34962), componentType: 5126,
      count: 6, type: 'VEC3' });
    const groups = primitives === 1 ? [OCTAHEDRON_FACES] : [OCTAHEDRON_FACES.slice(0, 4), OCTAHEDRON_FACES.slice(4)];
    this.json.meshes.push({
      name,
      primitives: groups.map((faces, material) => {
        const indices = new Uint16Array(faces.flat());
        return {
          attributes: { POSITION: position, NORMAL: normal },
          indices: this.accessor({ bufferView: this.view(Buffer.from(indices.buffer), 34963), componentType: 5123,
            count: indices.length, type: 'SCALAR' }),
          material,
        };
      }),
    });
    return this.json.meshes.length - 1;
  }

  bytes() {
    const bin = Buffer.concat(this.chunks);
    const binPadded = Buffer.concat([bin, Buffer.alloc((4 - (bin.length % 4)) % 4)]);
    if (binPadded.length) this.json.buffers.push({ byteLength: binPadded.length });
    else delete this.json.buffers;
    const text = Buffer.from(JSON.stringify(this.json), 'utf8');
    const jsonPadded = Buffer.concat([text, Buffer.alloc((4 - (text.length % 4)) % 4, 0x20)]);
    const chunk = (type, data) => {
      const header = Buffer.alloc(8);
      header.writeUInt32LE(data.length, 0);
      header.writeUInt32LE(type, 4);
      return Buffer.concat([header, data]);
    };
    const body = Buffer.concat([chunk(0x4e4f534a, jsonPadded), ...(binPadded.length ? [chunk(0x004e4942, binPadded)] : [])]);
    const header = Buffer.alloc(12);
    header.writeUInt32LE(0x46546c67, 0);
    header.writeUInt32LE(2, 4);
    header.writeUInt32LE(12 + body.length, 8);
    const glb = Buffer.concat([header, body]);
    return glb.buffer.slice(glb.byteOffset, glb.byteOffset + glb.byteLength);
  }
}

/**
 * A tree as the GLB `shatter export` writes: returns {glb (ArrayBuffer), primitives (Map node index -> 1 or 2 for
 * the nodes that have a mesh)}. `meshes`: 'all', 'leaves' or 'some' (a random subset); `withCentroids` false drops
 * the centroid extras (files written before they were exported); `edit(json)` may change the glTF JSON before it
 * is written, to make malformed files.
 */
export function encodeTreeGlb(tree, { random, meshes = 'all', withCentroids = true, edit = () => {} }) {
  const writer = new GlbWriter();
  const primitives = new Map();
  for (const node of tree.nodes) {
    const extras = {
      tree_node: node.index, depth: node.depth, first_leaf: node.firstLeaf, leaf_count: node.leafCount,
      volume: node.volume, triangles: node.triangles, cap_triangles: node.capTriangles,
    };
    if (withCentroids) extras.centroid = node.centroid;
    if (node.isLeaf) extras.leaf = node.firstLeaf;
    const name = node.isLeaf ? `leaf ${node.firstLeaf}` : `node ${node.index}`;
    const gltfNode = { name, extras };
    if (node.children.length) gltfNode.children = node.children;
    const selected = meshes === 'all' || (meshes === 'leaves' && node.isLeaf) || (meshes === 'some' && random.next() < 0.6);
    if (selected) {
      const count = random.int(1, 2);
      primitives.set(node.index, count);
      gltfNode.mesh = writer.octahedron(node.centroid, count, name);
    }
    writer.json.nodes.push(gltfNode);
  }
  writer.json.scenes.push({
    name: 'mesh tree',
    nodes: tree.nodes.length ? [0] : [],
    extras: {
      shatter_version: 'unit-test', leaves: tree.leafCount,
      bonds: tree.bonds.map((b) => ({ first: b.first, second: b.second, cut_node: b.cutNode, area: b.area,
        centroid: b.centroid, normal: b.normal })),
    },
  });
  edit(writer.json);
  return { glb: writer.bytes(), primitives };
}

/** A GLB that is no mesh tree: `count` plain meshes without extras, as another program would write. */
export function encodePlainGlb(count) {
  const writer = new GlbWriter();
  for (let i = 0; i < count; ++i) writer.json.nodes.push({ name: `mesh ${i}`, mesh: writer.octahedron([i, 0, 0], 1, `m${i}`) });
  writer.json.scenes.push({ nodes: writer.json.nodes.map((_, i) => i) });
  return writer.bytes();
}

/** Parses GLB bytes with three.js's GLTFLoader, as the page does (Viewer.parse). */
export function parseGlb(GLTFLoader, glb) {
  return new Promise((resolve, reject) => new GLTFLoader().parse(glb, '', resolve, reject));
}

// --- recordings ------------------------------------------------------------------------------------

/**
 * A recording of unit cubes: {root, clip, duration, bodies: [{object, times, positions (float32, as the track stores
 * them), birth, death}]}. `three` is the three.js the viewer's modules use. `motion`:
 *   'random'  positions drawn at random per key; bodies born and dying at random key times
 *   'static'  each body at one place, alive throughout
 *   'linear'  every body at one velocity (the same for all), alive throughout
 *   'birth'   body 0 at the origin throughout, the others born at `birthKey`'s time 40 to 60 m away
 * `kind`, when given, is a function of the body's index giving its extras' kind ("cluster" or "sphere"), as a
 * `simulate --record` file names them; without it the bodies name no kind.
 */
export function makeRecording(three, random, { bodies: bodyCount, motion = 'random', keyCount = random.int(2, 12),
  step = random.int(1, 8) / 64, birthKey = 1, kind = null }) {
  const root = new three.Group();
  const tracks = [];
  const bodies = [];
  const times = Array.from({ length: keyCount }, (_, i) => i * step);
  const velocity = [0, 1, 2].map(() => random.int(-80, 80) / 4);
  for (let b = 0; b < bodyCount; ++b) {
    const object = new three.Object3D();
    object.name = `body ${b}`;
    object.userData.body = b;
    if (kind) object.userData.kind = kind(b);
    object.add(new three.Mesh(new three.BoxGeometry(1, 1, 1)));
    root.add(object);
    const start = [0, 1, 2].map(() => random.int(-400, 400) / 7);
    let place;
    if (motion === 'random') place = () => [0, 1, 2].map(() => random.int(-400, 400) / 7);
    else if (motion === 'static') place = () => start;
    else if (motion === 'linear') place = (t) => start.map((v, k) => v + velocity[k] * t);
    else place = () => (b === 0 ? [0, 0, 0] : [random.int(40, 60), 0, 0]);
    const far = motion === 'birth' ? place() : null;
    const positions = Float32Array.from(times.flatMap((t) => far || place(t)));
    tracks.push(new three.VectorKeyframeTrack(`${object.name}.position`, times, positions));
    let birth = 0;
    let death = Infinity;
    if (motion === 'random') {
      const bornAt = random.int(0, keyCount - 2);
      const diesAt = random.next() < 0.5 ? keyCount : random.int(bornAt + 1, keyCount - 1);
      birth = times[bornAt];
      death = diesAt < keyCount ? times[diesAt] : Infinity;
    } else if (motion === 'birth' && b > 0) {
      birth = times[birthKey];
    }
    const scaleTimes = [0, birth, ...(death < Infinity ? [death] : [])].filter((t, i, all) => all.indexOf(t) === i);
    const scaleValues = scaleTimes.flatMap((t) => (t >= birth && t < death ? [1, 1, 1] : [0, 0, 0]));
    tracks.push(new three.VectorKeyframeTrack(`${object.name}.scale`, scaleTimes, scaleValues, three.InterpolateDiscrete));
    bodies.push({ object, times, positions, birth, death });
  }
  const clip = new three.AnimationClip('simulation', -1, tracks);
  return { root, clip, bodies, duration: times.at(-1) };
}
