// The viewer page: finds its data (inline in a file written by `shatter export
// --format html`, or from the `shatter view` server), shows it and wires the
// controls. Any failure ends as a message on the page, never a blank page.
// `window.shatterViewer` exposes the state for the browser tests
// (viewer/test/) and for anyone scripting the page from the console.

import * as THREE from 'three';

import { Viewer, bodyOf } from './viewer.js';
import { Editor, errorOf } from './editor.js';
import { ORIGINAL_COLOURS, originalObject, readOriginal } from './original.js';

const $ = (id) => document.getElementById(id);

function showError(text) {
  const box = $('message');
  box.textContent = text;
  box.hidden = false;
}

function config() {
  const element = $('shatter-config');
  if (!element) return { mode: 'none' };
  return JSON.parse(element.textContent);
}

function base64Bytes(text) {
  const binary = atob(text.replace(/\s+/g, ''));
  const bytes = new Uint8Array(binary.length);
  for (let i = 0; i < binary.length; ++i) bytes[i] = binary.charCodeAt(i);
  return bytes.buffer;
}

async function fetchBytes(url) {
  const response = await fetch(url, { cache: 'no-store' });
  if (!response.ok) throw new Error(`${url}: ${await errorOf(response)}`);
  return response.arrayBuffer();
}

const format = (x, digits = 6) => (typeof x === 'number' ? Number(x.toPrecision(digits)).toString() : String(x));

// One table row; the exact value (JavaScript's shortest round-trip form) is kept in data-value for scripts.
function row(name, field, value, shown = format(value)) {
  return `<tr><td>${name}</td><td data-field="${field}" data-value="${value}">${shown}</td></tr>`;
}

function describeTreeNode(viewer, index) {
  const node = viewer.tree.nodes[index];
  const bonds = viewer.bondsOf(index);
  const title = node.isLeaf ? `Fragment: leaf ${node.firstLeaf}` : `Node ${index} (leaves ${node.firstLeaf}–${node.firstLeaf + node.leafCount - 1})`;
  const c = node.centroid;
  let html = `<div><b data-field="title">${title}</b></div><table>`;
  html += row('tree node', 'node', index);
  if (node.isLeaf) html += row('leaf', 'leaf', node.firstLeaf);
  html += row('depth', 'depth', node.depth);
  html += row('volume', 'volume', node.volume);
  html += row('centroid', 'centroid', [c.x, c.y, c.z].join(','), [c.x, c.y, c.z].map((v) => format(v, 4)).join(', '));
  html += row('triangles', 'triangles', node.triangles);
  html += row('on caps', 'cap_triangles', node.capTriangles);
  html += row('bonds', 'bond_count', bonds.length);
  html += row('bond area', 'bond_area', bonds.reduce((s, b) => s + b.area, 0));
  html += '</table>';
  if (bonds.length) {
    html += '<ul class="bonds" data-field="bonds">';
    for (const b of bonds) {
      const inner = node.isLeaf ? '' : `leaf ${b.leaf} – `;
      html += `<li data-leaf="${b.leaf}" data-other="${b.other}" data-area="${b.area}">${inner}leaf ${b.other}: area ${format(b.area, 4)}</li>`;
    }
    html += '</ul>';
  }
  return html;
}

function describeBody(body) {
  const e = body.userData;
  let html = `<div><b data-field="title">${e.kind === 'sphere' ? 'Projectile' : 'Body'} ${e.body}</b></div><table>`;
  if (e.kind === 'cluster') {
    html += row('object', 'object', e.object);
    html += row('leaves', 'leaves', e.leaves);
    if (e.parent !== undefined) html += row('broke off body', 'parent', e.parent);
  }
  html += row('mass (kg)', 'mass', e.mass);
  html += row('born at (s)', 'birth_time', e.birth_time);
  if (e.death_time !== undefined) html += row('broke at (s)', 'death_time', e.death_time);
  return `${html}</table>`;
}

