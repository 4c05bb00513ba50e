#!/usr/bin/env node
// Peer benchmark: Manifold (npm manifold-3d, WASM) cutting a mesh into given Voronoi
// cells, the per-cell pipeline the fracture tools use: each cell's part of the solid
// is the input trimmed by the cell's planes one after another (trimByPlane), then
// split into its connected components (decompose). The cells themselves come from
// shatter (`shatter-bench-voronoi --manifold` writes them): the same quantized sites,
// the same Delaunay neighbours and the same exact bisectors shatter cuts, so both
// tools cut the same cells; computing the cells is not part of this script's time.
//
// usage: node voronoi.mjs --mesh FILE.off --cells FILE [--repeat R] [--json]

import { readFileSync } from 'node:fs';
import { performance } from 'node:perf_hooks';
import Module from 'manifold-3d';
import { packageVersion } from './float64_input.mjs';
import { buildInput, median, parseOff } from './off_input.mjs';

const USAGE = `usage: node voronoi.mjs --mesh FILE.off --cells FILE [--repeat R] [--json]

  --mesh FILE.off   closed, outward-oriented mesh in plain OFF (polygons are fan-triangulated)
  --cells FILE      the cells: a line "cells N", then per cell a line "cell K" and K
                    lines "a b c d", the plane a x + b y + c z + d = 0 whose negative
                    side holds the cell (shortest round-trip decimals of the doubles)
  --repeat R        cut every cell R times from the same input (default 1); the
                    report gives every time and the median
  --json            print exactly one JSON object on stdout`;

class UsageError extends Error {}

function parseArgs(argv) {
  const options = { mesh: null, cells: null, repeat: 1, json: false };
  for (let i = 0; i < argv.length; ++i) {
    const arg = argv[i];
    const value = () => {
      if (i + 1 >= argv.length) throw new UsageError(`${arg} needs a value`);
      return argv[++i];
    };
    switch (arg) {
      case '--mesh': options.mesh = value(); break;
      case '--cells': options.cells = value(); break;
      case '--repeat': {
        const text = value();
        if (!/^[0-9]+$/.test(text) || Number(text) < 1) throw new UsageError(`--repeat expects a positive integer, got '${text}'`);
        options.repeat = Number(text);
        break;
      }
      case '--json': options.json = true; break;
      case '--help': case '-h': process.stdout.write(USAGE + '\n'); process.exit(0); break;
      default: throw new UsageError(`unknown argument '${arg}'`);
    }
  }
  if (options.mesh === null) throw new UsageError('--mesh is required');
  if (options.cells === null) throw new UsageError('--cells is required');
  return options;
}

/// The cells file: an array of cells, each an array of [a, b, c, d].
function parseCells(text, name) {
  const lines = text.split(/\r\n|\n/).filter((l) => l.trim() !== '');
  let at = 0;
  const fail = (what) => { throw new Error(`${name}: ${what} (line ${at + 1})`); };
  const header = /^cells ([0-9]+)$/.exec(lines[at] ?? '');
  if (!header) fail(`expected "cells N"`);
  ++at;
  const cells = [];
  for (let c = 0; c < Number(header[1]); ++c) {
    const head = /^cell ([0-9]+)$/.exec(lines[at] ?? '');
    if (!head) fail(`expected "cell K" for cell ${c}`);
    ++at;
    const planes = [];
    for (let k = 0; k < Number(head[1]); ++k) {
      const numbers = (lines[at] ?? '').trim().split(/\s+/).map(Number);
      if (numbers.length !== 4 || !numbers.every(Number.isFinite)) fail(`expected four finite numbers for plane ${k} of cell ${c}`);
      if (numbers[0] === 0 && numbers[1] === 0 && numbers[2] === 0) fail(`plane ${k} of cell ${c} has a zero normal`);
      planes.push(numbers);
      ++at;
    }
    cells.push(planes);
  }
  if (at !== lines.length) fail('unexpected text after the last cell');
  return cells;
}

/// The cell's part of `input`: trimmed by each plane in turn (the negative side of
/// a x + b y + c z + d kept: trimByPlane keeps the side its normal points to, the
/// plane n̂ . x = offset with n̂ the unit normal, so the normal is -(a, b, c) and the
/// offset d / |(a, b, c)|), stopping once nothing is left; then its components.
function cutCell(input, planes) {
  let part = input;
  for (const [a, b, c, d] of planes) {
    const length = Math.hypot(a, b, c);
    const next = part.trimByPlane([-a, -b, -c], d / length);
    if (part !== input) part.delete();
    part = next;
    if (part.isEmpty()) break;
  }
  if (part.isEmpty()) {
    if (part !== input) part.delete();
    return [];
  }
  const components = part.decompose();
  if (part !== input) part.delete();
  const kept = [];
  for (const component of components) {
    if (component.isEmpty()) component.delete();
    else kept.push(component);
  }
  return kept;
}

