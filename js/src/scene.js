// The 3D view: meshcat's own viewer inside an anywidget.
//
// meshcat's viewer bundle (the meshcat Python package's
// viewer/dist/main.min.js) is prepended to this module by the Python side and
// defines globalThis.MeshCat. Scene content arrives over the widget comm:
//   {type: "snapshot", commands: n, tracks: [...], pins: {...}, stream?}  after "ready"
//   {type: "commands"}        meshcat msgpack commands, one per buffer
//   {type: "tracks", tracks: [...], remove: [...]}
//   {type: "chunk", index, generation, tracks: [...]}   a streamed scene's poses
// A track is {path, n, times, translation, rotation, scale}: buffer indices of
// float64 seconds from the scene's origin, float32 xyz, xyzw and scale.
// Poses are applied here every animation frame from the linked Player's time
// (timeline.js), so playback needs no kernel.
//
// A long recording streams (rbm_nb/scene/stream.py): the snapshot's tracks are
// a coarse copy and `stream` = {chunk: seconds, count, generation, first}.
// Chunk k holds every sample for the times [k, k + 1) * chunk. Each frame the
// view asks the kernel for the chunks at and ahead of the playhead (farther
// ahead the faster it plays) and drops those behind; where a chunk has not
// arrived, the coarse copy is shown. The clock never waits for a chunk.
import { PathRefiner } from "./lib/path_refine.js";
import { followPlayer } from "./timeline.js";

const STORES = new Map();
const CSS = `
.rbm-scene { position: relative; width: 100%; overflow: hidden; background: #222; outline: none;
  resize: vertical; min-height: 120px; }
.rbm-scene .rbm-pane { position: absolute; inset: 0; }
.rbm-scene .rbm-overlay { position: absolute; inset: 0; pointer-events: none; overflow: hidden; }
.rbm-scene .rbm-label { position: absolute; transform: translate(6px, -50%); font: 12px sans-serif;
  color: #fff; background: rgba(0,0,0,.55); padding: 1px 5px; border-radius: 3px; white-space: nowrap;
  pointer-events: auto; cursor: pointer; }
.rbm-scene .rbm-label.rbm-selected { background: #d9a400; color: #000; font-weight: bold; }
.rbm-scene .rbm-legend { position: absolute; left: 6px; bottom: 6px; font: 12px sans-serif; color: #fff;
  background: rgba(0,0,0,.5); padding: 4px 8px; border-radius: 4px; pointer-events: none; line-height: 1.5; }
.rbm-scene .rbm-swatch { display: inline-block; width: 14px; height: 4px; margin-right: 6px;
  vertical-align: middle; }
.rbm-scene .rbm-tools { position: absolute; left: 6px; top: 6px; display: flex; gap: 4px; }
.rbm-scene .rbm-tools button { font: 12px sans-serif; color: #fff; background: rgba(0,0,0,.55);
  border: 1px solid rgba(255,255,255,.35); border-radius: 3px; padding: 2px 8px; cursor: pointer; }
.rbm-scene .rbm-tools button:disabled { opacity: .45; cursor: default; }
.rbm-scene .rbm-tools button.rbm-on { background: #d9a400; color: #000; }
.rbm-scene .rbm-info { position: absolute; left: 6px; top: 6px; font: 12px sans-serif; color: #fff;
  background: rgba(0,0,0,.45); padding: 2px 6px; border-radius: 3px; pointer-events: none; }
`;

function injectStyle() {
  if (document.getElementById("rbm-scene-style")) {
    return;
  }
  const style = document.createElement("style");
  style.id = "rbm-scene-style";
  style.textContent = CSS;
  document.head.appendChild(style);
}

function bytesOf(buffer) {
  if (buffer instanceof Uint8Array) {
    return buffer;
  }
  if (ArrayBuffer.isView(buffer)) {
    return new Uint8Array(buffer.buffer, buffer.byteOffset, buffer.byteLength);
  }
  return new Uint8Array(buffer);
}

function typed(Kind, buffer) {
  // copy: comm buffers need not be aligned for Float64Array
  const bytes = bytesOf(buffer);
  return new Kind(bytes.slice().buffer);
}

