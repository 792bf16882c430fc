// The Player's clock: requestAnimationFrame in the browser, not a kernel thread.
//
// The arithmetic mirrors rbm_nb/widgets/playback.py (Playback.advance):
// while playing, time = anchorTime + (now - anchorWall) * speed, re-anchored on
// every seek, speed change and play; at the end it stops, or wraps with loop.
// The time is set on the model every animation frame (every linked view sees
// it at once) and sent to the kernel at most every THROTTLE_MS, and at once on
// pause and at the end. Nothing here waits for the kernel.
//
// The anchor is always the model's own time: play and every frame re-read
// it, so a time the clock did not see being set (a seek whose change event
// reached another listener first, a set without events, a kernel update
// applied while paused) is where play goes on from, never an older anchor
// (a report: paused at 61.56 s, the first frame after play showed 77.75 s;
// tests/notebook/test_clock_js.py).
import { THROTTLE_MS } from "../timeline.js";

export class Clock {
  constructor(model, { now = () => performance.now(), raf, caf } = {}) {
    this.model = model;
    this.now = now;
    this.raf = raf || ((f) => requestAnimationFrame(f));
    this.caf = caf || ((h) => cancelAnimationFrame(h));
    this.handle = null;
    this.lastSet = Number(model.get("time")) || 0;
    this.anchorTime = this.lastSet;
    this.anchorWall = now();
    this.lastPush = -Infinity;
    this.frames = 0;
    // set by the kernel or another view (a seek): continue from there
    this.onTime = () => this.follow();
    this.onSpeed = () => this.reanchor();
    this.onPlaying = () => {
      if (model.get("playing")) {
        this.start();
      } else {
        this.stopLoop();
        this.push();
      }
    };
    this.frame = () => {
      this.handle = null;
      if (!model.get("playing")) {
        return;
      }
      // a time set since the last frame that no event told us of: a seek
      this.follow();
      const now = this.now();
      const duration = Number(model.get("duration")) || 0;
      const speed = Number(model.get("speed")) || 1;
      let t = this.anchorTime + ((now - this.anchorWall) / 1000) * speed;
      if (t >= duration) {
        if (model.get("loop") && duration > 0) {
          t %= duration;
          this.anchorTime = t;
          this.anchorWall = now;
        } else {
          this.set(duration);
          model.set("playing", false);
          this.push();
          return;
        }
      }
      this.set(Math.max(t, 0));
      this.frames += 1;
      if (now - this.lastPush >= THROTTLE_MS) {
        this.push();
      }
      this.handle = this.raf(this.frame);
    };
    model.on("change:time", this.onTime);
    model.on("change:speed", this.onSpeed);
    model.on("change:playing", this.onPlaying);
    if (model.get("playing")) {
      this.start();
    }
  }

  set(t) {
    this.lastSet = t;
    this.model.set("time", t);
  }

  push() {
    this.lastPush = this.now();
    this.model.save_changes();
  }

  reanchor() {
    this.anchorTime = this.lastSet;
    this.anchorWall = this.now();
  }

  /** Re-anchor at the model's time if it is not the one this clock set last. */
  follow() {
    const t = Number(this.model.get("time")) || 0;
    if (t !== this.lastSet) {
      this.lastSet = t;
      this.reanchor();
    }
  }

  start() {
    // from the model's time as it is now, whoever set it
    this.lastSet = Number(this.model.get("time")) || 0;
    const duration = Number(this.model.get("duration")) || 0;
    if (this.lastSet >= duration) {
      this.set(0);
    }
    this.reanchor();
    if (this.handle === null) {
      this.handle = this.raf(this.frame);
    }
  }

  stopLoop() {
    if (this.handle !== null) {
      this.caf(this.handle);
      this.handle = null;
    }
  }

  dispose() {
    this.stopLoop();
    this.model.off("change:time", this.onTime);
    this.model.off("change:speed", this.onSpeed);
    this.model.off("change:playing", this.onPlaying);
  }
}
