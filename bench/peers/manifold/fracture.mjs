#!/usr/bin/env node
// Peer benchmark: Manifold (npm manifold-3d, WASM) doing shatter's benchmark method,
// "random plane through each piece's volume centroid, every connected component
// re-split, until N pieces". See README.md in this folder for the method in full.
//
// usage: node fracture.mjs --mesh FILE.off --fragments N [--seed S] [--repeat R] [--json] [--f32-input]

import { readFileSync } from 'node:fs';
import { performance } from 'node:perf_hooks';
import Module from 'manifold-3d';
import { packageVersion } from './float64_input.mjs';
import { buildInput, median, parseOff } from './off_input.mjs';

const USAGE = `usage: node fracture.mjs --mesh FILE.off --fragments N [--seed S] [--repeat R] [--json] [--f32-input]

  --mesh FILE.off   closed, outward-oriented mesh in plain OFF (polygons are fan-triangulated)
  --fragments N     stop as soon as there are at least N pieces (N >= 1)
  --seed S          splitmix64 seed, unsigned 64-bit integer (default 1)
  --repeat R        run the whole fracture R times from the same input and seed (default 1)
  --json            print exactly one JSON object on stdout
  --f32-input       keep Manifold's float32 input positions (default: restore the file's
                    float64 positions with warpBatch before timing)`;

class UsageError extends Error {}

// --- arguments ------------------------------------------------------------------

function parseArgs(argv) {
  const options = { mesh: null, fragments: null, seed: 1n, repeat: 1, json: false, f32Input: false };
  for (let i = 0; i < argv.length; ++i) {
    const arg = argv[i];
    const value = () => {
      if (i + 1 >= argv.length) throw new UsageError(`${arg} needs a value`);
      return argv[++i];
    };
    const integer = (text, min, max) => {
      if (!/^[0-9]+$/.test(text)) throw new UsageError(`${arg} expects an unsigned integer, got '${text}'`);
      const n = BigInt(text);
      if (n < BigInt(min) || n > BigInt(max)) throw new UsageError(`${arg} must be in [${min}, ${max}], got ${text}`);
      return n;
    };
    switch (arg) {
      case '--mesh': options.mesh = value(); break;
      case '--fragments': options.fragments = Number(integer(value(), 1, 100_000_000)); break;
      case '--seed': options.seed = integer(value(), 0, (1n << 64n) - 1n); break;
      case '--repeat': options.repeat = Number(integer(value(), 1, 1_000_000)); break;
      case '--json': options.json = true; break;
      case '--f32-input': options.f32Input = true; break;
      case '--help': case '-h': process.stdout.write(USAGE + '\n'); process.exit(0); break;
      default: throw new UsageError(`unknown argument '${arg}'`);
    }
  }
  if (options.mesh === null) throw new UsageError('--mesh is required');
  if (options.fragments === null) throw new UsageError('--fragments is required');
  return options;
}

// --- reproducible randomness ------------------------------------------------------
// splitmix64 in BigInt, one stream for the whole run, state initialised to the seed.
// symmetric() and direction() use the same formulas as shatter's NodeRandom
// (meshtree/src/build.cpp): (z >> 11) * 2^-52 - 1 in [-1, 1), rejection from the cube
// keeping 1e-4 < |v|^2 <= 1, then v * (1 / sqrt(|v|^2)). The planes are NOT the ones
// shatter draws (shatter seeds one stream per tree node), only the distribution is.

const MASK64 = (1n << 64n) - 1n;

class SplitMix64 {
  constructor(seed) { this.state = BigInt.asUintN(64, seed); }
  next() {
    this.state = (this.state + 0x9E3779B97F4A7C15n) & MASK64;
    let z = this.state;
    z = ((z ^ (z >> 30n)) * 0xBF58476D1CE4E5B9n) & MASK64;
    z = ((z ^ (z >> 27n)) * 0x94D049BB133111EBn) & MASK64;
    return z ^ (z >> 31n);
  }
  symmetric() { return Number(this.next() >> 11n) * 2 ** -52 - 1; }
  direction() {
    for (;;) {
      const x = this.symmetric(), y = this.symmetric(), z = this.symmetric();
      const lengthSquared = x * x + y * y + z * z;
      if (lengthSquared > 1e-4 && lengthSquared <= 1) {
        const inv = 1 / Math.sqrt(lengthSquared);
        return [x * inv, y * inv, z * inv];
      }
    }
  }
}

// --- volume centroid ----------------------------------------------------------------
// Divergence theorem over the triangles of getMesh() (float32 positions, widened to
// double), relative to the first vertex: centroid = o + sum(v6 * (a + b + c)) / (4 * sum(v6))
// with v6 = a . (b x c). A piece with no positive volume falls back to its vertex mean.

