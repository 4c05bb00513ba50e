// What the Manifold peers that read an OFF file share (fracture.mjs, voronoi.mjs):
// the OFF reader, the input Manifold with the file's float64 positions, and the
// median of repeated timings.
import { restoreFloat64 } from './float64_input.mjs';

// --- OFF reader -------------------------------------------------------------------
// Plain OFF: "OFF", then "nv nf ne", nv vertices "x y z", nf faces "k i0 ... i(k-1)".
// '#' starts a comment to the end of the line; whitespace (spaces, tabs, blank lines,
// CR/LF) is arbitrary, and an element may continue over several lines. Tokens left on
// the line where a vertex or face ends (e.g. per-face colours) are ignored. Polygons
// are fan-triangulated (i0, ij, ij+1). Coordinates are parsed as doubles.

export function parseOff(text, name) {
  const tokens = [];  // [token, line]
  const lines = text.replace(/^\uFEFF/, '').split(/\r\n|\n|\r/);
  for (let l = 0; l < lines.length; ++l) {
    const hash = lines[l].indexOf('#');
    const body = hash >= 0 ? lines[l].slice(0, hash) : lines[l];
    for (const t of body.split(/\s+/)) if (t !== '') tokens.push([t, l + 1]);
  }
  let at = 0;
  const fail = (what) => {
    const where = at < tokens.length ? `line ${tokens[at][1]}` : 'end of file';
    throw new Error(`${name}: ${what} (${where})`);
  };
  const next = (what) => {
    if (at >= tokens.length) fail(`unexpected end of file, expected ${what}`);
    return tokens[at++];
  };
  const count = (what) => {
    const [t] = next(what);
    if (!/^[0-9]+$/.test(t)) { --at; fail(`expected ${what} (a non-negative integer), got '${t}'`); }
    return Number(t);
  };
  const skipRestOfLine = (line) => { while (at < tokens.length && tokens[at][1] === line) ++at; };

  const [header] = next('the OFF header');
  if (header !== 'OFF') { --at; fail(`not a plain OFF file: header '${header}' (expected 'OFF')`); }
  const nv = count('the vertex count'), nf = count('the face count');
  const countsLine = tokens[at - 1][1];
  count('the edge count');
  skipRestOfLine(countsLine);

  const positions = new Float64Array(3 * nv);
  for (let v = 0; v < nv; ++v) {
    let line = 0;
    for (let k = 0; k < 3; ++k) {
      const [t, l] = next(`coordinate ${k} of vertex ${v}`);
      const x = Number(t);
      if (!Number.isFinite(x) || !/^[-+0-9.]/.test(t)) { --at; fail(`vertex ${v}: '${t}' is not a finite number`); }
      positions[3 * v + k] = x;
      line = l;
    }
    skipRestOfLine(line);
  }

  const tris = [];
  for (let f = 0; f < nf; ++f) {
    const k = count(`the corner count of face ${f}`);
    if (k < 3) { --at; fail(`face ${f} has ${k} corners (at least 3 needed)`); }
    const corners = [];
    let line = 0;
    for (let j = 0; j < k; ++j) {
      const [t, l] = next(`corner ${j} of face ${f}`);
      if (!/^[0-9]+$/.test(t) || Number(t) >= nv) { --at; fail(`face ${f}: bad vertex index '${t}' (${nv} vertices)`); }
      corners.push(Number(t));
      line = l;
    }
    skipRestOfLine(line);
    for (let j = 1; j + 1 < k; ++j) tris.push(corners[0], corners[j], corners[j + 1]);
  }
  if (nv === 0 || tris.length === 0) throw new Error(`${name}: empty mesh`);
  return { positions, triVerts: Uint32Array.from(tris), offVertices: nv, offFaces: nf };
}

/// Builds the input Manifold. Manifold's JS Mesh only takes float32 positions; unless
/// f32Input, the file's float64 positions are put back with warpBatch (whose callback
/// sees the internal float64 positions), matching each internal vertex by its float32
/// rounding. Falls back to float32 if that matching is ambiguous.
export function buildInput(wasm, off, f32Input) {
  const { Manifold, Mesh } = wasm;
  const mesh = new Mesh({ numProp: 3, vertProperties: Float32Array.from(off.positions), triVerts: off.triVerts });
  let built;
  try {
    built = new Manifold(mesh);
  } catch (e) {
    throw new Error(`Manifold rejected the input mesh: ${e?.message ?? e}`);
  }
  if (f32Input) return { manifold: built, precision: 'float32 (as requested by --f32-input)' };

  const { manifold, unmatched, changed } = restoreFloat64(built, off.positions);
  if (unmatched > 0) {
    return { manifold, precision: `float32 (${unmatched} vertices could not be matched back to float64 positions)` };
  }
  return { manifold, precision: `float64 (float32 Mesh, then warpBatch restored ${changed} coordinates)` };
}


/// The median of a non-empty list of numbers.
export function median(values) {
  const s = [...values].sort((a, b) => a - b);
  const m = s.length >> 1;
  return s.length % 2 ? s[m] : (s[m - 1] + s[m]) / 2;
}
