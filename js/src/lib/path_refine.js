// A path drawn finer where the camera has zoomed in (rbm_nb/scene/path_refine.py).
//
// The kernel sends each path simplified for the whole of it. When the camera
// has not moved for SETTLE_MS, this works out, per path, the box (in the
// path's own coordinates) of what the view shows of its line and the size of
// half a pixel at the nearer of those points. Where half a pixel is finer
// than the line drawn, it asks the kernel for the line through that box at
// that tolerance (the request carries the box and the tolerance; the kernel
// checks, snaps and clamps both), then draws the answer in place of the
// coarse line inside the box. Zoomed back out, the coarse line alone is drawn
// again. Answers are kept (a few boxes per path); an answer to a superseded
// request is kept but not drawn.

const SETTLE_MS = 250;
// the box asked for reaches this share of its size beyond what is seen, so
// a small pan or zoom stays inside it
const MARGIN = 0.25;
// a box's corners snap outward to multiples of this many tolerances (as the kernel)
const SNAP_CELLS = 256;
// refine when half a pixel is below this share of the coarse line's error
const FINER = 0.5;
// points tried along each coarse segment: a segment can cross the view with
// both ends outside it
const STEPS = 8;
const CACHED = 16;

export class PathRefiner {
  constructor(view) {
    this.view = view;
    this.model = view.model;
    this.THREE = view.THREE;
    this.id = Math.random().toString(36).slice(2);
    this.paths = null; // [{id, node, tolerance, error, diagonal}] from the kernel
    this.askedPaths = false;
    this.cameraKey = "";
    this.movedAt = 0;
    this.settled = false;
    this.latest = new Map(); // path id -> request id of the newest request
    this.sentAt = new Map(); // request id -> ms
    this.requests = 0;
    this.cache = new Map(); // request key -> answer
    this.shown = new Map(); // node -> {key, answer, source, objects}
    this.stats = { asked: 0, answered: 0, refused: 0, cached: 0, latencyMs: [], lastRefusal: null };
    this.onMessage = (msg, buffers) => this.take(msg, buffers || []);
    this.model.on("msg:custom", this.onMessage);
  }

  /** Content changed (commands applied): paths may have come, gone or been redrawn. */
  reset() {
    // a redrawn path's overlay is dropped once the list is back (evaluatePath)
    this.paths = null;
    this.askedPaths = false;
    this.settled = false;
  }

  tick(now) {
    const camera = this.view.viewer.camera;
    camera.updateMatrixWorld();
    const key = `${camera.matrixWorld.elements.join(",")}:${this.view.pane.clientWidth}x${this.view.pane.clientHeight}`;
    if (key !== this.cameraKey) {
      this.cameraKey = key;
      this.movedAt = now;
      this.settled = false;
      return;
    }
    if (!this.settled && now - this.movedAt >= SETTLE_MS) {
      this.settled = true;
      this.evaluate();
    }
  }

  evaluate() {
    for (const [node, shown] of [...this.shown]) {
      if (!shown.source.parent) this.drop(node); // deleted with its scene node
    }
    if (!this.paths) {
      if (!this.askedPaths) {
        this.askedPaths = true;
        this.model.send({ type: "paths", view: this.id });
      }
      return;
    }
    for (const path of this.paths) this.evaluatePath(path);
  }

  /** The coarse line object of a path, or null. */
  source(path) {
    let node;
    try {
      node = this.view.node(path.node);
    } catch (err) {
      return null;
    }
    // meshcat may keep the loaded line below the node's own object
    let found = null;
    if (node) {
      node.traverse((o) => {
        if (!found && o.isLineSegments && o.name !== "rbm-refined") found = o;
      });
    }
    return found;
  }