function volumeCentroid(mesh, counters) {
  const p = mesh.vertProperties, np = mesh.numProp, t = mesh.triVerts;
  const ox = p[0], oy = p[1], oz = p[2];
  let v6sum = 0, cx = 0, cy = 0, cz = 0;
  for (let i = 0; i < t.length; i += 3) {
    const a = t[i] * np, b = t[i + 1] * np, c = t[i + 2] * np;
    const ax = p[a] - ox, ay = p[a + 1] - oy, az = p[a + 2] - oz;
    const bx = p[b] - ox, by = p[b + 1] - oy, bz = p[b + 2] - oz;
    const qx = p[c] - ox, qy = p[c + 1] - oy, qz = p[c + 2] - oz;
    const v6 = ax * (by * qz - bz * qy) + ay * (bz * qx - bx * qz) + az * (bx * qy - by * qx);
    v6sum += v6;
    cx += v6 * (ax + bx + qx);
    cy += v6 * (ay + by + qy);
    cz += v6 * (az + bz + qz);
  }
  if (v6sum > 0 && Number.isFinite(v6sum)) {
    const s = 1 / (4 * v6sum);
    return [ox + cx * s, oy + cy * s, oz + cz * s];
  }
  counters.centroidFallbacks++;
  const n = p.length / np;
  let mx = 0, my = 0, mz = 0;
  for (let v = 0; v < n; ++v) { mx += p[v * np]; my += p[v * np + 1]; mz += p[v * np + 2]; }
  return [mx / n, my / n, mz / n];
}

// --- the fracture -------------------------------------------------------------------

const MAX_DRAWS = 64;

/// Splits one piece by a random plane through its volume centroid; returns the non-empty
/// connected components of both halves. Does not delete `piece`.
function splitPiece(piece, rng, counters) {
  const centroid = volumeCentroid(piece.getMesh(), counters);
  for (let draw = 0; draw < MAX_DRAWS; ++draw) {
    const normal = rng.direction();
    const offset = normal[0] * centroid[0] + normal[1] * centroid[1] + normal[2] * centroid[2];
    // First result: {x : normal . x > offset}; second: the other side (normal is unit).
    const halves = piece.splitByPlane(normal, offset);
    if (halves[0].isEmpty() || halves[1].isEmpty()) {
      for (const h of halves) h.delete();
      counters.redraws++;
      continue;
    }
    const components = [];
    for (const half of halves) {
      const parts = half.decompose();
      half.delete();
      for (const part of parts) {
        if (part.isEmpty()) part.delete();
        else components.push(part);
      }
    }
    return components;
  }
  throw new Error(`a piece (${piece.numTri()} triangles, volume ${piece.volume()}) was missed by ${MAX_DRAWS} planes through its centroid`);
}

/// Breadth-first rounds until at least `target` pieces. Returns the final pieces (which
/// may include `input` itself when target is 1), the number of rounds and the peak RSS.
function fracture(input, target, seed, counters) {
  const rng = new SplitMix64(seed);
  let pieces = [input];
  let rounds = 0;
  let peakRss = process.memoryUsage.rss();
  try {
    while (pieces.length < target) {
      ++rounds;
      const next = [];
      let count = pieces.length;
      for (let i = 0; i < pieces.length; ++i) {
        const piece = pieces[i];
        if (count >= target) { next.push(piece); continue; }
        let components;
        try {
          components = splitPiece(piece, rng, counters);
        } catch (e) {
          pieces = next.concat(pieces.slice(i));  // so the finally below frees them
          throw e;
        }
        count += components.length - 1;
        for (const c of components) next.push(c);
        if (piece !== input) piece.delete();
      }
      pieces = next;
      peakRss = Math.max(peakRss, process.memoryUsage.rss());
    }
  } catch (e) {
    for (const p of pieces) if (p !== input) p.delete();
    throw e;
  }
  return { pieces, rounds, peakRss };
}

// --- setup ----------------------------------------------------------------------------

/// Size of the WASM linear memory in bytes. The module does not export its memory, but
/// warpBatch's callback gets a view on it. Linear memory only grows, so this is the
/// high-water mark of Manifold's heap: constant across repeats means nothing leaks.
function wasmMemoryBytes(wasm) {
  const probe = wasm.Manifold.tetrahedron();
  let bytes = 0;
  const warped = probe.warpBatch((verts) => { bytes = verts.buffer.byteLength; });
  warped.delete();
  probe.delete();
  return bytes;
}

const MB = 1024 * 1024;

// --- main -------------------------------------------------------------------------------

