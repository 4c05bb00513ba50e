// Keeping a recording's bodies in view. In a `simulate --record` replay the
// bodies may travel far (a shot object slides 25 m along the floor, a wall's
// bricks spread over 30 m), so a camera fitted once at time 0 ends up looking
// at an empty floor. The camera instead follows a framing that is a function of
// the replay time alone: per time sample, the bounding sphere of the pieces
// alive then (scale not 0; not the projectile, followedBodies), smoothed over a
// short window of replay time so the view glides rather than jumps when bodies
// are born or die.
//
// Why per time and not one fit to the union over the whole replay: the union
// of a shot object's path is 25 times its size, which would show the object as
// a speck at every instant. Why a function of replay time and not of wall-clock
// time (a camera easing towards a target): scrubbing then shows the same view
// at the same time whatever was shown before, and the browser tests can check
// a frame without waiting for the camera to settle.

import * as THREE from 'three';

/** The distance at which a sphere of `radius` fills a perspective camera's view (fov in degrees, the vertical one). */
export function fitDistance(radius, fovDegrees, aspect) {
  const halfVertical = THREE.MathUtils.degToRad(fovDegrees) / 2;
  const halfHorizontal = Math.atan(Math.tan(halfVertical) * aspect);
  return radius / Math.sin(Math.min(halfVertical, halfHorizontal));
}

/** The bodies of a recording: the objects whose extras name a body. */
export function recordingBodies(root) {
  const bodies = [];
  root.traverse((o) => {
    if (o.userData && Number.isInteger(o.userData.body)) bodies.push(o);
  });
  return bodies;
}

/**
 * The bodies the camera follows: the breakable objects' pieces (extras kind "cluster", runtime/recording.hpp), when
 * the recording names any; else every body. The shot's sphere is left out: after the hit it rolls on, metres away
 * from the pieces, and a camera that kept it in view would show the pieces as specks.
 */
export function followedBodies(root) {
  const bodies = recordingBodies(root);
  const pieces = bodies.filter((body) => body.userData.kind === 'cluster');
  return pieces.length > 0 ? pieces : bodies;
}

const isAlive = (body) => !(body.scale.x === 0 && body.scale.y === 0 && body.scale.z === 0);

/**
 * The boxes of each body's meshes in the body's own frame: the meshes do not move within their body, so over a
 * replay only the body's transform changes, and a sample costs a box transform per mesh rather than a walk over
 * the scene. (Chained up to the body rather than taken from the world: an unborn body's zero scale cannot be undone.)
 */
export function bodyLocalBoxes(bodies) {
  return bodies.map((body) => {
    const boxes = [];
    body.traverse((o) => {
      if (!o.isMesh || o === body) return;
      if (!o.geometry.boundingBox) o.geometry.computeBoundingBox();
      const toBody = new THREE.Matrix4();
      for (let p = o; p !== body; p = p.parent) {
        p.updateMatrix();
        toBody.premultiply(p.matrix);
      }
      boxes.push(o.geometry.boundingBox.clone().applyMatrix4(toBody));
    });
    return boxes;
  });
}

/** The world box of the bodies alive in their current pose (empty when none is); `localBoxes` from bodyLocalBoxes. */
export function liveBodiesBox(bodies, localBoxes) {
  const box = new THREE.Box3();
  const meshBox = new THREE.Box3();
  bodies.forEach((body, i) => {
    if (!isAlive(body)) return;
    body.updateWorldMatrix(true, false);
    for (const local of localBoxes[i]) box.union(meshBox.copy(local).applyMatrix4(body.matrixWorld));
  });
  return box;
}

export class ReplayFraming {
  /**
   * Samples `replay` (a Replay over `root`) at `samplesPerSecond` and smooths over `window` seconds of replay time
   * either side. The samples are at least 2 and at most `maxSamples`, and fewer for a clip of many tracks (at most
   * `maxTrackSamples` track evaluations in all), so a wall of a thousand bodies still opens in a fraction of a second.
   * The bodies framed are followedBodies(root): the pieces, not the projectile. Leaves the replay's bodies posed at
   * time 0; `empty` is true when no such body is alive at any sample (then there is nothing to follow).
   */
  constructor(replay, root, { samplesPerSecond = 60, maxSamples = 600, maxTrackSamples = 200000, window = 0.25 } = {}) {
    const bodies = followedBodies(root);
    const localBoxes = bodyLocalBoxes(bodies);
    const affordable = Math.floor(maxTrackSamples / Math.max(1, replay.clip.tracks.length));
    const count = Math.max(2, Math.min(maxSamples, affordable, Math.ceil(replay.duration * samplesPerSecond) + 1));
    this.times = Array.from({ length: count }, (_, i) => (replay.duration * i) / (count - 1));
    const raw = this.times.map((t) => {
      replay.applyPose(t);
      const box = liveBodiesBox(bodies, localBoxes);
      return box.isEmpty() ? null
        : { centre: box.getCenter(new THREE.Vector3()), radius: Math.max(box.getSize(new THREE.Vector3()).length() / 2, 1e-6) };
    });
    replay.applyPose(0);
    this.empty = raw.every((s) => s === null);
    if (this.empty) return;
    fillGaps(raw);
    const step = replay.duration / (count - 1);
    const half = step > 0 ? Math.round(window / step) : 0;
    // The widest sphere within the window of each sample: a body about to be born far off is allowed for before it
    // appears, so the camera draws back ahead of it.
    const widest = raw.map((_, j) => {
      let radius = 0;
      for (let k = Math.max(0, j - half); k <= Math.min(count - 1, j + half); ++k) radius = Math.max(radius, raw[k].radius);
      return radius;
    });
    this.centres = [];
    this.radii = [];
    for (let i = 0; i < count; ++i) {
      // Means over a window symmetric about the sample (narrower near the ends), so a body moving at constant
      // velocity is centred exactly rather than trailed, and the radius ramps rather than steps.
      const reach = Math.min(half, i, count - 1 - i);
      const centre = new THREE.Vector3();
      let radius = 0;
      for (let j = i - reach; j <= i + reach; ++j) {
        centre.add(raw[j].centre);
        radius += widest[j];
      }
      centre.divideScalar(2 * reach + 1);
      radius /= 2 * reach + 1;
      // Every widest[j] in the mean covers sample i (|i - j| <= half), so radius >= this sample's own; grown by how
      // far the smoothed centre is from this sample's, the sphere holds this sample's bodies.
      this.centres.push(centre);
      this.radii.push(radius + centre.distanceTo(raw[i].centre));
    }
  }

  /** The framing sphere {centre, radius} at replay time `time`, interpolated between samples. */
  at(time) {
    const last = this.times.length - 1;
    const duration = this.times[last];
    const position = duration > 0 ? (Math.min(Math.max(time, 0), duration) / duration) * last : 0;
    const i = Math.min(Math.floor(position), last - 1);
    const f = position - i;
    return {
      centre: this.centres[i].clone().lerp(this.centres[i + 1], f),
      radius: this.radii[i] + f * (this.radii[i + 1] - this.radii[i]),
    };
  }
}

// A sample with no body alive takes the last one before it that has one (at the start, the first after it), so the
// camera holds still across the gap.
function fillGaps(samples) {
  let previous = samples.find((s) => s !== null);
  for (let i = 0; i < samples.length; ++i) {
    if (samples[i] === null) samples[i] = previous;
    else previous = samples[i];
  }
}
