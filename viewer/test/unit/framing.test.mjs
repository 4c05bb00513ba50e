// Properties of viewer/src/framing.js (the camera that keeps a recording's
// live bodies in view) on synthetic recordings of unit cubes: random motion
// with births and deaths, bodies standing still, bodies at one velocity,
// bodies born far from the rest, and a projectile among the pieces.

import assert from 'node:assert/strict';
import { describe, test } from 'node:test';

import { makeRecording, randomSource } from './synthetic.mjs';
import { loadViewerModules } from './viewer-modules.mjs';

const { THREE, Replay, ReplayFraming, bodyLocalBoxes, fitDistance, followedBodies, liveBodiesBox, recordingBodies } =
  await loadViewerModules();
const SEED = 5150;

function framed(recording, options) {
  const replay = new Replay(recording.root, recording.clip);
  return { replay, framing: new ReplayFraming(replay, recording.root, options) };
}

// The corners of the cubes alive at `time` (bodies are unrotated unit cubes), from the keys, not from three.js.
function liveCorners(recording, replay, time) {
  replay.seek(time);
  const corners = [];
  for (const body of recording.bodies) {
    if (body.object.scale.x === 0) continue;
    const p = body.object.position;
    for (const dx of [-0.5, 0.5]) for (const dy of [-0.5, 0.5]) for (const dz of [-0.5, 0.5]) corners.push(new THREE.Vector3(p.x + dx, p.y + dy, p.z + dz));
  }
  return corners;
}

const boxSphere = (corners) => {
  const box = new THREE.Box3().setFromPoints(corners);
  return { centre: box.getCenter(new THREE.Vector3()), radius: box.getSize(new THREE.Vector3()).length() / 2 };
};

describe('fitDistance', () => {
  test('puts a sphere exactly inside the narrower of the two view angles, and grows with its radius', () => {
    const random = randomSource(SEED);
    for (let n = 0; n < 200; ++n) {
      const fov = random.int(10, 100);
      const aspect = random.int(2, 40) / 10;
      const radius = random.int(1, 1000) / 10;
      const distance = fitDistance(radius, fov, aspect);
      const halfVertical = THREE.MathUtils.degToRad(fov) / 2;
      const halfHorizontal = Math.atan(Math.tan(halfVertical) * aspect);
      // The sphere's angular radius seen from the camera equals the narrower half angle: it touches two sides.
      assert.ok(Math.abs(Math.asin(radius / distance) - Math.min(halfVertical, halfHorizontal)) < 1e-12, `fov ${fov}, aspect ${aspect}`);
      assert.ok(Math.abs(fitDistance(3 * radius, fov, aspect) - 3 * distance) < 1e-9 * distance, `fov ${fov}, aspect ${aspect}`);
    }
  });
});