/** Samples of one track: {times, translation, rotation, scale, hint}. */
function decodeSamples(m, buffers) {
  return {
    times: typed(Float64Array, buffers[m.times]),
    translation: typed(Float32Array, buffers[m.translation]),
    rotation: typed(Float32Array, buffers[m.rotation]),
    scale: m.scale === null || m.scale === undefined ? null : typed(Float32Array, buffers[m.scale]),
    hint: 0,
  };
}

function decodeTracks(meta, buffers) {
  return meta.map((m) => ({
    path: m.path,
    parts: m.path.split("/").filter((p) => p.length > 0),
    whole: decodeSamples(m, buffers), // every sample, or a streamed scene's coarse copy
    chunks: new Map(), // chunk index -> samples (streamed scenes)
  }));
}

// Prefetch: the chunks covering this many seconds of wall-clock play ahead
// of the playhead are asked for (at least the next one), and chunks more than
// KEEP_BEHIND behind it are dropped, so the page holds a bounded window.
const PREFETCH_WALL_SECONDS = 4;
const MAX_AHEAD = 12;
const KEEP_BEHIND = 1;
// a request unanswered this long (ms) is asked again
const RETRY_MS = 5000;

class Store {
  constructor() {
    this.commands = [];
    this.tracks = new Map();
    this.pins = {};
    this.views = new Set();
    this.model = null;
    this.stream = null; // {chunk, count, generation, first} of a streamed scene
    this.asked = new Map(); // chunk index -> time asked (ms), until it arrives
    this.loaded = new Set(); // chunk indices held
    this.chunksReceived = 0;
    this.chunksDropped = 0;
  }

  /** Chunk index of a time (seconds from the scene's origin). */
  chunkOf(t) {
    const k = Math.floor(t / this.stream.chunk);
    return Math.min(Math.max(k, 0), this.stream.count - 1);
  }

  /** Ask for the chunks at and ahead of ``times``; drop the others. */
  want(times, speed) {
    if (!this.stream || !this.model) {
      return;
    }
    const ahead = Math.min(
      MAX_AHEAD,
      1 + Math.ceil((Math.abs(speed) * PREFETCH_WALL_SECONDS) / this.stream.chunk),
    );
    const keep = new Set();
    const missing = [];
    const now = performance.now();
    for (const t of times) {
      const here = this.chunkOf(t);
      for (let k = here - KEEP_BEHIND; k <= here + ahead; k++) {
        if (k < 0 || k >= this.stream.count) continue;
        keep.add(k);
        if (k < here) continue; // behind: kept if held, never asked for
        const asked = this.asked.get(k);
        if (!this.loaded.has(k) && (asked === undefined || now - asked > RETRY_MS)) {
          missing.push(k);
        }
      }
    }
    for (const k of [...this.loaded]) {
      if (!keep.has(k)) {
        this.loaded.delete(k);
        this.chunksDropped += 1;
        for (const track of this.tracks.values()) track.chunks.delete(k);
      }
    }
    if (missing.length) {
      missing.sort((a, b) => a - b);
      for (const k of missing) this.asked.set(k, now);
      this.model.send({ type: "chunks", indices: missing, generation: this.stream.generation });
    }
  }

  /** The samples to show ``track`` from at time ``t``: its chunk, else the whole/coarse copy. */
  samplesAt(track, t) {
    if (!this.stream) {
      return track.whole;
    }
    return track.chunks.get(this.chunkOf(t)) || null;
  }

