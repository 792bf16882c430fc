// The Player's clock: requestAnimationFrame in the browser, not a kernel thread.
//
// The arithmetic mirrors rbm_nb/widgets/playback.py (Playback.advance):
// while playing, time = anchorTime + (now - anchorWall) * speed, re-anchored on
// every seek, speed change and play; at the end it stops, or wraps with loop.
// The time is set on the model every animation frame (every linked view sees
// it at once) and sent to the kernel at most every THROTTLE_MS, and at once on
// pause and at the end. Nothing here waits for the kernel.
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
    this.onTime = () => {
      const t = Number(model.get("time"));
      if (t !== this.lastSet) {
        // set by the kernel or another view (a seek): continue from there
        this.lastSet = t;
        this.reanchor();
      }
    };
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

  start() {
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
