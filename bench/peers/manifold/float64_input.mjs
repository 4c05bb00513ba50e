// What both Manifold peers (fracture.mjs, robustness.mjs) need to start from the same
// float64 input shatter reads: Manifold's JS Mesh only takes float32 positions, so the
// file's float64 positions are put back with warpBatch (whose callback sees the internal
// float64 positions), each internal vertex matched by its float32 rounding.
import { readFileSync } from 'node:fs';
import { fileURLToPath } from 'node:url';

/// The installed manifold-3d's version, from its package.json.
export function packageVersion() {
  const url = new URL('./package.json', import.meta.resolve('manifold-3d'));
  return JSON.parse(readFileSync(fileURLToPath(url), 'utf8')).version;
}

function float32Key(x, y, z, scratch, bits) {
  scratch[0] = x; scratch[1] = y; scratch[2] = z;
  return `${bits[0]},${bits[1]},${bits[2]}`;
}

/// `built` (a Manifold made from `positions` rounded to float32) with the float64
/// `positions` restored: { manifold, unmatched: 0, changed } on success, where `built`
/// is deleted and `changed` counts the coordinates the warp moved. When a vertex has no
/// float32 match, or two float64 positions share one float32 rounding (ambiguous), the
/// warp is all or nothing: { manifold: built, unmatched > 0, changed: 0 }.
export function restoreFloat64(built, positions) {
  const scratch = new Float32Array(3), bits = new Uint32Array(scratch.buffer);
  const byKey = new Map(), ambiguous = new Set();
  const p = positions;
  for (let v = 0; v < p.length / 3; ++v) {
    const key = float32Key(p[3 * v], p[3 * v + 1], p[3 * v + 2], scratch, bits);
    const seen = byKey.get(key);
    if (seen === undefined) byKey.set(key, v);
    else if (p[3 * seen] !== p[3 * v] || p[3 * seen + 1] !== p[3 * v + 1] || p[3 * seen + 2] !== p[3 * v + 2]) ambiguous.add(key);
  }
  let unmatched = 0, changed = 0;
  const warped = built.warpBatch((verts, n) => {
    // A first pass checks every vertex, so the warp is all or nothing.
    const source = new Int32Array(n);
    for (let i = 0; i < n; ++i) {
      const key = float32Key(verts[3 * i], verts[3 * i + 1], verts[3 * i + 2], scratch, bits);
      const v = byKey.get(key);
      source[i] = v === undefined || ambiguous.has(key) ? -1 : v;
      if (source[i] < 0) ++unmatched;
    }
    if (unmatched > 0) return;
    for (let i = 0; i < n; ++i) {
      for (let k = 0; k < 3; ++k) {
        const x = p[3 * source[i] + k];
        if (verts[3 * i + k] !== x) { verts[3 * i + k] = x; ++changed; }
      }
    }
  });
  if (unmatched > 0) {
    warped.delete();
    return { manifold: built, unmatched, changed: 0 };
  }
  built.delete();
  return { manifold: warped, unmatched: 0, changed };
}