  handle(msg, buffers) {
    if (msg.type === "snapshot") {
      this.commands = buffers.slice(0, msg.commands).map((b) => bytesOf(b).slice());
      this.tracks = new Map(decodeTracks(msg.tracks, buffers).map((t) => [t.path, t]));
      this.pins = msg.pins || {};
      this.stream = msg.stream || null;
      this.asked.clear();
      this.loaded.clear();
      // the kernel sends the chunks at its playhead right after this message
      for (const k of this.stream ? this.stream.first : []) this.asked.set(k, performance.now());
      for (const view of this.views) {
        view.rebuild();
      }
    } else if (msg.type === "chunk") {
      if (!this.stream || msg.generation !== this.stream.generation) {
        return; // an answer about content that has changed since
      }
      this.asked.delete(msg.index);
      this.loaded.add(msg.index);
      this.chunksReceived += 1;
      for (const m of msg.tracks) {
        const track = this.tracks.get(m.path);
        if (track) track.chunks.set(msg.index, decodeSamples(m, buffers));
      }
      for (const view of this.views) {
        view.posesDirty = true;
      }
    } else if (msg.type === "commands") {
      const fresh = buffers.map((b) => bytesOf(b).slice());
      this.commands.push(...fresh);
      for (const view of this.views) {
        view.apply(fresh);
      }
    } else if (msg.type === "tracks") {
      for (const path of msg.remove || []) {
        this.tracks.delete(path);
      }
      for (const t of decodeTracks(msg.tracks || [], buffers)) {
        this.tracks.set(t.path, t);
      }
      if (msg.pins) {
        this.pins = msg.pins;
      }
      for (const view of this.views) {
        view.posesDirty = true;
      }
    }
  }
}

function storeFor(model) {
  const key = model.get("_uid");
  let store = STORES.get(key);
  if (!store) {
    store = new Store();
    STORES.set(key, store);
  }
  return store;
}

/** Index of the latest time <= t, -1 before the first (hint: last answer). */
function searchTime(times, t, hint) {
  const n = times.length;
  if (n === 0 || t < times[0]) {
    return -1;
  }
  if (hint >= 0 && hint < n && times[hint] <= t && (hint + 1 === n || times[hint + 1] > t)) {
    return hint;
  }
  if (hint + 1 < n && times[hint + 1] <= t && (hint + 2 >= n || times[hint + 2] > t)) {
    return hint + 1;
  }
  let lo = 0;
  let hi = n - 1;
  while (lo < hi) {
    const mid = (lo + hi + 1) >> 1;
    if (times[mid] <= t) {
      lo = mid;
    } else {
      hi = mid - 1;
    }
  }
  return lo;
}

function isSoftware(gl) {
  const info = gl.getExtension("WEBGL_debug_renderer_info");
  const name = info ? String(gl.getParameter(info.UNMASKED_RENDERER_WEBGL)) : "";
  return /swiftshader|llvmpipe|software/i.test(name);
}

// Whether WebGL draws on the CPU (remote desktops, CI, headless browsers),
// asked once per page of a throwaway context that is released at once: a
// WebGL context holds its drawing buffers until it is garbage collected, so
// the 3D view makes exactly one, with the settings this answer decides.
let SOFTWARE = null;
function softwareWebGL() {
  if (SOFTWARE === null) {
    SOFTWARE = false;
    try {
      const gl = document.createElement("canvas").getContext("webgl", { antialias: false });
      if (gl) {
        SOFTWARE = isSoftware(gl);
        const lose = gl.getExtension("WEBGL_lose_context");
        if (lose) lose.loseContext();
      }
    } catch (err) {
      SOFTWARE = false;
    }
  }
  return SOFTWARE;
}

function cssColor(value) {
  return typeof value === "number" ? `#${value.toString(16).padStart(6, "0")}` : String(value);
}

// Screen-space sizing. Far from the camera, real sizes vanish: a 20 cm head
// on a 100 m walk is one pixel. Every group drawn relative to a moving frame
// (meshcat node /rbm/anchor_<frame>: a head model, its eyes and gaze rays) is
// magnified about that frame's origin until its largest mesh dimension spans
// GLYPH_PX pixels, and every other frame triad until its axes span TRIAD_PX;
// close up, both are drawn at their real size.
const GLYPH_PX = 72;
const TRIAD_PX = 40;
// a long line in a magnified group (a gaze ray) is drawn at its real length,
// or this long on screen when that is shorter, never magnified further
const RAY_PX = 160;
const ANCHOR_PREFIX = "anchor_";

