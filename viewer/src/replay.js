// A `shatter simulate --record` recording played back: one animation clip that
// moves each body (translation, rotation) and shows it from its birth to its
// death (a stepped scale channel; runtime/recording.hpp). Time is set, not
// accumulated inside the mixer, so scrubbing and playing agree exactly.

import * as THREE from 'three';

/** The most replay time one frame moves on, s: real time below 10 frames a second, slower than it above. */
export const MAX_STEP = 0.1;

export class Replay {
  constructor(root, clip) {
    this.clip = clip;
    this.mixer = new THREE.AnimationMixer(root);
    this.action = this.mixer.clipAction(clip);
    // Played once and held at its end: three.js's default (LoopRepeat) wraps the clip's last instant back to its
    // first pose, so the end of the timeline would show the bodies as they started.
    this.action.setLoop(THREE.LoopOnce, 1);
    this.action.clampWhenFinished = true;
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
    this.applyPose(this.time);
    this.onTime(this.time);
    this.onChange();
  }

  /** Poses the bodies as at `time` without moving the clock or telling anyone: for looking ahead (framing.js). */
  applyPose(time) {
    // Reaching the end pauses a clamped action; reset() lifts that, so scrubbing back from the end moves the bodies.
    this.action.reset();
    this.mixer.setTime(Math.min(Math.max(time, 0), this.duration));
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

  /**
   * Moves on by `dt` seconds of real time while playing, but by at most MAX_STEP: after a stall (a hidden tab, whose
   * frames the browser stops, or a frame that took seconds to draw in software) the replay goes on from where it
   * was instead of jumping past what was never shown, possibly to its end. Stops at the end.
   */
  advance(dt) {
    if (!this.playing) return;
    const next = this.time + Math.min(dt, MAX_STEP);
    if (next >= this.duration) {
      this.seek(this.duration);
      this.playing = false;
    } else {
      this.seek(next);
    }
  }
}
