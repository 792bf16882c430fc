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
import { modelId } from "./timeline.js";

const NAMES = ["yaw", "pitch", "roll", "x", "y", "z"];
const CSS = `
.rbm-sliders { font: 13px sans-serif; padding: 4px 0; }
.rbm-sliders .rbm-row { display: flex; align-items: center; gap: 8px; margin: 2px 0; }
.rbm-sliders label { width: 70px; text-align: right; }
.rbm-sliders input[type=range] { width: 300px; }
.rbm-sliders .rbm-value { width: 70px; font-variant-numeric: tabular-nums; }
.rbm-sliders pre { margin: 6px 0 0 0; white-space: pre-wrap; font-size: 12px; }
`;

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
  return () => root.remove();
}

export default { render };