class View {
  constructor(model, el, store) {
    const MeshCat = globalThis.MeshCat;
    if (!MeshCat) {
      throw new Error("rbm_nb: meshcat's viewer did not load");
    }
    this.THREE = MeshCat.THREE;
    this.model = model;
    this.store = store;
    this.root = document.createElement("div");
    this.root.className = "rbm-scene";
    this.root.tabIndex = 0;
    this.pane = document.createElement("div");
    this.pane.className = "rbm-pane";
    this.overlay = document.createElement("div");
    this.overlay.className = "rbm-overlay";
    this.legend = document.createElement("div");
    this.legend.className = "rbm-legend";
    this.info = document.createElement("div");
    this.info.className = "rbm-info";
    this.info.style.display = "none";
    this.tools = document.createElement("div");
    this.tools.className = "rbm-tools";
    this.followButton = document.createElement("button");
    this.followButton.type = "button";
    this.followButton.className = "rbm-follow";
    this.fitButton = document.createElement("button");
    this.fitButton.type = "button";
    this.fitButton.className = "rbm-fit";
    this.fitButton.textContent = "fit";
    this.fitButton.title = "Show the whole scene";
    this.tools.append(this.followButton, this.fitButton);
    this.root.append(this.pane, this.overlay, this.legend, this.info, this.tools);
    el.appendChild(this.root);
    this.root.style.height = `${model.get("height")}px`;

    // Our own renderer, handed to meshcat (which would make an antialiased
    // one with soft shadows): without a GPU, antialiasing is done on the CPU,
    // halves the frame rate and multiplies the drawing buffers by its samples
    const renderer = new this.THREE.WebGLRenderer({ antialias: !softwareWebGL(), alpha: true });
    // lines and triads cast no useful shadows; shadow maps cost a second render per frame
    renderer.shadowMap.enabled = false;
    this.pane.appendChild(renderer.domElement);
    const viewer = new MeshCat.Viewer(this.pane, false, renderer);
    // meshcat sizes itself to the window; a widget has its own box
    const pane = this.pane;
    const original = viewer.set_3d_pane_size.bind(viewer);
    viewer.set_3d_pane_size = (w, h) =>
      original(w === undefined ? pane.clientWidth || 1 : w, h === undefined ? pane.clientHeight || 1 : h);
    viewer.camera.far = 1e5;
    viewer.camera.near = 0.01;
    viewer.camera.updateProjectionMatrix();
    if (viewer.gui && viewer.gui.domElement) {
      viewer.gui.domElement.style.zIndex = "2";
    }
    this.viewer = viewer;
    this.resize = new ResizeObserver(() => viewer.set_3d_pane_size());
    this.resize.observe(this.pane);

    this.player = null;
    this.stopFollowing = followPlayer(model, () => {}, {
      onPlayer: (player) => {
        this.player = player;
        this.posesDirty = true;
      },
    });
    this.lastTime = NaN;
    this.posesDirty = true;
    this.labels = new Map();
    this.frames = 0;
    this.coarseFrames = 0; // frames that showed a coarse pose (a chunk was late)
    this.shown = null;
    this.nodes = new Map();
    this.glyphs = null; // [{object, size}] of the anchors, found after each change
    this.refiner = new PathRefiner(this); // paths finer where the camera zooms in
    this.rebuild();
    this.applyCamera();
    this.showLegend();
    this.showLabels();

    model.on("change:_camera", () => this.applyCamera());
    model.on("change:_legend", () => this.showLegend());
    model.on("change:_labels", () => this.showLabels());
    model.on("change:_frames", () => {
      this.glyphs = null;
    });
    model.on("change:labels", () => this.showLabels());
    model.on("change:selected", () => this.showLabels());
    model.on("change:height", () => {
      this.root.style.height = `${model.get("height")}px`;
    });
    for (const name of ["time", "_origin", "_player_shift", "_pins"]) {
      model.on(`change:${name}`, () => {
        this.posesDirty = true;
      });
    }
    this.followButton.addEventListener("click", () => {
      const following = model.get("follow");
      model.set("follow", following ? null : model.get("selected") || null);
      model.save_changes();
      this.showTools();
    });
    this.fitButton.addEventListener("click", () => {
      if (model.get("follow")) {
        model.set("follow", null);
        model.save_changes();
      }
      this.applyCamera();
    });
    model.on("change:follow", () => this.showTools());
    model.on("change:selected", () => this.showTools());
    this.showTools();
    this.installPicking();
    this.root.rbmView = this;
    this.loop = () => {
      this.handle = requestAnimationFrame(this.loop);
      this.tick();
    };
    this.handle = requestAnimationFrame(this.loop);
  }

