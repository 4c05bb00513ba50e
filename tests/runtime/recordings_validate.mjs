// CTest "runtime: every recording passes the Khronos glTF validator": fractures
// several corpus meshes with several seeds, records every scene of `shatter
// simulate` as .glb, and runs the Khronos validator (npm gltf-validator) on each
// file. Any error (a rotation component above 1, a non-unit quaternion, a NaN, a
// bad accessor) fails the test, naming the file and the validator's message; so
// does a recording that could not be made. Warnings and infos are printed, not
// counted: the validator flags unused data that glTF allows.
//
// Environment: SHATTER_EXE (the shatter binary), SHATTER_NODE_MODULES (a
// node_modules folder with gltf-validator), SHATTER_CORPUS (tests/data/corpus),
// SHATTER_TEST_WORK (a scratch folder, emptied first).
import { execFileSync } from 'node:child_process';
import { mkdirSync, readFileSync, rmSync } from 'node:fs';
import { createRequire } from 'node:module';
import path from 'node:path';

function required(name) {
  const value = process.env[name];
  if (!value) throw new Error(`${name} is not set (tests/runtime/CMakeLists.txt sets it)`);
  return value;
}

const shatter = required('SHATTER_EXE');
const corpus = required('SHATTER_CORPUS');
const work = required('SHATTER_TEST_WORK');
const require = createRequire(path.join(required('SHATTER_NODE_MODULES'), 'index.js'));
const validator = require('gltf-validator');

// Shapes of the kinds people fracture: a thin-limbed animal, a mechanical part with
// sharp edges, a gear with thin teeth, a knotted tube; three seeds each, every scene.
const meshes = ['elephant.off', 'fandisk.off', 'pinion.off', 'knot1.off'];
const seeds = [1, 2, 3];
const scenes = ['drop', 'shoot', 'wall'];

rmSync(work, { recursive: true, force: true });
mkdirSync(work, { recursive: true });
const run = (...args) => execFileSync(shatter, args, { stdio: ['ignore', 'ignore', 'pipe'] });

let recordings = 0;
const failures = [];
for (const mesh of meshes) {
  for (const seed of seeds) {
    const tree = path.join(work, `${path.parse(mesh).name}-${seed}.shatter`);
    run('fracture', path.join(corpus, mesh), '--fragments', '32', '--seed', String(seed), '--out', tree);
    for (const scene of scenes) {
      const glb = path.join(work, `${path.parse(mesh).name}-${seed}-${scene}.glb`);
      run('simulate', tree, '--scene', scene, '--steps', '120', '--print-every', '1000', '--record', glb);
      const report = await validator.validateBytes(new Uint8Array(readFileSync(glb)), { maxIssues: 50 });
      ++recordings;
      const { numErrors, numWarnings } = report.issues;
      console.log(`${path.basename(glb)}: ${numErrors} errors, ${numWarnings} warnings`);
      if (numErrors > 0) {
        for (const message of report.issues.messages.filter((m) => m.severity === 0)) {
          failures.push(`${path.basename(glb)}: ${message.code} ${message.pointer ?? ''} ${message.message}`);
        }
      }
    }
  }
}
if (recordings !== meshes.length * seeds.length * scenes.length) throw new Error(`only ${recordings} recordings made`);
if (failures.length > 0) {
  console.error(`${failures.length} validator errors:\n${failures.join('\n')}`);
  process.exit(1);
}
console.log(`${recordings} recordings, 0 validator errors`);