const MB = 1024 * 1024;

async function main() {
  const options = parseArgs(process.argv.slice(2));
  const read = (path) => {
    try {
      return readFileSync(path, 'utf8');
    } catch (e) {
      throw new Error(`cannot read ${path}: ${e.code ?? e.message}`);
    }
  };
  const off = parseOff(read(options.mesh), options.mesh);
  const cells = parseCells(read(options.cells), options.cells);

  const wasm = await Module();
  wasm.setup();
  const { manifold: input, precision } = buildInput(wasm, off, false);
  const inputStatus = input.status();
  if (inputStatus !== 'NoError') throw new Error(`input Manifold status ${inputStatus}`);
  const inputVolume = input.volume();
  if (!(inputVolume > 0)) throw new Error(`input volume ${inputVolume} is not positive: the mesh must be closed and outward oriented`);

  const runs = [];
  let peakRss = process.memoryUsage.rss();
  let stats = null;
  for (let r = 0; r < options.repeat; ++r) {
    const fragments = [];
    const t0 = performance.now();
    for (const planes of cells) {
      for (const part of cutCell(input, planes)) fragments.push(part);
    }
    runs.push((performance.now() - t0) / 1000);
    peakRss = Math.max(peakRss, process.memoryUsage.rss());
    // Not timed: what the fragments are.
    let volume = 0, triangles = 0, bad = 0;
    for (const f of fragments) {
      volume += f.volume();
      triangles += f.numTri();
      if (f.status() !== 'NoError') ++bad;
      f.delete();
    }
    const run = { fragments: fragments.length, volume, triangles, bad };
    if (stats !== null && (stats.fragments !== run.fragments || stats.triangles !== run.triangles)) {
      throw new Error(`repeat ${r} made ${run.fragments} fragments of ${run.triangles} triangles, repeat 0 ${stats.fragments} of ${stats.triangles}`);
    }
    stats = run;
  }
  input.delete();

  const report = {
    tool: 'manifold-3d',
    manifold_3d_version: packageVersion(),
    node_version: process.version,
    mesh: options.mesh,
    input: { off_triangles: off.triVerts.length / 3, positions: precision, volume: inputVolume },
    method: 'per cell: the input trimmed by each of the cell\'s planes (trimByPlane, nearest neighbour\'s bisector first, stopping when empty), then decompose() into components',
    cells: cells.length,
    planes: cells.reduce((n, c) => n + c.length, 0),
    fragments: stats.fragments,
    total_triangles: stats.triangles,
    bad_pieces: stats.bad,
    total_volume: stats.volume,
    input_volume: inputVolume,
    volume_relative_error: (stats.volume - inputVolume) / inputVolume,
    seconds: { median: median(runs), runs },
    peak_rss_mb: peakRss / MB,
  };
  if (options.json) {
    process.stdout.write(JSON.stringify(report) + '\n');
  } else {
    process.stdout.write([
      `manifold-3d ${report.manifold_3d_version} on node ${report.node_version}`,
      `mesh        ${options.mesh}: ${report.input.off_triangles} triangles, volume ${inputVolume} (${precision})`,
      `cells       ${report.cells} (${report.planes} planes)`,
      `fragments   ${report.fragments} (${report.total_triangles} triangles, ${report.bad_pieces} bad)`,
      `volume      ${report.total_volume} vs input ${inputVolume} (relative error ${report.volume_relative_error.toExponential(2)})`,
      `seconds     median ${report.seconds.median.toFixed(3)} over ${runs.length} run(s): ${runs.map((s) => s.toFixed(3)).join(' ')}`,
      `peak RSS    ${report.peak_rss_mb.toFixed(1)} MB`,
    ].join('\n') + '\n');
  }
}

main().catch((e) => {
  if (e instanceof UsageError) {
    process.stderr.write(`error: ${e.message}\n${USAGE}\n`);
    process.exit(2);
  }
  process.stderr.write(`error: ${e?.message ?? e}\n`);
  process.exit(1);
});