  /** Seconds from the scene's origin that should be shown now. */
  currentTime() {
    if (this.player) {
      // the kernel counts the shift between the two second 0s exactly (int64
      // ns); subtracting the two float epoch seconds here lost ~0.24 us
      const shift = this.model.get("_player_shift");
      if (shift !== null && shift !== undefined) {
        return Number(shift) + Number(this.player.get("time"));
      }
      const origin = Number(this.player.get("origin")) || 0;
      return origin + Number(this.player.get("time")) - (Number(this.model.get("_origin")) || 0);
    }
    const t = this.model.get("time");
    return t === null || t === undefined ? 0 : Number(t);
  }

  rebuild() {
    this.viewer.delete_path(["rbm"]);
    this.nodes.clear();
    this.apply(this.store.commands);
    this.posesDirty = true;
  }

  apply(commands) {
    for (const bytes of commands) {
      this.viewer.handle_command_bytearray(bytes);
    }
    this.nodes.clear();
    this.glyphs = null;
    this.triads = null;
    this.posesDirty = true;
    this.refiner.reset();
    this.viewer.set_dirty();
  }

  /** Pixels per metre at a world position (perspective camera). */
  pixelsPerMetre(position) {
    const camera = this.viewer.camera;
    const distance = camera.getWorldPosition(new this.THREE.Vector3()).distanceTo(position);
    const height = this.pane.clientHeight || 1;
    const fov = ((camera.fov || 75) * Math.PI) / 180;
    return height / (2 * Math.max(distance, 1e-9) * Math.tan(fov / 2));
  }

  /** Largest dimension (m) of the meshes below ``object`` at scale 1 (lines if none). */
  naturalSize(object) {
    const THREE = this.THREE;
    const saved = object.scale.clone();
    object.scale.setScalar(1);
    object.updateMatrixWorld(true);
    const meshes = new THREE.Box3();
    const all = new THREE.Box3();
    object.traverse((o) => {
      if (o === object || !o.geometry) return;
      (o.isMesh ? meshes : all).expandByObject(o);
    });
    object.scale.copy(saved);
    object.updateMatrixWorld(true);
    const box = meshes.isEmpty() ? all : meshes;
    if (box.isEmpty()) return 0;
    const size = box.getSize(new THREE.Vector3());
    return Math.max(size.x, size.y, size.z);
  }

  findGlyphs() {
    const root = this.viewer.scene_tree.find(["rbm"]);
    const glyphs = [];
    for (const name of Object.keys(root.children || {})) {
      if (!name.startsWith(ANCHOR_PREFIX)) continue;
      const object = root.children[name].object;
      const size = this.naturalSize(object);
      if (size <= 0) continue;
      // the group's long lines: the geometry nodes of parts larger than the model
      const rays = [];
      const parts = root.children[name].children || {};
      for (const part of Object.keys(parts)) {
        const length = this.naturalSize(parts[part].object);
        if (length <= 2 * size) continue;
        parts[part].object.traverse((o) => {
          if (o.name === "geom") rays.push({ object: o, length });
        });
      }
      glyphs.push({ path: `/rbm/${name}`, object, size, scale: 1, rays });
    }
    this.glyphs = glyphs;
    const frames = this.model.get("_frames") || {};
    this.triads = [];
    for (const path of Object.values(frames)) {
      if (glyphs.some((g) => path.startsWith(`${g.path}/`))) continue;
      const geom = this.node(`${path}/geom`);
      if (!geom) continue;
      const size = this.naturalSize(geom);
      if (size > 0) this.triads.push({ path, object: geom, size, scale: 1 });
    }
  }

