// Sliders for the pose of one static frame (rbm_nb.widgets.FrameSliders).
//
// Synced traits (Python side: rbm_nb/widgets/teaching.py, class SliderPanel):
//   values  {yaw, pitch, roll (degrees), x, y, z (metres)}: set here on input
//   shown   which sliders to draw;  reach  translation range (+-reach m)
//   scene   the SceneWidget the frame is drawn in ("IPY_MODEL_<id>" or null)
//   node    the scene path of the frame's pose node, "" when the frame's pose
//           in the scene is not the sliders' pose (its parent is not the base)
//   point   [x, y, z] in the parent frame or null: printed in the frame's axes
//   report  what the kernel printed for the current pose
// Moving a slider turns the frame's node in every view of the scene and
// prints the point in the frame's axes at once, here in the browser: a page
// without a kernel (nbconvert HTML, the docs) still teaches. With a kernel,
// Python re-registers the frame and its `report` replaces the local one.
// The "grab" button puts three.js's transform gizmo on the frame in the 3D
// view (turn, then move, then off): dragging it sets the sliders.
import { makeTransformControls } from "three/examples/jsm/controls/TransformControls.js";
import { modelId } from "./timeline.js";

const NAMES = ["yaw", "pitch", "roll", "x", "y", "z"];
const CSS = `
.rbm-sliders { font: 13px sans-serif; padding: 4px 0; }
.rbm-sliders .rbm-row { display: flex; align-items: center; gap: 8px; margin: 2px 0; }
.rbm-sliders label { width: 70px; text-align: right; }
.rbm-sliders input[type=range] { width: 300px; }
.rbm-sliders .rbm-value { width: 70px; font-variant-numeric: tabular-nums; }
.rbm-sliders pre { margin: 6px 0 0 0; white-space: pre-wrap; font-size: 12px; }
.rbm-sliders button.rbm-grab { margin: 4px 0 0 78px; font: 12px sans-serif; }
`;

let TransformControls = null;

/** three's TransformControls on meshcat's three.js (loaded with the scene view). */
function gizmoClass() {
  if (TransformControls === null) {
    TransformControls = makeTransformControls(globalThis.MeshCat.THREE).TransformControls;
  }
  return TransformControls;
}

/** Yaw, pitch, roll (degrees) of a row-major rotation matrix, R = Rz Ry Rx. */
export function yawPitchRoll(R) {
  const d = 180 / Math.PI;
  const pitch = Math.asin(Math.max(-1, Math.min(1, -R[2][0])));
  if (Math.abs(R[2][0]) > 1 - 1e-9) {
    // gimbal lock: only yaw - roll (or yaw + roll) is defined; put it all in yaw
    return [Math.atan2(-R[0][1], R[1][1]) * d, pitch * d, 0];
  }
  return [Math.atan2(R[1][0], R[0][0]) * d, pitch * d, Math.atan2(R[2][1], R[2][2]) * d];
}

function injectStyle() {
  if (document.getElementById("rbm-sliders-style")) {
    return;
  }
  const style = document.createElement("style");
  style.id = "rbm-sliders-style";
  style.textContent = CSS;
  document.head.appendChild(style);
}

