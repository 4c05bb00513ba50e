// The viewer's modules (viewer/src), loaded into node for the unit tests.
// They import three.js by its bare name, which node cannot resolve from the
// source tree (npm installs it into the build folder only), so they are
// bundled with the build's esbuild, three.js resolved from
// SHATTER_NODE_MODULES as viewer/build.mjs resolves it, into one ES module
// that also exports the copy of three.js they use (objects the tests build
// must come from that copy). This works the same on node 18 and later, with
// no loader hook.

import { mkdtempSync, rmSync, writeFileSync } from 'node:fs';
import { createRequire } from 'node:module';
import os from 'node:os';
import path from 'node:path';
import { fileURLToPath, pathToFileURL } from 'node:url';

const source = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '..', '..', 'src');

const ENTRY = `
export * as THREE from 'three';
export { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
export * from './tree.js';
export * from './replay.js';
export * from './framing.js';
export { fragmentColour } from './viewer.js';
export * from './original.js';
`;

/** The bundle's exports: THREE, GLTFLoader, what tree.js, replay.js, framing.js and original.js export, and fragmentColour. */
export async function loadViewerModules() {
  const nodeModules = process.env.SHATTER_NODE_MODULES;
  if (!nodeModules) {
    throw new Error('SHATTER_NODE_MODULES is not set: point it at the node_modules `npm ci` made for the viewer '
      + '(<build>/viewer/node_modules; CTest sets it, see tests/viewer/CMakeLists.txt)');
  }
  const require = createRequire(path.join(path.resolve(nodeModules), 'package.json'));
  const esbuild = require('esbuild');
  const result = await esbuild.build({
    stdin: { contents: ENTRY, resolveDir: source, sourcefile: 'unit-test-entry.js' },
    bundle: true,
    format: 'esm',
    platform: 'node',
    write: false,
    sourcemap: 'inline',
    nodePaths: [path.resolve(nodeModules)],
    logLevel: 'warning',
  });
  const folder = mkdtempSync(path.join(os.tmpdir(), 'shatter-viewer-unit-'));
  process.on('exit', () => rmSync(folder, { recursive: true, force: true }));
  const file = path.join(folder, 'viewer-modules.mjs');
  writeFileSync(file, result.outputFiles[0].text);
  return import(pathToFileURL(file).href);
}