  /** Magnify glyphs and triads that would be smaller than their minimum on screen. */
  keepVisible() {
    if (this.glyphs === null) this.findGlyphs();
    let changed = false;
    const resize = (item, pixels) => {
      const position = item.object.getWorldPosition(new this.THREE.Vector3());
      const scale = Math.max(1, pixels / (item.size * this.pixelsPerMetre(position)));
      if (Math.abs(scale - item.scale) > 1e-3 * item.scale) {
        item.scale = scale;
        item.object.scale.setScalar(scale);
        changed = true;
      }
    };
    for (const glyph of this.glyphs) {
      resize(glyph, GLYPH_PX);
      const ppm = this.pixelsPerMetre(glyph.object.getWorldPosition(new this.THREE.Vector3()));
      for (const ray of glyph.rays) {
        const wanted = Math.max(ray.length, RAY_PX / ppm) / (glyph.scale * ray.length);
        if (Math.abs(ray.object.scale.x - wanted) > 1e-3 * wanted) {
          ray.object.scale.setScalar(wanted);
          changed = true;
        }
      }
    }
    for (const triad of this.triads) resize(triad, TRIAD_PX);
    if (changed) this.viewer.set_dirty();
  }

  /** Screen radius (px) of the glyph or triad drawn at ``path``, 0 if none. */
  screenRadius(path) {
    const items = [...(this.glyphs || []), ...(this.triads || [])];
    const item = items.find((g) => path === g.path || path.startsWith(`${g.path}/`));
    if (!item) return 0;
    const position = item.object.getWorldPosition(new this.THREE.Vector3());
    return (item.scale * item.size * this.pixelsPerMetre(position)) / 2;
  }

  node(path) {
    let object = this.nodes.get(path);
    if (object === undefined) {
      object = this.viewer.scene_tree.find(path.split("/").filter((p) => p.length > 0)).object;
      this.nodes.set(path, object);
    }
    return object;
  }

  /** Times (seconds from the scene's origin) whose poses are shown: the playhead and pins. */
  shownTimes(t) {
    const pins = this.model.get("_pins") || {};
    return [t, ...Object.values(pins).map(Number)];
  }

  applyPoses(t) {
    const pins = this.model.get("_pins") || {};
    let coarse = 0;
    for (const track of this.store.tracks.values()) {
      const object = this.node(track.path);
      const at = Object.prototype.hasOwnProperty.call(pins, track.path) ? pins[track.path] : t;
      let samples = this.store.samplesAt(track, at);
      if (samples === null) {
        // its chunk has not arrived (a jump, a busy kernel): the coarse copy
        // until it does; the clock goes on
        samples = track.whole;
        coarse += 1;
        this.posesDirty = true;
      }
      const i = searchTime(samples.times, at + 1e-6, samples.hint);
      if (i < 0) {
        object.visible = false;
        continue;
      }
      samples.hint = i;
      const p = samples.translation;
      const q = samples.rotation;
      if (Number.isNaN(p[3 * i]) || Number.isNaN(q[4 * i])) {
        object.visible = false; // a missing sample: nothing to show there
        continue;
      }
      object.visible = true;
      object.position.set(p[3 * i], p[3 * i + 1], p[3 * i + 2]);
      object.quaternion.set(q[4 * i], q[4 * i + 1], q[4 * i + 2], q[4 * i + 3]);
      if (samples.scale) {
        object.scale.setScalar(samples.scale[i]);
      }
    }
    // what the last frame showed, for tests and benchmarks
    this.shown = { time: t, coarse };
    if (coarse) this.coarseFrames += 1;
    this.viewer.set_dirty();
  }

  // scene (z-up) coordinates -> the node the camera lives in (meshcat turns
  // its three.js scene to make z point up; OrbitControls work in that node)
  toCameraNode(point) {
    const parent = this.viewer.camera.parent;
    this.viewer.scene.updateMatrixWorld(true);
    const world = this.viewer.scene.localToWorld(new this.THREE.Vector3().fromArray(point));
    return parent ? parent.worldToLocal(world) : world;
  }

  applyCamera() {
    const cam = this.model.get("_camera");
    if (!cam || !cam.position) {
      return;
    }
    const viewer = this.viewer;
    viewer.camera.position.copy(this.toCameraNode(cam.position));
    viewer.controls.target.copy(this.toCameraNode(cam.target));
    viewer.controls.update();
    viewer.set_dirty();
  }