  /** What the view shows of a path: {low, high, distance} in its coordinates, or null. */
  seen(object) {
    const THREE = this.THREE;
    const camera = this.view.viewer.camera;
    object.updateMatrixWorld(true);
    const toClip = new THREE.Matrix4()
      .multiplyMatrices(camera.projectionMatrix, camera.matrixWorldInverse)
      .multiply(object.matrixWorld);
    const eye = camera.getWorldPosition(new THREE.Vector3());
    const p = object.geometry.attributes.position.array;
    const low = [Infinity, Infinity, Infinity];
    const high = [-Infinity, -Infinity, -Infinity];
    const distances = [];
    const local = new THREE.Vector3();
    const clip = new THREE.Vector4();
    const world = new THREE.Vector3();
    let seenAny = false;
    const tryPoint = (x, y, z) => {
      clip.set(x, y, z, 1).applyMatrix4(toClip);
      if (!(clip.w > 0)) return;
      const nx = clip.x / clip.w;
      const ny = clip.y / clip.w;
      if (nx < -1 || nx > 1 || ny < -1 || ny > 1) return;
      seenAny = true;
      low[0] = Math.min(low[0], x);
      low[1] = Math.min(low[1], y);
      low[2] = Math.min(low[2], z);
      high[0] = Math.max(high[0], x);
      high[1] = Math.max(high[1], y);
      high[2] = Math.max(high[2], z);
      distances.push(world.set(x, y, z).applyMatrix4(object.matrixWorld).distanceTo(eye));
    };
    for (let i = 0; i + 5 < p.length; i += 6) {
      for (let s = 0; s <= STEPS; s++) {
        const f = s / STEPS;
        local.set(p[i] + f * (p[i + 3] - p[i]), p[i + 1] + f * (p[i + 4] - p[i + 1]), p[i + 2] + f * (p[i + 5] - p[i + 2]));
        tryPoint(local.x, local.y, local.z);
      }
    }
    if (!seenAny) return null;
    distances.sort((a, b) => a - b);
    return { low, high, distance: distances[Math.floor(0.1 * (distances.length - 1))] };
  }

  /** Metres of half a pixel at ``distance`` from the camera, in the path's units. */
  halfPixel(object, distance) {
    const camera = this.view.viewer.camera;
    const height = this.view.pane.clientHeight || 1;
    const scale = object.getWorldScale(new this.THREE.Vector3()).x || 1;
    let pixel;
    if (camera.isOrthographicCamera) {
      pixel = (camera.top - camera.bottom) / (camera.zoom || 1) / height;
    } else {
      pixel = (2 * distance * Math.tan(((camera.fov || 75) * Math.PI) / 360)) / height;
    }
    return (0.5 * pixel) / scale;
  }

  evaluatePath(path) {
    const object = this.source(path);
    const shown = this.shown.get(path.node);
    if (shown && shown.source !== object) this.drop(path.node);
    if (!object) return;
    const seen = this.seen(object);
    const tolerance = seen ? this.halfPixel(object, seen.distance) : Infinity;
    if (!seen || !(tolerance < FINER * path.error)) {
      this.drop(path.node); // zoomed out: the coarse line is fine again
      return;
    }
    const level = Math.floor(Math.log2(tolerance));
    const cell = SNAP_CELLS * 2 ** level;
    const lo = [];
    const hi = [];
    for (let k = 0; k < 3; k++) {
      const room = MARGIN * (seen.high[k] - seen.low[k]);
      lo.push(Math.floor((seen.low[k] - room) / cell) * cell);
      hi.push(Math.ceil((seen.high[k] + room) / cell) * cell);
    }
    const current = this.shown.get(path.node);
    if (current && current.answer.level <= level && contains(current.answer, seen)) return;
    const key = `${path.id}:${level}:${lo.join(",")}:${hi.join(",")}`;
    if (this.cache.has(key)) {
      this.stats.cached += 1;
      this.show(path, this.cache.get(key));
      return;
    }
    this.requests += 1;
    this.latest.set(path.id, this.requests);
    this.sentAt.set(this.requests, performance.now());
    this.stats.asked += 1;
    this.model.send({ type: "path_refine", view: this.id, id: this.requests, path: path.id, lo, hi, tolerance });
    this.pendingKey = key;
    this.keys = this.keys || new Map();
    this.keys.set(this.requests, key);
  }

