#!/usr/bin/env node
// Manifold's side of the robustness comparison (bench/robustness_bench.cpp, papers/run
// section 5): a long-lived worker that cuts each degenerate case of an exported
// shatter-fuzz corpus by its chain of planes with `splitByPlane`, every piece of one
// plane cut by the next, and hands every piece back in float64 so that shatter's exact
// validator judges what Manifold computed. One Node process serves many cases (its
// start and the WASM set-up would otherwise dominate); the C++ runner kills and restarts
// it when a case passes its time limit or the process dies, and counts that case alone.
//
// Protocol, one JSON object per line each way:
//   out, once at start:  {"ready": true, "manifold_3d_version": "..."}
//   in:  {"positions": [x, y, z, ...], "triangles": [i, j, k, ...], "planes": [[a, b, c, d], ...]}
//        (the case's mesh as written, and its planes a x + b y + c z + d = 0, as doubles)
//   out: {"cuts": [{"level": L, "parent": P, "below": PIECE|null, "above": PIECE|null}, ...],
//         "input_precision": "float64"|"float32 (...)",
//         "error": null | {"kind": "refused"|"crashed", "detail": "..."}}
//        PIECE = {"positions": [...], "triangles": [...]}. Cut order: level by level, the
//        parents of level L+1 being level L's non-empty results in cut order, below
//        before above. `error` says what stopped the chain after the cuts listed:
//        "refused" when Manifold reported an error (the input rejected, or a result whose
//        status() is not NoError); "crashed" when the WASM module trapped or threw
//        anything else (the worker then exits, so a damaged heap never serves a case).
//
// The plane a x + b y + c z + d = 0 goes to splitByPlane(normal = (a, b, c), originOffset =
// -d / |(a, b, c)|): Manifold normalizes the normal itself and reads the offset along the
// unit normal (README.md here); the division is one rounding in doubles, none at all for
// the axis-aligned normals of most classes. Its first result is the side the normal
// points to (above), the second the other. Each side is kept whole, as CGAL's clip
// keeps it (no decompose: a cavity would become an inside-out shell of its own).
//
// Positions: Manifold's JS Mesh is float32 both ways. The input's float64 positions are
// put back after construction with warpBatch, as fracture.mjs does (each internal vertex
// matched by its float32 rounding; when that is ambiguous the input stays float32 and
// input_precision says so). A result's float64 positions are read with an identity
// warpBatch, whose vertex order is getMesh()'s (checked on every piece: each float64
// coordinate must round to getMesh()'s float32 one, or the worker stops with an error).

import { createInterface } from 'node:readline';
import Module from 'manifold-3d';
import { packageVersion, restoreFloat64 } from './float64_input.mjs';

class Refused extends Error {}

/// The case's mesh as a Manifold, its float64 positions restored when they can be.
function buildInput(wasm, positions, triangles) {
  const { Manifold, Mesh } = wasm;
  const mesh = new Mesh({ numProp: 3, vertProperties: Float32Array.from(positions), triVerts: Uint32Array.from(triangles) });
  let built;
  try {
    built = new Manifold(mesh);
  } catch (e) {
    throw new Refused(`Manifold rejected the input mesh: ${e?.message ?? e}`);
  }
  const status = built.status();
  if (status !== 'NoError') {
    built.delete();
    throw new Refused(`Manifold rejected the input mesh: status ${status}`);
  }
  const { manifold, unmatched } = restoreFloat64(built, positions);
  if (unmatched > 0) return { manifold, precision: `float32 (${unmatched} vertices not matched back to float64)` };
  return { manifold, precision: 'float64' };
}

/// A non-empty result in float64, in getMesh()'s vertex order.
function piece(manifold) {
  let positions = null;
  const probe = manifold.warpBatch((verts, n) => { positions = Array.from(verts.subarray(0, 3 * n)); });
  probe.delete();
  const mesh = manifold.getMesh();
  if (mesh.numProp !== 3 || mesh.vertProperties.length !== positions.length) {
    throw new Error(`harness: getMesh() has ${mesh.vertProperties.length / mesh.numProp} vertices, warpBatch ${positions.length / 3}`);
  }
  for (let i = 0; i < positions.length; ++i) {
    if (Math.fround(positions[i]) !== mesh.vertProperties[i]) throw new Error('harness: warpBatch and getMesh() disagree on the vertex order');
  }
  return { positions, triangles: Array.from(mesh.triVerts) };
}

/// Cuts one case into `answer` (answer.cuts grows cut by cut, so that what was done
/// before an error is still judged). Throws Refused when Manifold reports an error.
function runCase(wasm, request, answer) {
  const cuts = answer.cuts;
  const { manifold: input, precision } = buildInput(wasm, request.positions, request.triangles);
  answer.input_precision = precision;
  let pieces = [input];
  try {
    request.planes.forEach((plane, level) => {
      const [a, b, c, d] = plane;
      const offset = -d / Math.hypot(a, b, c);
      const next = [];
      try {
        pieces.forEach((parent, p) => {
          const [above, below] = parent.splitByPlane([a, b, c], offset);
          const sides = { below, above };
          const cut = { level, parent: p, below: null, above: null };
          for (const side of ['below', 'above']) {
            const half = sides[side];
            const status = half.status();
            if (status !== 'NoError') {
              below.delete(); above.delete();
              throw new Refused(`splitByPlane result status ${status} (level ${level}, piece ${p})`);
            }
          }
          for (const side of ['below', 'above']) {
            const half = sides[side];
            if (half.isEmpty()) { half.delete(); continue; }
            cut[side] = piece(half);
            next.push(half);
          }
          cuts.push(cut);
        });
      } catch (e) {
        for (const m of next) m.delete();
        throw e;
      }
      for (const m of pieces) m.delete();
      pieces = next;
    });
  } finally {
    for (const m of pieces) m.delete();
  }
}

async function main() {
  const wasm = await Module();
  wasm.setup();
  process.stdout.write(JSON.stringify({ ready: true, manifold_3d_version: packageVersion() }) + '\n');
  const lines = createInterface({ input: process.stdin, crlfDelay: Infinity });
  for await (const line of lines) {
    if (line.trim() === '') continue;
    const request = JSON.parse(line);
    const answer = { cuts: [], input_precision: null, error: null };
    let fatal = false;
    try {
      runCase(wasm, request, answer);
    } catch (e) {
      const refused = e instanceof Refused;
      fatal = !refused;
      answer.error = { kind: refused ? 'refused' : 'crashed', detail: refused ? e.message : `${e?.name ?? 'Error'}: ${e?.message ?? e}` };
    }
    // Written before the next line is read: the runner waits for exactly one answer.
    await new Promise((resolve) => process.stdout.write(JSON.stringify(answer) + '\n', resolve));
    if (fatal) process.exit(3);
  }
}

main().catch((e) => {
  process.stderr.write(`error: ${e?.message ?? e}\n`);
  process.exit(1);
});