  worldPosition(path) {
    const object = this.node(path);
    object.updateWorldMatrix(true, false);
    return object.getWorldPosition(new this.THREE.Vector3());
  }

  follow() {
    const name = this.model.get("follow");
    const frames = this.model.get("_frames") || {};
    if (!name || !frames[name]) {
      this.followed = null;
      return;
    }
    const object = this.node(frames[name]);
    if (!object.visible) {
      return;
    }
    const viewer = this.viewer;
    const parent = viewer.camera.parent;
    const world = this.worldPosition(frames[name]);
    const target = parent ? parent.worldToLocal(world) : world;
    const delta = target.clone().sub(viewer.controls.target);
    if (this.followed !== name) {
      // starting to follow: come close enough to see the frame, same direction
      this.followed = name;
      const size = new this.THREE.Box3().setFromObject(object).getSize(new this.THREE.Vector3());
      const distance = Math.max(4 * size.length(), 1);
      const offset = viewer.camera.position.clone().sub(viewer.controls.target);
      if (offset.length() > distance) {
        offset.setLength(distance);
        viewer.camera.position.copy(viewer.controls.target).add(offset);
      }
    }
    if (delta.lengthSq() > 0) {
      viewer.controls.target.add(delta);
      viewer.camera.position.add(delta);
      viewer.controls.update();
      viewer.set_dirty();
    }
  }

  showTools() {
    const following = this.model.get("follow");
    const selected = this.model.get("selected");
    this.followButton.classList.toggle("rbm-on", Boolean(following));
    if (following) {
      this.followButton.textContent = `following ${following}`;
      this.followButton.title = "Stop following";
      this.followButton.disabled = false;
    } else {
      this.followButton.textContent = selected ? `follow ${selected}` : "follow";
      this.followButton.title = selected
        ? `Keep the camera on ${selected}`
        : "Click a frame in the view to select it, then follow it";
      this.followButton.disabled = !selected;
    }
  }

  showLegend() {
    const entries = this.model.get("_legend") || [];
    this.legend.replaceChildren(
      ...entries.map((entry) => {
        const row = document.createElement("div");
        const swatch = document.createElement("span");
        swatch.className = "rbm-swatch";
        const colors = Array.isArray(entry.color) ? entry.color : [entry.color];
        swatch.style.background =
          colors.length > 1
            ? `linear-gradient(90deg, ${colors.map(cssColor).join(", ")})`
            : cssColor(colors[0]);
        row.append(swatch, entry.text);
        return row;
      }),
    );
    this.legend.style.display = entries.length ? "" : "none";
  }

  showLabels() {
    const wanted = this.model.get("labels") ? this.model.get("_labels") || {} : {};
    for (const [path, div] of this.labels) {
      if (!(path in wanted)) {
        div.remove();
        this.labels.delete(path);
      }
    }
    const frames = this.model.get("_frames") || {};
    const selected = this.model.get("selected");
    const selectedPath = selected ? frames[selected] : null;
    for (const [path, text] of Object.entries(wanted)) {
      let div = this.labels.get(path);
      if (!div) {
        div = document.createElement("div");
        div.className = "rbm-label";
        this.overlay.appendChild(div);
        this.labels.set(path, div);
      }
      div.textContent = text;
      div.classList.toggle("rbm-selected", path === selectedPath);
      div.onclick = () => {
        const name = Object.keys(frames).find((n) => frames[n] === path);
        if (name && name !== this.model.get("selected")) {
          this.model.set("selected", name);
          this.model.save_changes();
        }
      };
    }
  }

  screenPosition(path) {
    const object = this.node(path);
    let visible = true;
    for (let o = object; o; o = o.parent) {
      if (!o.visible) {
        visible = false;
        break;
      }
    }
    if (!visible) {
      return null;
    }
    const v = this.worldPosition(path).project(this.viewer.camera);
    if (v.z > 1 || v.z < -1) {
      return null;
    }
    const w = this.pane.clientWidth;
    const h = this.pane.clientHeight;
    return [((v.x + 1) / 2) * w, ((1 - v.y) / 2) * h];
  }

