// Properties of viewer/src/replay.js (the recording's clock) on synthetic
// recordings shaped as `simulate --record` writes them (runtime/recording.hpp):
// one node per body, moved by linear translation keys and shown from its birth
// to its death by a stepped scale channel. No WebGL is involved: the animation
// mixer only sets the bodies' transforms.

import assert from 'node:assert/strict';
import { describe, test } from 'node:test';

import { makeRecording, randomSource } from './synthetic.mjs';
import { loadViewerModules } from './viewer-modules.mjs';

const { THREE, Replay, MAX_STEP } = await loadViewerModules();
const SEED = 7041;

// Where a body is at `time` by linear interpolation of its keys, computed here independently of three.js.
function expectedPosition(body, time) {
  const { times, positions } = body;
  let i = 0;
  while (i + 1 < times.length - 1 && times[i + 1] <= time) ++i;
  const t = Math.min(Math.max((time - times[i]) / (times[i + 1] - times[i]), 0), 1);
  return [0, 1, 2].map((k) => positions[3 * i + k] + t * (positions[3 * (i + 1) + k] - positions[3 * i + k]));
}

const recordings = [];
{
  const random = randomSource(SEED);
  for (let i = 0; i < 12; ++i) recordings.push({ ...makeRecording(THREE, random, { bodies: random.int(1, 9) }), label: `seed ${SEED}, recording ${i}` });
}

// Random times strictly between keys (at a key a stepped channel may be either side) plus the ends.
function sampleTimes(random, recording, count) {
  const times = [0, recording.duration];
  while (times.length < count) {
    const t = random.next() * recording.duration;
    if (recording.bodies[0].times.every((key) => Math.abs(key - t) > 1e-6)) times.push(t);
  }
  return times;
}

const poseOf = (recording) => recording.bodies.map((b) => [...b.object.position.toArray(), ...b.object.scale.toArray()]);

function assertPoseAt(recording, time, what) {
  for (const [i, body] of recording.bodies.entries()) {
    const expected = expectedPosition(body, time);
    const actual = body.object.position.toArray();
    for (let k = 0; k < 3; ++k) {
      assert.ok(Math.abs(actual[k] - expected[k]) <= 1e-9 * (1 + Math.abs(expected[k])),
        `${what}, body ${i}: at ${time} s at ${actual}, expected ${expected}`);
    }
    // At the very end a body that dies there is already gone (the stepped key at its death time applies).
    const alive = time >= body.birth && time < body.death;
    assert.equal(body.object.scale.x, alive ? 1 : 0, `${what}, body ${i}: shown at ${time} s (born ${body.birth}, died ${body.death})`);
  }
}

describe('Replay', () => {
  test('lasts as long as its clip and starts paused at 0 with the first pose', () => {
    for (const r of recordings) {
      const replay = new Replay(r.root, r.clip);
      assert.equal(replay.duration, r.duration, r.label);
      assert.equal(replay.time, 0, r.label);
      assert.equal(replay.playing, false, r.label);
      assertPoseAt(r, 0, r.label);
    }
  });

  test('seek shows the interpolated position and the birth-to-death visibility at any time', () => {
    const random = randomSource(SEED + 1);
    for (const r of recordings) {
      const replay = new Replay(r.root, r.clip);
      for (const time of sampleTimes(random, r, 25)) {
        replay.seek(time);
        assert.equal(replay.time, time, r.label);
        assertPoseAt(r, time, r.label);
      }
    }
  });

  test('seek depends on the time only, not on the times shown before', () => {
    const random = randomSource(SEED + 2);
    for (const r of recordings) {
      const replay = new Replay(r.root, r.clip);
      const times = sampleTimes(random, r, 12);
      const direct = times.map((t) => { replay.seek(t); return poseOf(r); });
      for (let n = 0; n < 20; ++n) {
        const i = random.int(0, times.length - 1);
        replay.seek(random.next() * r.duration);
        replay.seek(times[i]);
        assert.deepEqual(poseOf(r), direct[i], `${r.label}: at ${times[i]} s after a jump`);
      }
    }
  });

  test('seek clamps to the clip', () => {
    for (const r of recordings) {
      const replay = new Replay(r.root, r.clip);
      replay.seek(0);
      const first = poseOf(r);
      replay.seek(r.duration);
      const last = poseOf(r);
      replay.seek(-3);
      assert.equal(replay.time, 0, r.label);
      assert.deepEqual(poseOf(r), first, r.label);
      replay.seek(r.duration + 3);
      assert.equal(replay.time, r.duration, r.label);
      assert.deepEqual(poseOf(r), last, r.label);
    }
  });

  test('advance moves the clock by at most MAX_STEP however long a frame took', () => {
    const random = randomSource(SEED + 4);
    for (const r of recordings) {
      const replay = new Replay(r.root, r.clip);
      replay.play();
      for (let n = 0; n < 5 && replay.playing; ++n) {
        const before = replay.time;
        replay.advance(random.int(1, 100) * MAX_STEP);
        assert.ok(replay.time - before <= MAX_STEP + 1e-12, `${r.label}: ${before} -> ${replay.time} in one frame`);
        assert.ok(replay.time === r.duration || Math.abs(replay.time - before - MAX_STEP) < 1e-12, `${r.label}: a full step unless at the end`);
      }
    }
  });

  test('advance moves the clock by the real time while playing, stops at the end, and not at all when paused', () => {
    const random = randomSource(SEED + 3);
    for (const r of recordings) {
      const replay = new Replay(r.root, r.clip);
      const told = [];
      let changes = 0;
      replay.onTime = (t) => told.push(t);
      replay.onChange = () => { ++changes; };
      replay.advance(0.5);
      assert.equal(replay.time, 0, `${r.label}: paused`);
      replay.play();
      assert.equal(replay.playing, true, r.label);
      let expected = 0;
      while (replay.playing) {
        const dt = random.int(1, 30) / 1000;
        replay.advance(dt);
        expected = Math.min(expected + dt, r.duration);
        assert.ok(Math.abs(replay.time - expected) < 1e-12, `${r.label}: ${replay.time} after steps summing to ${expected}`);
        assertPoseAt(r, replay.time, r.label);
      }
      assert.equal(replay.time, r.duration, `${r.label}: stops exactly at the end`);
      assert.equal(told.at(-1), r.duration, r.label);
      assert.ok(changes >= told.length, r.label);
      replay.play();
      assert.equal(replay.time, 0, `${r.label}: play at the end starts again from 0`);
      replay.advance(r.duration / 3);
      replay.pause();
      const paused = replay.time;
      replay.advance(1);
      assert.equal(replay.time, paused, `${r.label}: pause stops the clock`);
    }
  });
});