describe('ReplayFraming', () => {
  test('holds every body alive at each sample time inside its sphere', () => {
    const random = randomSource(SEED + 1);
    for (let n = 0; n < 30; ++n) {
      const recording = makeRecording(THREE, random, { bodies: random.int(1, 8), keyCount: random.int(2, 40) });
      const { replay, framing } = framed(recording);
      let checked = 0;
      for (const time of framing.times) {
        const corners = liveCorners(recording, replay, time);
        const { centre, radius } = framing.at(time);
        for (const corner of corners) {
          assert.ok(corner.distanceTo(centre) <= radius * (1 + 1e-9) + 1e-9,
            `recording ${n} at ${time} s: a corner ${corner.distanceTo(centre)} from the centre, radius ${radius}`);
        }
        checked += corners.length;
      }
      assert.ok(checked > 0, `recording ${n}: no body alive at any sample`);
    }
  });

  test('is the bodies\' own bounding sphere, unchanged over time, when they stand still', () => {
    const random = randomSource(SEED + 2);
    for (let n = 0; n < 10; ++n) {
      const recording = makeRecording(THREE, random, { bodies: random.int(1, 6), motion: 'static' });
      const { replay, framing } = framed(recording);
      const expected = boxSphere(liveCorners(recording, replay, 0));
      for (let k = 0; k <= 20; ++k) {
        const { centre, radius } = framing.at((recording.duration * k) / 20);
        assert.ok(centre.distanceTo(expected.centre) < 1e-6 && Math.abs(radius - expected.radius) < 1e-6,
          `recording ${n}: ${centre.toArray()} r ${radius}, expected ${expected.centre.toArray()} r ${expected.radius}`);
      }
    }
  });

  test('moves with bodies at one velocity without trailing them or drawing back', () => {
    const random = randomSource(SEED + 3);
    for (let n = 0; n < 10; ++n) {
      const recording = makeRecording(THREE, random, { bodies: random.int(1, 6), motion: 'linear', keyCount: 30, step: 1 / 16 });
      const { replay, framing } = framed(recording);
      for (const time of framing.times) {
        const expected = boxSphere(liveCorners(recording, replay, time));
        const { centre, radius } = framing.at(time);
        const scale = 1 + expected.centre.length();
        assert.ok(centre.distanceTo(expected.centre) < 1e-4 * scale, `recording ${n} at ${time} s: centre ${centre.toArray()}, bodies at ${expected.centre.toArray()}`);
        assert.ok(Math.abs(radius - expected.radius) < 1e-4 * scale, `recording ${n} at ${time} s: radius ${radius}, bodies ${expected.radius}`);
      }
    }
  });

  test('draws back ahead of bodies born far away, over the window instead of in one jump', () => {
    const random = randomSource(SEED + 4);
    for (let n = 0; n < 10; ++n) {
      const recording = makeRecording(THREE, random, { bodies: random.int(2, 4), motion: 'birth', keyCount: 3, step: 1, birthKey: 1 });
      const window = 0.25;
      const { replay, framing } = framed(recording, { window });
      const birth = recording.bodies[1].birth;
      const before = boxSphere(liveCorners(recording, replay, 0));
      const after = boxSphere(liveCorners(recording, replay, birth));
      const what = `recording ${n}`;
      assert.ok(framing.at(birth - 2.5 * window).radius < before.radius + 1e-9, `${what}: unchanged long before the birth`);
      assert.ok(framing.at(birth - window / 2).radius > before.radius + (after.radius - before.radius) / 2,
        `${what}: half way out a quarter of the window before the birth`);
      let largestStep = 0;
      let largestShift = 0;
      for (let i = 1; i < framing.times.length; ++i) {
        largestStep = Math.max(largestStep, Math.abs(framing.radii[i] - framing.radii[i - 1]));
        largestShift = Math.max(largestShift, framing.centres[i].distanceTo(framing.centres[i - 1]));
      }
      assert.ok(largestStep < (after.radius - before.radius) / 5, `${what}: the radius steps by ${largestStep} at once`);
      assert.ok(largestShift < after.centre.distanceTo(before.centre) / 5, `${what}: the centre jumps by ${largestShift}`);
    }
  });

  test('leaves the bodies posed at time 0 and is empty when no body is ever alive', () => {
    const random = randomSource(SEED + 5);
    const recording = makeRecording(THREE, random, { bodies: 3 });
    const replay = new Replay(recording.root, recording.clip);
    replay.seek(0);
    const atZero = recording.bodies.map((b) => b.object.position.toArray());
    const framing = new ReplayFraming(replay, recording.root);
    assert.equal(framing.empty, false);
    assert.deepEqual(recording.bodies.map((b) => b.object.position.toArray()), atZero);

    const ghosts = new THREE.Group();
    const ghost = new THREE.Object3D();
    ghost.name = 'ghost';
    ghost.userData.body = 0;
    ghost.add(new THREE.Mesh(new THREE.BoxGeometry(1, 1, 1)));
    ghosts.add(ghost);
    const clip = new THREE.AnimationClip('never', -1, [new THREE.VectorKeyframeTrack('ghost.scale', [0, 1], [0, 0, 0, 0, 0, 0],
      THREE.InterpolateDiscrete)]);
    assert.equal(new ReplayFraming(new Replay(ghosts, clip), ghosts).empty, true);
  });

  test('frames the pieces (kind "cluster") and not the projectile, as if it were not a body', () => {
    const random = randomSource(SEED + 7);
    for (let n = 0; n < 20; ++n) {
      const count = random.int(2, 8);
      const spheres = new Set(random.shuffle([...Array(count).keys()]).slice(0, random.int(1, count - 1)));
      const kind = (b) => (spheres.has(b) ? 'sphere' : 'cluster');
      const seed = random.int(0, 1 << 30);
      const recording = makeRecording(THREE, randomSource(seed), { bodies: count, kind });
      const followed = followedBodies(recording.root);
      assert.deepEqual(followed, recording.bodies.filter((_, b) => !spheres.has(b)).map((b) => b.object), `recording ${n}`);
      const { framing } = framed(recording);
      // The same recording with the spheres' extras naming no body: the framing must not change.
      const without = makeRecording(THREE, randomSource(seed), { bodies: count, kind });
      for (const b of spheres) delete without.bodies[b].object.userData.body;
      const { framing: expected } = framed(without);
      assert.equal(framing.empty, expected.empty, `recording ${n}`);
      if (framing.empty) continue;
      framing.times.forEach((time, i) => {
        assert.ok(framing.centres[i].equals(expected.centres[i]) && framing.radii[i] === expected.radii[i],
          `recording ${n} at ${time} s: the projectile changed the framing`);
      });
    }
    // A recording that names no cluster (every body a sphere) still has its bodies followed.
    const spheresOnly = makeRecording(THREE, random, { bodies: 3, kind: () => 'sphere' });
    assert.deepEqual(followedBodies(spheresOnly.root), recordingBodies(spheresOnly.root));
  });

  test('liveBodiesBox and recordingBodies see the bodies the clip shows', () => {
    const random = randomSource(SEED + 6);
    for (let n = 0; n < 10; ++n) {
      const recording = makeRecording(THREE, random, { bodies: random.int(1, 8) });
      const replay = new Replay(recording.root, recording.clip);
      const bodies = recordingBodies(recording.root);
      assert.deepEqual(bodies, recording.bodies.map((b) => b.object));
      // Taken while some bodies are unborn (scale 0), as the viewer takes them at time 0.
      const localBoxes = bodyLocalBoxes(bodies);
      for (let k = 0; k <= 10; ++k) {
        const corners = liveCorners(recording, replay, (recording.duration * k) / 10);
        const box = liveBodiesBox(bodies, localBoxes);
        if (corners.length === 0) assert.ok(box.isEmpty(), `recording ${n}`);
        else assert.ok(box.equals(new THREE.Box3().setFromPoints(corners)), `recording ${n}: ${JSON.stringify(box)}`);
      }
    }
  });
});