  take(msg, buffers) {
    if (!msg || msg.view !== this.id) return;
    if (msg.type === "paths") {
      this.paths = msg.paths || [];
      this.evaluate();
      return;
    }
    if (msg.type !== "path_refine") return;
    if (msg.refused) {
      this.stats.refused += 1;
      this.stats.lastRefusal = msg.refused;
      return;
    }
    const sent = this.sentAt.get(msg.id);
    this.sentAt.delete(msg.id);
    if (sent !== undefined) this.stats.latencyMs.push(performance.now() - sent);
    this.stats.answered += 1;
    const bytes = buffers[0];
    const view = bytes instanceof ArrayBuffer ? new Uint8Array(bytes) : new Uint8Array(bytes.buffer, bytes.byteOffset, bytes.byteLength);
    const answer = { ...msg, positions: new Float32Array(view.slice().buffer) };
    const key = this.keys && this.keys.get(msg.id);
    if (key) {
      this.keys.delete(msg.id);
      this.cache.set(key, answer);
      if (this.cache.size > CACHED) this.cache.delete(this.cache.keys().next().value);
    }
    if (this.latest.get(msg.path) !== msg.id) return; // the view has moved on
    const path = (this.paths || []).find((p) => p.id === msg.path);
    if (path) this.show(path, answer);
  }

  /** Draw ``answer`` in place of the coarse line inside its box. */
  show(path, answer) {
    const object = this.source(path);
    if (!object) return;
    this.drop(path.node);
    const THREE = this.THREE;
    const coarse = object.geometry.attributes.position.array;
    const kept = [];
    const inside = (i) =>
      coarse[i] >= answer.lo[0] && coarse[i] <= answer.hi[0] &&
      coarse[i + 1] >= answer.lo[1] && coarse[i + 1] <= answer.hi[1] &&
      coarse[i + 2] >= answer.lo[2] && coarse[i + 2] <= answer.hi[2];
    for (let i = 0; i + 5 < coarse.length; i += 6) {
      if (inside(i) && inside(i + 3)) continue; // the refined line draws this part
      for (let k = 0; k < 6; k++) kept.push(coarse[i + k]);
    }
    const objects = [];
    for (const positions of [new Float32Array(kept), answer.positions]) {
      const geometry = new THREE.BufferGeometry();
      geometry.setAttribute("position", new THREE.BufferAttribute(positions, 3));
      const line = new THREE.LineSegments(geometry, object.material);
      line.matrixAutoUpdate = false;
      line.matrix.copy(object.matrix);
      line.name = "rbm-refined";
      object.parent.add(line);
      objects.push(line);
    }
    object.visible = false;
    this.shown.set(path.node, { answer, source: object, objects, refined: answer.positions.length / 3 });
    this.view.viewer.set_dirty();
  }

  drop(node) {
    const shown = this.shown.get(node);
    if (!shown) return;
    for (const line of shown.objects) {
      if (line.parent) line.parent.remove(line);
      line.geometry.dispose();
    }
    shown.source.visible = true;
    this.shown.delete(node);
    this.view.viewer.set_dirty();
  }

  /** Vertices drawn for ``node`` that the view shows (for tests). */
  visibleVertices(node) {
    const path = (this.paths || []).find((p) => p.node === node);
    const object = path ? this.source(path) : null;
    const shown = this.shown.get(node);
    const lines = shown ? shown.objects : object ? [object] : [];
    const camera = this.view.viewer.camera;
    const THREE = this.THREE;
    let count = 0;
    for (const line of lines) {
      line.updateMatrixWorld(true);
      const toClip = new THREE.Matrix4()
        .multiplyMatrices(camera.projectionMatrix, camera.matrixWorldInverse)
        .multiply(line.matrixWorld);
      const p = line.geometry.attributes.position.array;
      const v = new THREE.Vector4();
      // segment ends come in pairs; a vertex shared by two segments counts once
      for (let i = 0; i + 2 < p.length; i += 3) {
        if (i >= 3 && i % 6 === 0 && p[i] === p[i - 3] && p[i + 1] === p[i - 2] && p[i + 2] === p[i - 1]) continue;
        v.set(p[i], p[i + 1], p[i + 2], 1).applyMatrix4(toClip);
        if (v.w > 0 && Math.abs(v.x / v.w) <= 1 && Math.abs(v.y / v.w) <= 1) count += 1;
      }
    }
    return count;
  }

  dispose() {
    this.model.off("msg:custom", this.onMessage);
    for (const node of [...this.shown.keys()]) this.drop(node);
  }
}

function contains(answer, seen) {
  for (let k = 0; k < 3; k++) {
    if (seen.low[k] < answer.lo[k] || seen.high[k] > answer.hi[k]) return false;
  }
  return true;
}