/** R = Rz(yaw) Ry(pitch) Rx(roll), row-major 3x3, from degrees. */
export function rotationMatrix(yaw, pitch, roll) {
  const r = Math.PI / 180;
  const [cy, sy] = [Math.cos(yaw * r), Math.sin(yaw * r)];
  const [cp, sp] = [Math.cos(pitch * r), Math.sin(pitch * r)];
  const [cr, sr] = [Math.cos(roll * r), Math.sin(roll * r)];
  return [
    [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
    [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
    [-sp, cp * sr, cp * cr],
  ];
}

/** The 4x4 pose as meshcat wants it: 16 numbers, column-major. */
export function columnMajor(R, t) {
  return [
    R[0][0], R[1][0], R[2][0], 0,
    R[0][1], R[1][1], R[2][1], 0,
    R[0][2], R[1][2], R[2][2], 0,
    t[0], t[1], t[2], 1,
  ]; // prettier-ignore
}

/** A point of the parent in the frame's axes: R^T (p - t). */
export function inFrame(R, t, p) {
  const d = [p[0] - t[0], p[1] - t[1], p[2] - t[2]];
  return [0, 1, 2].map((j) => R[0][j] * d[0] + R[1][j] * d[1] + R[2][j] * d[2]);
}

function fmt(v) {
  const x = Math.abs(v) < 5e-4 ? 0 : v;
  return x.toFixed(3);
}

async function sceneViews(model) {
  const id = modelId(model.get("scene"));
  if (id === null) {
    return [];
  }
  const scene = await model.widget_manager.get_model(id);
  const uid = scene.get("_uid");
  return [...document.querySelectorAll(".rbm-scene")]
    .map((el) => el.rbmView)
    .filter((view) => view && view.model.get("_uid") === uid);
}

function render({ model, el }) {
  injectStyle();
  const root = document.createElement("div");
  root.className = "rbm-sliders";
  const inputs = {};
  const shown = model.get("shown") || NAMES;
  const reach = Number(model.get("reach")) || 5;
  for (const name of NAMES) {
    if (!shown.includes(name)) {
      continue;
    }
    const angle = ["yaw", "pitch", "roll"].includes(name);
    const row = document.createElement("div");
    row.className = "rbm-row";
    const label = document.createElement("label");
    label.textContent = `${name} (${angle ? "°" : "m"})`;
    const input = document.createElement("input");
    input.type = "range";
    input.className = `rbm-slider-${name}`;
    input.min = String(angle ? -180 : -reach);
    input.max = String(angle ? 180 : reach);
    input.step = angle ? "1" : "0.05";
    const value = document.createElement("span");
    value.className = "rbm-value";
    label.htmlFor = input.id = `rbm-${name}-${Math.random().toString(36).slice(2)}`;
    row.append(label, input, value);
    root.appendChild(row);
    inputs[name] = { input, value };
  }
  const grab = document.createElement("button");
  grab.type = "button";
  grab.className = "rbm-grab";
  grab.title = "Turn or move the frame with a gizmo in the 3D view";
  root.appendChild(grab);
  const local = document.createElement("pre");
  local.className = "rbm-local";
  const report = document.createElement("pre");
  report.className = "rbm-report";
  root.append(local, report);
  el.appendChild(root);

  const current = () => ({ ...(model.get("values") || {}) });

  function show(values) {
    for (const [name, { input, value }] of Object.entries(inputs)) {
      input.value = String(values[name] ?? 0);
      value.textContent = Number(values[name] ?? 0).toFixed(name.length > 1 ? 0 : 2);
    }
  }

  async function place(values, fromInput) {
    const R = rotationMatrix(values.yaw || 0, values.pitch || 0, values.roll || 0);
    const t = [values.x || 0, values.y || 0, values.z || 0];
    const point = model.get("point");
    if (point && fromInput) {
      const p = inFrame(R, t, point);
      local.textContent =
        `(${point.map(fmt).join(", ")}) in ${model.get("parent")} is ` +
        `(${p.map(fmt).join(", ")}) m in ${model.get("frame")}'s axes`;
    }
    const node = model.get("node");
    if (!node || !fromInput) {
      return; // the kernel's scene content already has this pose
    }
    const path = node.split("/").filter((p) => p.length > 0);
    for (const view of await sceneViews(model)) {
      view.viewer.set_transform(path, columnMajor(R, t));
      view.viewer.set_dirty();
    }
  }

  function changed(values) {
    show(values);
    place(values, true);
    model.set("values", values);
    model.save_changes();
  }

  // -- the gizmo: one TransformControls per view of the scene
  const MODES = [null, "rotate", "translate"];
  let mode = 0;
  let gizmos = [];
  let frameLoop = 0;

  function nodeOf(view) {
    const path = (model.get("node") || "").split("/").filter((p) => p.length > 0);
    return path.length ? view.viewer.scene_tree.find(path).object : null;
  }

  function fromNode(object) {
    const e = object.matrix.elements; // column-major
    const R = [
      [e[0], e[4], e[8]],
      [e[1], e[5], e[9]],
      [e[2], e[6], e[10]],
    ];
    const [yaw, pitch, roll] = yawPitchRoll(R);
    const round = (v, step) => Math.round(v / step) * step;
    return {
      yaw: round(yaw, 0.1), pitch: round(pitch, 0.1), roll: round(roll, 0.1),
      x: round(e[12], 0.001), y: round(e[13], 0.001), z: round(e[14], 0.001),
    }; // prettier-ignore
  }

  function dropGizmos() {
    cancelAnimationFrame(frameLoop);
    for (const { view, controls } of gizmos) {
      controls.detach();
      view.viewer.scene.remove(controls);
      controls.dispose();
      view.viewer.controls.enabled = true;
      view.viewer.set_dirty();
    }
    gizmos = [];
  }

  async function showGizmos() {
    dropGizmos();
    if (MODES[mode] === null) {
      return;
    }
    const Gizmo = gizmoClass();
    for (const view of await sceneViews(model)) {
      const object = nodeOf(view);
      if (!object) {
        continue;
      }
      const controls = new Gizmo(view.viewer.camera, view.viewer.renderer.domElement);
      controls.setMode(MODES[mode]);
      controls.setSpace("local");
      controls.attach(object);
      // meshcat turns its Scene by -90 deg about x (three is y-up); the gizmo
      // places its handles in world coordinates, so undo the turn for it
      controls.quaternion.copy(view.viewer.scene.quaternion).invert();
      view.viewer.scene.add(controls);
      controls.addEventListener("dragging-changed", (event) => {
        view.viewer.controls.enabled = !event.value; // no orbiting while dragging
      });
      controls.addEventListener("change", () => view.viewer.set_dirty());
      controls.addEventListener("objectChange", () => {
        object.updateMatrix();
        changed({ ...current(), ...fromNode(object) });
      });
      gizmos.push({ view, controls });
    }
    // the kernel redraws the frame under the same path: follow the new node
    const follow = () => {
      for (const gizmo of gizmos) {
        const object = nodeOf(gizmo.view);
        if (object && gizmo.controls.object !== object && !gizmo.controls.dragging) {
          gizmo.controls.attach(object);
        }
      }
      frameLoop = requestAnimationFrame(follow);
    };
    frameLoop = requestAnimationFrame(follow);
  }

  function showMode() {
    grab.textContent = ["grab in 3D: off", "grab in 3D: turn", "grab in 3D: move"][mode];
  }
  grab.addEventListener("click", () => {
    mode = (mode + 1) % MODES.length;
    showMode();
    showGizmos();
  });
  grab.style.display = model.get("node") ? "" : "none";
  model.on("change:node", () => {
    grab.style.display = model.get("node") ? "" : "none";
  });
  showMode();
  // for tests and the curious: the gizmos of this panel
  root.rbmGizmos = () => gizmos.map((g) => g.controls);

  for (const [name, { input }] of Object.entries(inputs)) {
    input.addEventListener("input", () => {
      const values = current();
      values[name] = Number(input.value);
      show(values);
      place(values, true);
      // the kernel's printout is for the old pose until it answers (never, on
      // a page without a kernel)
      report.style.opacity = "0.45";
      model.set("values", values);
      model.save_changes();
    });
  }
  const showReport = () => {
    report.textContent = model.get("report") || "";
    report.style.opacity = "1";
  };
  model.on("change:values", () => show(current()));
  model.on("change:report", showReport);
  show(current());
  showReport();
  return () => {
    dropGizmos();
    root.remove();
  };
}

export default { render };
