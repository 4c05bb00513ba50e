#!/usr/bin/env node
// Manifold's handling of a damaged mesh, the peer of `shatter validate --repair` in
// bench/repair-rate --peers (issue 21: against CGAL's and Manifold's handling of the
// same files in the same run).
//
//   node repair.mjs IN.off OUT.off
//
// Manifold has no repair of its own; what it offers a mesh from elsewhere is
// Mesh.merge() (vertices at equal positions along open edges joined, so that a file
// with split vertices becomes manifold) and then the Manifold constructor, which
// accepts a closed oriented 2-manifold and names anything else in status(). That is
// done here, and nothing more: a result whose status is NoError is written to OUT.off
// with its float64 positions (put back after the float32 Mesh, as fracture.mjs does),
// and bench/repair-rate judges it with shatter's exact validator (which also looks for
// self-intersections, which Manifold does not check). One JSON line goes to stdout:
// {"tool", "steps", "status", "seconds"} ("seconds": merge and construction only).
import { readFileSync, writeFileSync } from 'node:fs';
import Module from 'manifold-3d';
import { packageVersion, restoreFloat64 } from './float64_input.mjs';
import { parseOff } from './off_input.mjs';

const [input, output] = process.argv.slice(2);
if (!input || !output) {
  console.error('usage: node repair.mjs IN.off OUT.off');
  process.exit(2);
}
const line = { tool: `Manifold ${packageVersion()} (npm manifold-3d, WASM)`, steps: [] };
const finish = (code) => { console.log(JSON.stringify(line)); process.exit(code); };

let off;
try {
  off = parseOff(readFileSync(input, 'utf8'), input);
} catch (e) {
  line.error = `unreadable: ${e?.message ?? e}`;
  finish(1);
}

const wasm = await Module();
wasm.setup();
const { Manifold, Mesh } = wasm;
const start = process.hrtime.bigint();
const mesh = new Mesh({ numProp: 3, vertProperties: Float32Array.from(off.positions), triVerts: off.triVerts });
if (mesh.merge()) line.steps.push({ merge: true });
let built;
try {
  built = new Manifold(mesh);
  line.status = built.status();
} catch (e) {
  line.status = `${e?.message ?? e}`;
}
line.seconds = Number(process.hrtime.bigint() - start) / 1e9;
if (line.status !== 'NoError') {
  line.error = `Manifold refused the mesh: ${line.status}`;
  finish(1);
}

const { manifold } = restoreFloat64(built, off.positions);
let positions = null;
const probe = manifold.warpBatch((verts, n) => { positions = Array.from(verts.subarray(0, 3 * n)); });
probe.delete();
const triangles = manifold.getMesh().triVerts;
const lines = ['OFF', `${positions.length / 3} ${triangles.length / 3} 0`];
for (let i = 0; i < positions.length; i += 3) {
  lines.push(`${positions[i]} ${positions[i + 1]} ${positions[i + 2]}`);  // shortest round-trip decimals
}
for (let i = 0; i < triangles.length; i += 3) lines.push(`3 ${triangles[i]} ${triangles[i + 1]} ${triangles[i + 2]}`);
writeFileSync(output, lines.join('\n') + '\n');
finish(0);