  placeLabels() {
    for (const [path, div] of this.labels) {
      const xy = this.screenPosition(path);
      if (xy === null) {
        div.style.display = "none";
      } else {
        // beside the drawn glyph or triad, never over it
        const r = this.screenRadius(path);
        div.style.display = "";
        div.style.left = `${xy[0] + r}px`;
        div.style.top = `${xy[1] - r}px`;
      }
    }
  }

  /** Name of the frame drawn nearest to (x, y) in pixels, within 24 px. */
  pick(x, y) {
    const frames = this.model.get("_frames") || {};
    let best = null;
    let bestDistance = 24;
    for (const [name, path] of Object.entries(frames)) {
      const xy = this.screenPosition(path);
      if (xy === null) {
        continue;
      }
      // anywhere on a magnified model selects its frame
      const d = Math.hypot(xy[0] - x, xy[1] - y) - Math.max(0, this.screenRadius(path) - 24);
      if (d < bestDistance) {
        bestDistance = d;
        best = name;
      }
    }
    return best;
  }

  installPicking() {
    let down = null;
    this.pane.addEventListener("pointerdown", (event) => {
      down = [event.clientX, event.clientY];
    });
    this.pane.addEventListener("pointerup", (event) => {
      if (down === null || Math.hypot(event.clientX - down[0], event.clientY - down[1]) > 4) {
        down = null;
        return;
      }
      down = null;
      const box = this.pane.getBoundingClientRect();
      const name = this.pick(event.clientX - box.left, event.clientY - box.top);
      if (name !== null && name !== this.model.get("selected")) {
        this.model.set("selected", name);
        this.model.save_changes();
      }
    });
  }

  tick() {
    const t = this.currentTime();
    if (this.store.stream) {
      const speed = this.player && this.player.get("playing") ? Number(this.player.get("speed")) || 1 : 0;
      this.store.want(this.shownTimes(t), speed);
    }
    if (t !== this.lastTime || this.posesDirty) {
      this.lastTime = t;
      this.posesDirty = false;
      this.applyPoses(t);
    }
    this.follow();
    this.keepVisible();
    this.refiner.tick(performance.now());
    if (this.viewer.needs_render) {
      this.viewer.render();
      this.frames += 1;
    }
    if (this.labels.size) {
      this.placeLabels();
    }
  }

  dispose() {
    cancelAnimationFrame(this.handle);
    this.refiner.dispose();
    this.resize.disconnect();
    this.stopFollowing();
    this.store.views.delete(this);
    this.viewer.renderer.dispose();
    // three's dispose() keeps the context (and its drawing buffers) until
    // the canvas is garbage collected: release it now
    this.viewer.renderer.forceContextLoss();
    this.root.remove();
  }
}

/** The snapshot saved with the widget state (widget.py pack_snapshot), or null. */
function savedSnapshot(value) {
  if (!value || !value.byteLength) {
    return null;
  }
  const bytes = bytesOf(value);
  const data = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  let at = 4 + data.getUint32(0, true);
  const content = JSON.parse(new TextDecoder().decode(bytes.subarray(4, at)));
  const buffers = [];
  while (at < bytes.byteLength) {
    const n = data.getUint32(at, true);
    buffers.push(bytes.subarray(at + 4, at + 4 + n));
    at += 4 + n;
  }
  return { content, buffers };
}

function initialize({ model }) {
  const store = storeFor(model);
  store.model = model;
  const onMessage = (msg, buffers) => store.handle(msg, buffers || []);
  model.on("msg:custom", onMessage);
  // a page without a kernel (saved notebook, nbconvert HTML, docs) draws the
  // saved snapshot; a kernel's answer to "ready" below replaces it
  const saved = store.commands.length === 0 ? savedSnapshot(model.get("_saved")) : null;
  if (saved) {
    store.handle(saved.content, saved.buffers);
  }
  // ask the kernel for the content (also after a page reload)
  model.send({ type: "ready" });
  return () => {
    model.off("msg:custom", onMessage);
    STORES.delete(model.get("_uid")); // the model is gone: drop its content
  };
}

function render({ model, el }) {
  injectStyle();
  const store = storeFor(model);
  const view = new View(model, el, store);
  store.views.add(view);
  return () => view.dispose();
}

export default { initialize, render };