async function main() {
  const options = parseArgs(process.argv.slice(2));
  let text;
  try {
    text = readFileSync(options.mesh, 'utf8');
  } catch (e) {
    throw new Error(`cannot read ${options.mesh}: ${e.code ?? e.message}`);
  }
  const off = parseOff(text, options.mesh);

  const wasm = await Module();
  wasm.setup();
  const { manifold: input, precision } = buildInput(wasm, off, options.f32Input);
  const inputStatus = input.status();
  if (inputStatus !== 'NoError') throw new Error(`input Manifold status ${inputStatus}`);
  const inputVolume = input.volume();
  if (!(inputVolume > 0)) throw new Error(`input volume ${inputVolume} is not positive: the mesh must be closed and outward oriented`);
  const inputTris = input.numTri(), inputVerts = input.numVert(), inputGenus = input.genus();

  const runs = [];
  const rssAfterRepeat = [], wasmAfterRepeat = [];
  let peakRss = process.memoryUsage.rss();
  let result = null;
  let deterministic = true;
  for (let r = 0; r < options.repeat; ++r) {
    const counters = { redraws: 0, centroidFallbacks: 0 };
    const t0 = performance.now();
    const { pieces, rounds, peakRss: runPeak } = fracture(input, options.fragments, options.seed, counters);
    const t1 = performance.now();
    runs.push((t1 - t0) / 1000);
    peakRss = Math.max(peakRss, runPeak);

    // Untimed: what came out.
    let totalTriangles = 0, totalVolume = 0, badPieces = 0;
    for (const piece of pieces) {
      totalTriangles += piece.numTri();
      totalVolume += piece.volume();
      if (piece.status() !== 'NoError' || piece.isEmpty()) ++badPieces;
    }
    const summary = { pieces: pieces.length, rounds, totalTriangles, totalVolume, badPieces, ...counters };
    if (result && (result.pieces !== summary.pieces || result.totalTriangles !== summary.totalTriangles)) deterministic = false;
    result = summary;
    for (const piece of pieces) if (piece !== input) piece.delete();
    rssAfterRepeat.push(process.memoryUsage.rss() / MB);
    wasmAfterRepeat.push(wasmMemoryBytes(wasm) / MB);
  }
  input.delete();

  const report = {
    tool: 'manifold-3d',
    manifold_3d_version: packageVersion(),
    node_version: process.version,
    mesh: options.mesh,
    input: {
      off_vertices: off.offVertices,
      off_faces: off.offFaces,
      off_triangles: off.triVerts.length / 3,
      manifold_triangles: inputTris,
      manifold_vertices: inputVerts,
      genus: inputGenus,
      volume: inputVolume,
      positions: precision,
    },
    method: 'breadth-first rounds; each piece split by splitByPlane through its volume centroid with a uniformly random unit normal, both halves decomposed into connected components, until >= N pieces',
    prng: 'splitmix64 (BigInt), one stream, state = seed; normal by rejection from [-1,1)^3 with 1e-4 < |v|^2 <= 1',
    seed: options.seed.toString(),
    fragments_requested: options.fragments,
    pieces: result.pieces,
    rounds: result.rounds,
    total_triangles: result.totalTriangles,
    total_volume: result.totalVolume,
    input_volume: inputVolume,
    volume_relative_error: (result.totalVolume - inputVolume) / inputVolume,
    bad_pieces: result.badPieces,
    redraws: result.redraws,
    centroid_fallbacks: result.centroidFallbacks,
    deterministic_across_repeats: deterministic,
    repeat: options.repeat,
    seconds: { median: median(runs), runs },
    peak_rss_mb: peakRss / MB,
    rss_mb_after_each_repeat: rssAfterRepeat,
    wasm_memory_mb_after_each_repeat: wasmAfterRepeat,
    caveats: [
      'WASM build of Manifold (single-threaded, no pthreads) run under Node, not native code',
      'Manifold JS Mesh positions are float32: getMesh() (used for the centroids) returns float32 positions; Manifold computes in float64 internally',
      `input positions: ${precision}`,
    ],
  };

  if (options.json) {
    process.stdout.write(JSON.stringify(report) + '\n');
    return;
  }
  const f = (x, d = 3) => x.toFixed(d);
  const out = [
    `manifold-3d ${report.manifold_3d_version} on node ${report.node_version}`,
    `mesh        ${report.mesh}: ${report.input.off_triangles} triangles from OFF, ${inputTris} triangles / ${inputVerts} vertices in Manifold, genus ${inputGenus}, volume ${inputVolume}`,
    `positions   ${precision}`,
    `seed        ${report.seed}, fragments requested ${options.fragments}`,
    `pieces      ${report.pieces} in ${report.rounds} rounds (${report.redraws} plane redraws, ${report.centroid_fallbacks} centroid fallbacks)`,
    `triangles   ${report.total_triangles} over all pieces`,
    `volume      ${report.total_volume} vs input ${inputVolume} (relative error ${report.volume_relative_error.toExponential(2)})`,
    `bad pieces  ${report.bad_pieces} (status not NoError, or empty)`,
    `seconds     median ${f(report.seconds.median)} over ${options.repeat} run(s): ${runs.map((s) => f(s)).join(' ')}`,
    `peak RSS    ${f(report.peak_rss_mb, 1)} MB (after each repeat: ${rssAfterRepeat.map((m) => f(m, 1)).join(' ')} MB)`,
    `WASM memory ${wasmAfterRepeat.map((m) => f(m, 1)).join(' ')} MB after each repeat (linear memory never shrinks)`,
    deterministic ? null : 'WARNING     repeats did not produce the same pieces',
  ].filter((line) => line !== null);
  process.stdout.write(out.join('\n') + '\n');
}

main().catch((e) => {
  const message = e instanceof Error ? e.message : String(e);
  const hint = e instanceof UsageError ? ' (see --help)' : '';
  process.stderr.write(`error: ${message.split('\n')[0]}${hint}\n`);
  process.exit(1);
});
