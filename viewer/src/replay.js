// A `shatter simulate --record` recording played back: one animation clip that
// moves each body (translation, rotation) and shows it from its birth to its
// death (a stepped scale channel; runtime/recording.hpp). Time is set, not
// accumulated inside the mixer, so scrubbing and playing agree exactly.

import * as THREE from 'three';

export class Replay {
  constructor(root, clip) {
    this.clip = clip;
    this.mixer = new THREE.AnimationMixer(root);
    this.action = this.mixer.clipAction(clip);
    this.action.play();
    this.duration = clip.duration;
    this.time = 0;
    this.playing = false;
    this.onChange = () => {};
    this.onTime = () => {};
    this.seek(0);
  }

  /** Shows the state at `time` seconds (clamped to the clip). */
  seek(time) {
    this.time = Math.min(Math.max(time, 0), this.duration);
    this.mixer.setTime(this.time);
    this.onTime(this.time);
    this.onChange();
  }

  play() {
    if (this.time >= this.duration) this.seek(0);
    this.playing = true;
    this.onChange();
  }

  pause() {
    this.playing = false;
    this.onChange();
  }

  /** Moves on by `dt` seconds of real time while playing; stops at the end. */
  advance(dt) {
    if (!this.playing) return;
    const next = this.time + dt;
    if (next >= this.duration) {
      this.seek(this.duration);
      this.playing = false;
    } else {
      this.seek(next);
    }
  }
}