function showSelection(viewer, target) {
  const body = $('info-body');
  if (target === null || target === undefined) {
    $('info-empty').hidden = false;
    body.hidden = true;
    body.innerHTML = '';
    return;
  }
  if (viewer.kind === 'tree') body.innerHTML = describeTreeNode(viewer, target);
  else if (target.userData && Number.isInteger(target.userData.body)) body.innerHTML = describeBody(target);
  else body.innerHTML = `<div><b data-field="title">${target.name || 'mesh'}</b></div>`;
  $('info-empty').hidden = true;
  body.hidden = false;
}

function wireControls(viewer) {
  $('explode').addEventListener('input', (e) => {
    viewer.setExplode(Number(e.target.value));
    $('explode-value').textContent = Number(e.target.value).toFixed(2);
  });
  $('depth').addEventListener('input', (e) => {
    const depth = viewer.depths[Number(e.target.value)];
    viewer.setDepth(depth);
    updateDepthLabel(viewer);
    showSelection(viewer, viewer.selected);
  });
  $('show-bonds').addEventListener('change', (e) => viewer.setShowBonds(e.target.checked));
  $('colour-fragments').addEventListener('change', (e) => viewer.setColourFragments(e.target.checked));
  $('interior-material').addEventListener('change', (e) => viewer.setInteriorMaterial(e.target.checked));

  // A click (not the end of an orbit drag) picks the fragment under the pointer.
  const canvas = viewer.renderer.domElement;
  let down = null;
  canvas.addEventListener('pointerdown', (e) => { down = { x: e.clientX, y: e.clientY }; });
  canvas.addEventListener('pointerup', (e) => {
    if (!down || Math.hypot(e.clientX - down.x, e.clientY - down.y) > 4) return;
    const rect = canvas.getBoundingClientRect();
    const target = viewer.pickAt(e.clientX - rect.left, e.clientY - rect.top);
    viewer.select(target);
    showSelection(viewer, target);
  });

  $('play').addEventListener('click', () => {
    if (!viewer.replay) return;
    if (viewer.replay.playing) viewer.replay.pause();
    else viewer.replay.play();
    $('play').textContent = viewer.replay.playing ? 'Pause' : 'Play';
  });
  $('follow-bodies').addEventListener('change', (e) => viewer.setFollowBodies(e.target.checked));
  $('time').addEventListener('input', (e) => {
    if (!viewer.replay) return;
    viewer.replay.pause();
    $('play').textContent = 'Play';
    viewer.replay.seek(Number(e.target.value));
  });
}

function updateDepthLabel(viewer) {
  const shown = viewer.shownNodes().length;
  $('depth-value').textContent = `${viewer.depth} (${shown} ${shown === 1 ? 'piece' : 'pieces'})`;
}

// Sets the controls to what was just loaded.
function presentModel(viewer, name) {
  $('file-name').textContent = name;
  $('tree-controls').hidden = viewer.kind !== 'tree';
  $('timeline').hidden = viewer.kind !== 'recording';
  showSelection(viewer, null);
  let summary = '';
  if (viewer.kind === 'tree') {
    const t = viewer.tree;
    summary = `Mesh tree: ${t.nodes.length} nodes, ${t.leafCount} fragments, depth ${t.maxDepth}, ${t.bonds.length} bonds`;
    if (t.version) summary += `; shatter ${t.version}`;
    const depth = $('depth');
    depth.min = 0;
    depth.max = Math.max(viewer.depths.length - 1, 0);
    depth.value = depth.max;
    depth.disabled = viewer.depths.length < 2;
    $('depth-hint').textContent = viewer.depths.length < 2
      ? 'This file holds the fragments only (export with --nodes all for every level).' : '';
    updateDepthLabel(viewer);
    viewer.setExplode(Number($('explode').value));
    viewer.setShowBonds($('show-bonds').checked);
  } else if (viewer.kind === 'recording') {
    const r = viewer.replay;
    let bodies = 0;
    viewer.root.traverse((o) => { if (o.userData && Number.isInteger(o.userData.body)) ++bodies; });
    summary = `Simulation recording: ${bodies} bodies, ${r.duration.toFixed(3)} s`;
    const time = $('time');
    time.max = r.duration;
    time.value = 0;
    r.onTime = (t) => {
      time.value = t;
      $('time-value').textContent = `${t.toFixed(3)} s`;
      if (!r.playing) $('play').textContent = 'Play';
    };
    viewer.setFollowBodies($('follow-bodies').checked);
    r.seek(0);
  } else {
    summary = 'glTF file (not a shatter mesh tree or recording).';
  }
  $('summary').textContent = summary;
  viewer.setColourFragments($('colour-fragments').checked);
  viewer.setInteriorMaterial($('interior-material').checked);
}

// The "Original input" panel (`shatter view TREE --original MESH`, or a page from `export --format html --original
// MESH`): the file's name, what validation finds in it with a colour key and counts, and the repair the tree records,
// one line per change.
function presentOriginal(original) {
  $('original').hidden = false;
  $('original-name').textContent = `${original.file}: ${original.triangles} triangles, ${original.vertices} vertices`;
  $('original-validation').textContent = original.validation === 'valid' ? 'Valid as read.'
    : `As read: ${original.validation}.`;
  const legend = $('original-legend');
  legend.replaceChildren();
  const key = (colour, text, field, count) => {
    const item = document.createElement('li');
    item.dataset.field = field;
    item.dataset.value = String(count);
    const swatch = document.createElement('span');
    swatch.className = 'swatch';
    swatch.style.background = `#${colour.toString(16).padStart(6, '0')}`;
    item.append(swatch, `${text}: ${count}`);
    legend.append(item);
  };
  key(ORIGINAL_COLOURS.boundary, 'boundary (open) edges', 'boundary_edges', original.boundaryEdges.length / 2);
  key(ORIGINAL_COLOURS.nonManifold, 'non-manifold edges', 'non_manifold_edges', original.nonManifoldEdges.length / 2);
  key(ORIGINAL_COLOURS.selfIntersecting, 'self-intersecting triangles', 'self_intersecting_triangles',
    original.selfIntersecting.length);
  const repair = $('original-repair');
  repair.replaceChildren();
  const line = (text, field) => {
    const item = document.createElement('li');
    item.dataset.field = field;
    item.textContent = text;
    repair.append(item);
  };
  if (original.repair) {
    $('original-repair-title').textContent = `Repaired before the build (${original.repair.trianglesBefore} triangles, `
      + `${original.repair.trianglesAfter} after):`;
    for (const change of original.repair.changes) line(change, 'repair');
    for (const note of original.repair.notDone) line(`not done: ${note}`, 'repair_not_done');
  } else {
    $('original-repair-title').textContent = 'The tree records no repair: its root is this file as read.';
  }
  for (const warning of original.readWarnings) line(`read: ${warning}`, 'read_warning');
}

// Shows the original beside the tree's root (the tree cut back to depth 0) or hides it (the depth shown before back).
function showOriginal(viewer, on) {
  if (!viewer.original) return;
  if (viewer.kind === 'tree' && viewer.depths.length) {
    if (on) {
      if (viewer.depthBeforeOriginal === undefined) viewer.depthBeforeOriginal = viewer.depth;
      viewer.setDepth(viewer.depths[0]);
    } else if (viewer.depthBeforeOriginal !== undefined) {
      viewer.setDepth(viewer.depthBeforeOriginal);
      viewer.depthBeforeOriginal = undefined;
    }
    $('depth').value = Math.max(viewer.depths.indexOf(viewer.depth), 0);
    updateDepthLabel(viewer);
    showSelection(viewer, viewer.selected);
  }
  viewer.setShowOriginal(on);
}

// The original input (GET api/original's answer, or the page's inline copy): drawn hidden, its panel shown, its
// switch wired.
function attachOriginal(viewer, answer) {
  const original = readOriginal(answer);
  const object = originalObject(original);
  object.userData.read = { ...original, box: object.userData.box };
  viewer.setOriginal(object);
  presentOriginal(original);
  $('show-original').addEventListener('change', (e) => showOriginal(viewer, e.target.checked));
}

async function main() {
  const cfg = config();
  const viewer = new Viewer($('view'));
  const api = {
    viewer,
    THREE,
    ready: false,
    error: null,
    /** What the page shows, in numbers the tests compare with `shatter info`. */
    state() {
      const out = { kind: viewer.kind, renders: viewer.renderCount };
      if (viewer.kind === 'tree') {
        const shown = viewer.shownNodes();
        Object.assign(out, {
          leaves: viewer.tree.leafCount,
          depth: viewer.depth,
          depths: viewer.depths,
          explode: viewer.explode,
          shown: shown.map((n) => n.index),
          meshesShown: shown.filter((n) => n.object && n.object.visible).length,
          centroids: shown.map((n) => n.centroid.clone().add(n.object.position).toArray()),
          bondSegments: viewer.bondMesh ? viewer.bondMesh.userData.bondCount : 0,
        });
        if (viewer.original) {
          const o = viewer.original.userData.read;
          out.original = { shown: viewer.original.visible, triangles: o.triangles, vertices: o.vertices,
            boundaryEdges: o.boundaryEdges.length / 2, nonManifoldEdges: o.nonManifoldEdges.length / 2,
            selfIntersecting: o.selfIntersecting.length, position: viewer.original.position.toArray(),
            box: o.box };
        }
      } else if (viewer.kind === 'recording') {
        const bodies = [];
        viewer.root.traverse((o) => {
          if (o.userData && Number.isInteger(o.userData.body)) {
            bodies.push({ body: o.userData.body, kind: o.userData.kind, position: o.position.toArray(),
              quaternion: o.quaternion.toArray(), scale: o.scale.toArray() });
          }
        });
        Object.assign(out, { time: viewer.replay.time, duration: viewer.replay.duration, playing: viewer.replay.playing,
          bodies, followBodies: viewer.followBodies,
          camera: { position: viewer.camera.position.toArray(), target: viewer.controls.target.toArray() } });
      }
      return out;
    },
    /** A canvas pixel (CSS, from the page's top left) where a click picks tree node `index`, or null. */
    pixelOf(index) {
      const p = viewer.pixelOf(index);
      if (!p) return null;
      const rect = viewer.renderer.domElement.getBoundingClientRect();
      return { x: rect.left + p.x, y: rect.top + p.y };
    },
    bodyOf,
  };
  window.shatterViewer = api;
  wireControls(viewer);

  const load = async (buffer, name) => {
    viewer.show(await Viewer.parse(buffer));
    presentModel(viewer, name);
  };

  try {
    if (cfg.mode === 'file') {
      await load(base64Bytes($('shatter-model').textContent), cfg.name || '');
      // `shatter export --format html --original MESH`: the answer `view --original` serves, inline.
      const inline = $('shatter-original');
      if (inline) attachOriginal(viewer, JSON.parse(inline.textContent));
    } else if (cfg.mode === 'served') {
      const response = await fetch('api/session', { cache: 'no-store' });
      if (!response.ok) throw new Error(`api/session: ${await errorOf(response)}`);
      const session = await response.json();
      await load(await fetchBytes(`model.glb?generation=${session.generation}`), session.file);
      if (session.original) {
        const answer = await fetch('api/original', { cache: 'no-store' });
        if (!answer.ok) throw new Error(`api/original: ${await errorOf(answer)}`);
        attachOriginal(viewer, await answer.json());
      }
      if (session.editable) {
        $('editor').hidden = false;
        const editor = new Editor({
          fragments: $('edit-fragments'), seed: $('edit-seed'), strategy: $('edit-strategy'),
          run: $('edit-run'), progress: $('edit-progress'), status: $('edit-status'),
        }, async (generation) => {
          $('message').hidden = true;
          await load(await fetchBytes(`model.glb?generation=${generation}`), session.file);
          // A new tree comes at its deepest level: with the original shown, back to its root beside it.
          if (viewer.original && $('show-original').checked) {
            viewer.depthBeforeOriginal = undefined;
            showOriginal(viewer, true);
          }
        }, showError);
        editor.setOptions(session.options);
        api.editor = editor;
      }
    } else {
      throw new Error('This page has no data: open it with `shatter view <file>` or write it with '
        + '`shatter export <file.shatter> --format html --out <file.html>`.');
    }
    api.ready = true;
  } catch (error) {
    api.error = error.message;
    showError(`Could not show the file: ${error.message}`);
  } finally {
    $('loading').hidden = true;
  }
}

main();
