// TimeSeries widget: stacked uPlot panels over one time axis.
//
// The kernel sends each panel's samples once, as binary buffers (x: float64
// seconds from the recording's start, y: float64 per component, NaN where there
// is no value or a time gap). When the time base changes afterwards (a Player
// linked later), the kernel sends only `x_shift`, added here to the x it sent. Everything interactive happens here: drag to
// zoom, wheel to zoom, shift+drag to pan, double-click to see everything,
// hover for the values, click to seek. The cursor follows the linked Player's
// `time` as the browser's clock moves it, so it keeps up while the kernel is
// busy; without a Player it follows this widget's own `time`.

import uPlot from "uplot";
import uPlotCss from "uplot/dist/uPlot.min.css" with { type: "text" };
import { followPlayer, formatTime, seek as seekPlayer } from "./timeline.js";

const CSS = `
.rbm-ts { font: 12px sans-serif; color: #222; }
.rbm-ts-head { display: flex; gap: 1em; align-items: baseline; margin: 2px 0 4px 4px; }
.rbm-ts-title { font-weight: bold; }
.rbm-ts-time { font-variant-numeric: tabular-nums; }
.rbm-ts-hint { color: #777; margin-left: auto; font-size: 11px; }
.rbm-ts-res { color: #555; font-size: 11px; }
.rbm-ts .u-legend { font-size: 11px; text-align: left; margin-left: 50px; }
.rbm-ts .u-legend .u-value { font-variant-numeric: tabular-nums; }
.rbm-ts-error { color: #a00; background: #fee; border: 1px solid #d99;
  padding: 2px 6px; margin: 2px 0 2px 50px; }
.rbm-ts-cursor { position: absolute; top: 0; bottom: 0; width: 0;
  border-left: 2px solid #d62728; pointer-events: none; }
`;

function injectCss() {
  if (document.getElementById("rbm-ts-css")) return;
  const style = document.createElement("style");
  style.id = "rbm-ts-css";
  style.textContent = uPlotCss + CSS;
  document.head.appendChild(style);
}

// A DataView (or ArrayBuffer) from the comm as a typed array (copied when misaligned).
function typed(view, Kind) {
  const { buffer, byteOffset, byteLength } = view instanceof ArrayBuffer ? new DataView(view) : view;
  if (byteOffset % Kind.BYTES_PER_ELEMENT === 0) {
    return new Kind(buffer, byteOffset, byteLength / Kind.BYTES_PER_ELEMENT);
  }
  return new Kind(buffer.slice(byteOffset, byteOffset + byteLength));
}

// A missing sample (NaN) becomes undefined, not null: uPlot collects the runs
// of nulls with \`gaps.push(...findGaps(...))\`, one argument per run, which
// overflows the call stack past ~125k runs (1.4 h of eye data) and leaves the
// panel empty. For undefined it collects nothing and asks the series' \`gaps\`
// option instead: gapSpans below, which makes the same clip without spreading.
function withMissing(values) {
  const out = new Array(values.length);
  for (let i = 0; i < values.length; i++) {
    out[i] = Number.isNaN(values[i]) ? undefined : values[i];
  }
  return out;
}

// The pixel spans [from, to] that uPlot clips out of a line: from the sample
// before each run of missing samples to the one after it (uPlot draws straight
// through undefined; the clip removes that bridge). Spans that touch are merged,
// so there are never more than about one per pixel column. A break narrower
// than MIN_GAP_PX cannot be seen at this zoom, and clipping it would erase the
// samples on both sides (at 1.5 h of eye data nearly every pixel column holds a
// short run of missing samples): those are left bridged until the user zooms in.
const MIN_GAP_PX = 2;

function gapSpans(u, sidx, idx0, idx1) {
  const xs = u.data[0];
  const ys = u.data[sidx];
  const last = xs.length - 1;
  const px = (v) => Math.round(u.valToPos(v, "x", true));
  const spans = [];
  for (let i = idx0; i <= idx1; i++) {
    if (ys[i] !== undefined) continue;
    const from = i;
    while (i < idx1 && ys[i + 1] === undefined) i++;
    const a = px(xs[Math.max(from - 1, 0)]);
    const b = px(xs[Math.min(i + 1, last)]);
    if (!(b - a >= MIN_GAP_PX)) continue;
    const prev = spans[spans.length - 1];
    if (prev && a <= prev[1]) prev[1] = Math.max(prev[1], b);
    else spans.push([a, b]);
  }
  return spans;
}

function formatValue(v, units) {
  if (v === null || v === undefined || Number.isNaN(v)) return "missing";
  const text = Math.abs(v) >= 1e4 || (Math.abs(v) < 1e-3 && v !== 0)
    ? v.toExponential(3) : v.toPrecision(4).replace(/(\.\d*?)0+$/, "$1").replace(/\.$/, "");
  return units ? `${text} ${units}` : text;
}

// "seconds since 2020-02-02 00:27:14.000": the absolute part of the shared readout
function axisLabel(t0Ns) {
  if (t0Ns === null || t0Ns === undefined) return "seconds since start";
  return `seconds since ${formatTime(0, t0Ns).split(" \u00b7 ")[1]}`;
}

// Robust y range of the samples shown: the 0.5th to 99.5th percentiles, with
// room for values up to half that span beyond them. A handful of impossible
// samples (a mis-detected pupil at 88 deg, a glitch of 4000 deg/s) no longer
// sets the scale, while saccade peaks and everything near the bulk stay in view.
const ROBUST_LOW = 0.005;
const ROBUST_HIGH = 0.995;
const ROBUST_ROOM = 0.5;
const ROBUST_SAMPLES = 20000;

function robustRange(u, dataMin, dataMax) {
  const [i0, i1] = u.series[0].idxs || [0, u.data[0].length - 1];
  const values = [];
  const step = Math.max(1, Math.floor(((i1 - i0 + 1) * (u.data.length - 1)) / ROBUST_SAMPLES));
  for (let k = 1; k < u.data.length; k++) {
    const ys = u.data[k];
    for (let i = i0; i <= i1; i += step) {
      const v = ys[i];
      if (v !== null && v !== undefined && Number.isFinite(v)) values.push(v);
    }
  }
  if (values.length < 2 || !(dataMax > dataMin)) {
    const mid = Number.isFinite(dataMin) ? dataMin : 0;
    return [mid - 1, mid + 1];
  }
  values.sort((a, b) => a - b);
  const at = (p) => values[Math.min(values.length - 1, Math.floor(p * (values.length - 1)))];
  const lo = at(ROBUST_LOW);
  const hi = at(ROBUST_HIGH);
  const room = ROBUST_ROOM * Math.max(hi - lo, 1e-9);
  const min = Math.max(dataMin, lo - room);
  const max = Math.min(dataMax, hi + room);
  const pad = 0.05 * Math.max(max - min, 1e-9);
  return [min - pad, max + pad];
}

// Listen on the window in the capture phase: JupyterLab's notebook handles a
// shift+mousedown as a cell selection and stops the mousemove/mouseup events
// that follow at the document, so listeners there never heard the pan.
function onDrag(move, up) {
  const done = (ev) => {
    window.removeEventListener("mousemove", move, true);
    window.removeEventListener("mouseup", done, true);
    up(ev);
  };
  window.addEventListener("mousemove", move, true);
  window.addEventListener("mouseup", done, true);
}

// a click seeks only once it is clear it is not the first half of a double-click
const DOUBLE_CLICK_MS = 300;

async function render({ model, el }) {
  injectCss();
  const root = document.createElement("div");
  root.className = "rbm-ts";
  const head = document.createElement("div");
  head.className = "rbm-ts-head";
  const title = document.createElement("span");
  title.className = "rbm-ts-title";
  title.textContent = model.get("title") || "";
  const readout = document.createElement("span");
  readout.className = "rbm-ts-time";
  const hint = document.createElement("span");
  hint.className = "rbm-ts-hint";
  hint.textContent =
    "drag/wheel: zoom \u00b7 shift+drag: pan \u00b7 double-click: all \u00b7 click or drag the red line: seek";
  // what the panels show: every sample, or a min/max overview at a pixel width
  const resolution = document.createElement("span");
  resolution.className = "rbm-ts-res";
  head.append(title, readout, resolution, hint);
  const body = document.createElement("div");
  root.append(head, body);
  el.appendChild(root);

  const t0Ns = () => model.get("t0_ns");
  let player = null;
  const currentTime = () => (player ? player.get("time") : model.get("time"));

  const panels = model.get("panels");
  const data = model.get("data");
  const charts = [];
  const cursors = [];
  let syncing = false;
  const syncKey = `rbm-ts-${Math.random().toString(36).slice(2)}`;

  function placeCursors() {
    const t = currentTime();
    readout.textContent = `t = ${formatTime(t, t0Ns())}`;
    charts.forEach((u, i) => {
      const x = u.valToPos(t, "x");
      const inside = Number.isFinite(x) && x >= 0 && x <= u.over.clientWidth;
      cursors[i].style.display = inside ? "block" : "none";
      if (inside) cursors[i].style.left = `${x - 1}px`;
    });
  }

  function seek(t) {
    if (player) {
      seekPlayer(player, t); // every view linked to the player follows at once
    } else {
      model.set("time", t);
      model.save_changes();
    }
    placeCursors();
  }

  // within a few pixels of the red line: a drag there scrubs instead of zooming
  function nearCursor(u, e) {
    const x = u.valToPos(currentTime(), "x");
    const rect = u.over.getBoundingClientRect();
    return Number.isFinite(x) && Math.abs(e.clientX - rect.left - x) <= 5;
  }

  function publishRange(u) {
    const { min, max } = u.scales.x;
    const old = model.get("x_range") || [];
    if (old.length === 2 && old[0] === min && old[1] === max) return;
    model.set("x_range", [min, max]);
    model.save_changes();
  }

  function setRangeEverywhere(min, max, source) {
    syncing = true;
    try {
      charts.forEach((u) => {
        if (u !== source) u.setScale("x", { min, max });
      });
    } finally {
      syncing = false;
    }
  }

  // x as sent (in the data's time base) and as shown (plus x_shift)
  const sentX = data.map((d) => typed(d.x, Float64Array));
  const shownX = (raw, shift) => {
    if (!shift) return raw;
    const out = new Float64Array(raw.length);
    for (let k = 0; k < raw.length; k++) out[k] = raw[k] + shift;
    return out;
  };
  let shift = model.get("x_shift") || 0;
  let dataMin = Infinity;
  let dataMax = -Infinity;
  function findExtent() {
    dataMin = Infinity;
    dataMax = -Infinity;
    sentX.forEach((x) => {
      if (x.length) {
        dataMin = Math.min(dataMin, x[0] + shift);
        dataMax = Math.max(dataMax, x[x.length - 1] + shift);
      }
    });
    if (!(dataMax > dataMin)) dataMax = dataMin + 1;
  }
  findExtent();

  // A panel that cannot draw says so in the widget, not only in the console.
  const errors = [];
  function reportFailure(i, err) {
    const text = `${panels[i].label}: this panel could not be drawn (${err && err.name ? `${err.name}: ${err.message}` : err})`;
    if (errors.includes(text)) return;
    errors.push(text);
    console.error(`rbm_nb TimeSeries: ${text}`, err);
    const note = document.createElement("div");
    note.className = "rbm-ts-error";
    note.textContent = text;
    body.insertBefore(note, body.firstChild);
  }
  const linearPaths = uPlot.paths.linear();
  const guardedPaths = (i) => (u, sidx, idx0, idx1) => {
    try {
      return linearPaths(u, sidx, idx0, idx1);
    } catch (err) {
      reportFailure(i, err);
      return null; // uPlot skips a series without paths; the others still draw
    }
  };

  // -- the exact readout: the time under the mouse (seconds of the axis), and
  // the kernel's answer for it once it arrives (see askExact below)
  let hoverT = null;
  let exactAnswer = null; // {t, samples: [{x, values}] per panel}
  let shownWindow = null; // the window of full-resolution rows spliced in, if any
  // the time under a chart's cursor (every synced panel agrees), null when
  // the mouse is away. uPlot fills the legend before its setCursor hook runs,
  // so the legend asks the chart, not the last hook's answer.
  function cursorTime(u) {
    const left = u.cursor.left;
    return left === null || left === undefined || left < 0 ? null : u.posToVal(left, "x");
  }
  // whether panel i's data here is not every sample at time t
  function approximate(i, t) {
    if (!panels[i].reduced || t === null) return false;
    if (!shownWindow || !shownWindow.full[i]) return true;
    const wx = shownWindow.x[i];
    // the window holds every row in [start, end] and one beyond each side:
    // the nearest sample of any time between its first and last row is here
    return !(wx.length && t >= wx[0] + shift && t <= wx[wx.length - 1] + shift);
  }
  // the kernel's answer for panel i at time t, if it has come
  function exactFor(i, t) {
    if (!exactAnswer || t === null || exactAnswer.t !== t || !approximate(i, t)) return null;
    return exactAnswer.samples[i];
  }
  let onCursor = () => {};
  // The hover dot of each line sits on the sample the readout shows: the
  // kernel's exact sample once it has come, else the one uPlot picked (a
  // kept sample of the overview). Out of sight (uPlot's own -10 px) where
  // that sample has no value.
  function hoverDot(i) {
    return (u, si) => {
      const size = u.cursor.points.size(u, si);
      const exact = exactFor(i, cursorTime(u));
      const idx = u.cursor.idxs ? u.cursor.idxs[si] : u.cursor.idx;
      let x = null;
      let y = null;
      if (exact) {
        x = exact.x;
        y = exact.values[si - 1];
      } else if (idx !== null && idx !== undefined) {
        x = u.data[0][idx];
        y = u.data[si][idx];
      }
      if (x === null || x === undefined || y === null || y === undefined || !Number.isFinite(y)) {
        return { left: -10 - size / 2, top: -10 - size / 2, width: size, height: size };
      }
      const left = u.valToPos(x, "x");
      const top = u.valToPos(y, u.series[si].scale);
      return { left: left - size / 2, top: top - size / 2, width: size, height: size };
    };
  }

  const width = () => Math.max(200, (body.clientWidth || el.clientWidth || 800) - 4);
  const height = model.get("panel_height");

  panels.forEach((panel, i) => {
    const x = shownX(sentX[i], shift);
    const ys = data[i].y.map((v) => withMissing(typed(v, Float64Array)));
    const last = i === panels.length - 1;
    // The readout (legend) shows the recording's own sample nearest the
    // cursor: from the data here where it is every sample, else the kernel's
    // answer; until that arrives, the kept sample marked "\u2248" (approximate).
    const series = [
      {
        label: "time",
        value: (u, v) => {
          if (v === null) return "\u2014";
          const t = cursorTime(u);
          const exact = exactFor(i, t);
          if (exact) return formatTime(exact.x, t0Ns());
          return (approximate(i, t) ? "\u2248 " : "") + formatTime(v, t0Ns());
        },
      },
      ...panel.components.map((name, k) => ({
        label: name,
        stroke: panel.colors[k],
        width: 1.25,
        spanGaps: false,
        gaps: gapSpans,
        paths: guardedPaths(i),
        // no cursor: a dash; a cursor on a sample with no value: "missing"
        value: (u, v, si, idx) => {
          if (idx === null || idx === undefined) return "\u2014";
          const t = cursorTime(u);
          const exact = exactFor(i, t);
          if (exact) return formatValue(exact.values[k], panel.units);
          return (approximate(i, t) ? "\u2248 " : "") + formatValue(v, panel.units);
        },
      })),
    ];
    let panStart = null;
    let downAt = null;
    let pendingSeek = null;
    let scrubbing = false;
    const opts = {
      width: width(),
      height: height + (last ? 40 : 0),
      scales: { x: { time: false }, y: { range: robustRange } },
      series,
      axes: [
        {
          size: last ? 40 : 8,
          label: last ? axisLabel(t0Ns()) : null,
          labelSize: 16,
          labelFont: "bold 11px sans-serif",
          font: "11px sans-serif",
          values: last ? (u, splits) => splits.map((v) => `${+v.toFixed(6)}`) : () => [],
        },
        {
          label: panel.units ? `${panel.label} (${panel.units})` : panel.label,
          size: 60,
          labelSize: 16,
          // small enough that "head speed (m/s)" fits beside a 120 px panel
          labelFont: "bold 11px sans-serif",
          font: "11px sans-serif",
        },
      ],
      cursor: {
        points: { bbox: hoverDot(i) },
        sync: { key: syncKey, filters: { pub: (type) => type === "mousemove" || type === "mouseleave" } },
        drag: { x: true, y: false, setScale: true, dist: 5 },
        bind: {
          mousedown: (u, targ, handler) => (e) => {
            if (e.button !== 0 || e.target !== targ) return;
            downAt = [e.clientX, e.clientY];
            if (nearCursor(u, e)) {
              // drag the red line: scrub the player (and every view it drives)
              scrubbing = true;
              e.stopPropagation();
              const move = (ev) => {
                const rect = u.over.getBoundingClientRect();
                seek(u.posToVal(Math.min(Math.max(ev.clientX - rect.left, 0), rect.width), "x"));
              };
              onDrag(move, () => {
                scrubbing = false;
                downAt = null;
              });
              return;
            }
            if (e.shiftKey) {
              // ours, not the notebook's (shift+click there selects cells)
              e.stopPropagation();
              e.preventDefault();
              const { min, max } = u.scales.x;
              panStart = { x: e.clientX, min, max, perPx: (max - min) / u.over.clientWidth };
              const move = (ev) => {
                ev.stopPropagation();
                const shift = (ev.clientX - panStart.x) * panStart.perPx;
                u.setScale("x", { min: panStart.min - shift, max: panStart.max - shift });
              };
              onDrag(move, (ev) => {
                ev.stopPropagation();
                panStart = null;
                downAt = null;
              });
              return;
            }
            handler(e);
          },
          mouseup: (u, targ, handler) => (e) => {
            if (e.button !== 0) return;
            if (downAt && !panStart && u.over.contains(e.target)) {
              const moved = Math.hypot(e.clientX - downAt[0], e.clientY - downAt[1]);
              if (moved < 4 && !e.shiftKey) {
                const rect = u.over.getBoundingClientRect();
                const t = u.posToVal(e.clientX - rect.left, "x");
                clearTimeout(pendingSeek);
                pendingSeek = null;
                // the second click of a double-click: no seek, the zoom resets
                if (e.detail < 2) {
                  pendingSeek = setTimeout(() => {
                    pendingSeek = null;
                    seek(t);
                  }, DOUBLE_CLICK_MS);
                }
              }
            }
            downAt = null;
            handler(e);
          },
          dblclick: (u, targ, handler) => (e) => {
            if (e.button !== 0 || e.target !== targ) return;
            clearTimeout(pendingSeek);
            pendingSeek = null;
            u.setScale("x", { min: dataMin, max: dataMax });
          },
        },
      },
      legend: { live: true },
      hooks: {
        setCursor: [(u) => onCursor(u)],
        setScale: [
          (u, key) => {
            if (key !== "x") return;
            placeCursors();
            if (syncing) return;
            setRangeEverywhere(u.scales.x.min, u.scales.x.max, u);
            publishRange(u);
          },
        ],
      },
    };
    let u;
    try {
      u = new uPlot(opts, [x, ...ys], body);
    } catch (err) {
      reportFailure(i, err);
      return;
    }
    u.rbmPanel = i;
    const cursor = document.createElement("div");
    cursor.className = "rbm-ts-cursor";
    u.over.appendChild(cursor);
    u.over.addEventListener("mousemove", (e) => {
      u.over.style.cursor = scrubbing || nearCursor(u, e) ? "ew-resize" : "";
    });
    u.over.addEventListener(
      "wheel",
      (e) => {
        e.preventDefault();
        const { min, max } = u.scales.x;
        const rect = u.over.getBoundingClientRect();
        const at = u.posToVal(e.clientX - rect.left, "x");
        const factor = e.deltaY < 0 ? 0.8 : 1.25;
        const lo = Math.max(dataMin - (dataMax - dataMin), at - (at - min) * factor);
        const hi = Math.min(dataMax + (dataMax - dataMin), at + (max - at) * factor);
        u.setScale("x", { min: lo, max: hi });
      },
      { passive: false },
    );
    charts.push(u);
    cursors.push(cursor);
  });

  // a range set from Python (or kept from an earlier view) wins over "everything"
  const initial = model.get("x_range");
  const first = charts[0];
  if (first) {
    if (initial && initial.length === 2) first.setScale("x", { min: initial[0], max: initial[1] });
    else first.setScale("x", { min: dataMin, max: dataMax });
  }

  const onRange = () => {
    const r = model.get("x_range");
    if (!first || !r || r.length !== 2) return;
    const { min, max } = first.scales.x;
    if (r[0] !== min || r[1] !== max) first.setScale("x", { min: r[0], max: r[1] });
  };
  model.on("change:x_range", onRange);

  // a new time base: shift the x already here (nothing is sent again); the
  // view keeps showing the same samples
  const onShift = () => {
    const next = model.get("x_shift") || 0;
    const delta = next - shift;
    if (!delta) return;
    shift = next;
    findExtent();
    const { min, max } = first ? first.scales.x : {};
    charts.forEach((u) => u.setData([shownX(sentX[u.rbmPanel], shift), ...overview[charts.indexOf(u)]], false));
    shownKey = "";
    if (first) first.setScale("x", { min: min + delta, max: max + delta });
  };
  model.on("change:x_shift", onShift);

  const onTime = () => placeCursors();
  model.on("change:time", onTime);
  model.on("change:t0_ns", onTime);

  // -- detail on zoom: the kernel sent an envelope (max_points); a zoom asks it
  // for the samples in view, at full resolution when they are few enough.
  // Answers are kept (a few ranges); an answer to a superseded request is dropped.
  const detail = model.get("detail");
  const overview = charts.map((u) => u.data.slice(1));
  const viewId = Math.random().toString(36).slice(2);
  // the plot area's width in device pixels: one M4 column each
  const plotWidth = () => (first ? Math.max(10, Math.round(first.bbox.width)) : 0);
  let overviewWidth = model.get("overview_width");
  let askedOverview = 0;
  let windowFull = null; // per panel: every sample in view (a window shown)
  const samples = panels.reduce((n, p) => n + (p.samples || 0), 0);
  function describe() {
    if (!detail) {
      resolution.textContent = "every sample";
    } else if (windowFull && windowFull.every(Boolean)) {
      resolution.textContent = "zoomed: every sample in view";
    } else {
      // (no promise of detail on zoom: an exported page has no kernel to ask)
      resolution.textContent = `${samples.toLocaleString("en-US")} samples shown as min/max per pixel column (${overviewWidth} columns)`;
    }
    root.rbmResolution = resolution.textContent;
  }
  describe();
  const cache = new Map();
  const CACHED_WINDOWS = 8;
  const WINDOW_DELAY_MS = 60;
  let latest = 0;
  let askTimer = null;
  let applying = false;
  let shownKey = "";

  // x of the window's rows are in the data's time base, as the overview's
  function splice(u, w) {
    // the overview outside the window, the window's own rows inside it
    const p = u.rbmPanel;
    const ox = shownX(sentX[p], shift);
    const ys = overview[charts.indexOf(u)];
    const wx = w.x[p];
    const count = wx.length;
    if (!count) return [ox, ...ys];
    const lo = wx[0] + shift;
    const hi = wx[count - 1] + shift;
    let a = 0;
    while (a < ox.length && ox[a] < lo) a++;
    let b = a;
    while (b < ox.length && ox[b] <= hi) b++;
    const x = new Float64Array(a + count + (ox.length - b));
    x.set(ox.subarray(0, a), 0);
    for (let k = 0; k < count; k++) x[a + k] = wx[k] + shift;
    x.set(ox.subarray(b), a + count);
    return [x, ...ys.map((oy, c) => oy.slice(0, a).concat(w.y[p][c], oy.slice(b)))];
  }

  function showWindow(key, w) {
    shownKey = key;
    applying = true;
    syncing = true; // the range stays; only the rows in it change
    try {
      charts.forEach((u) => {
        const { min, max } = u.scales.x;
        u.setData(w ? splice(u, w) : [shownX(sentX[u.rbmPanel], shift), ...overview[charts.indexOf(u)]], false);
        u.setScale("x", { min, max }); // uPlot redraws on a scale change, not on setData(_, false)
      });
    } finally {
      applying = false;
      syncing = false;
    }
    root.rbmWindow = w ? { start: w.start, end: w.end, rows: w.rows, full: w.full } : null;
    shownWindow = w;
    windowFull = w ? w.full : null;
    describe();
  }

  // an overview at this view's own width replaces the one sent with the widget
  function takeOverview(w) {
    charts.forEach((u, c) => {
      const p = u.rbmPanel;
      sentX[p] = w.x[p];
      overview[c] = w.y[p];
    });
    overviewWidth = w.width;
    findExtent();
    shownKey = "";
  }

  function askWindow() {
    if (!detail || !first) return;
    const { min, max } = first.scales.x;
    const width = plotWidth();
    const key = `${min}:${max}:${shift}:${width}`;
    if (key === shownKey) return;
    if (min <= dataMin && max >= dataMax) {
      if (width !== overviewWidth && askedOverview !== width) {
        askedOverview = width; // once per width: the kernel answers with `whole`
        latest += 1;
        model.send({ type: "window", id: latest, view: viewId, start: dataMin, end: dataMax, width, whole: true });
      }
      showWindow(key, null); // everything in view: the overview is the picture
      return;
    }
    if (cache.has(key)) {
      showWindow(key, cache.get(key));
      return;
    }
    latest += 1;
    model.send({ type: "window", id: latest, view: viewId, start: min, end: max, width });
  }

  // -- exact readout: when the mouse rests on a time where some panel here is
  // not every sample, ask the kernel for the recording's samples nearest that
  // time. The request carries only the time; the answers are kept (a few
  // hundred times); an answer to a superseded request is dropped.
  const exactCache = new Map();
  const CACHED_EXACT = 256;
  const EXACT_DELAY_MS = 30;
  let exactTimer = null;
  let exactId = 0;
  let exactAskedAt = 0;
  const exactView = `${viewId}:exact`;
  root.rbmExact = { asked: 0, answered: 0, cached: 0, latencyMs: [], shown: null };
  function showExact() {
    charts.forEach((u) => {
      if (u.cursor.idx === null || u.cursor.idx === undefined) return;
      // uPlot fills the legend and places the hover dots (hoverDot) only for
      // a series whose index under the cursor changed: forget them, and put
      // the cursor where it is
      u.cursor.idxs.fill(null);
      u.setCursor({ left: u.cursor.left, top: u.cursor.top }, false, false);
    });
    const readout = charts.map((u) => {
      const p = u.rbmPanel;
      const exact = exactFor(p, hoverT);
      return {
        panel: p,
        approximate: approximate(p, hoverT),
        exact: !!exact,
        x: exact ? exact.x : null,
        values: exact ? Array.from(exact.values) : null,
        legend: Array.from(u.root.querySelectorAll(".u-legend .u-value")).map((e) => e.textContent),
      };
    });
    root.rbmExact.shown = { t: hoverT, panels: readout };
  }
  function askExact() {
    exactTimer = null;
    if (hoverT === null) return;
    if (!charts.some((u) => approximate(u.rbmPanel, hoverT))) return;
    const key = `${hoverT}:${shift}`;
    if (exactCache.has(key)) {
      root.rbmExact.cached += 1;
      exactAnswer = exactCache.get(key);
      showExact();
      return;
    }
    exactId += 1;
    exactAskedAt = performance.now();
    root.rbmExact.asked += 1;
    model.send({ type: "exact", id: exactId, view: exactView, t: hoverT });
  }
  onCursor = (u) => {
    const t = cursorTime(u);
    if (t === hoverT) return; // the other panels follow the same cursor (sync)
    hoverT = t;
    clearTimeout(exactTimer);
    if (t !== null && detail) exactTimer = setTimeout(askExact, EXACT_DELAY_MS);
    root.rbmExact.shown = { t: hoverT, panels: null };
  };
  function takeExact(msg, buffers) {
    if (msg.id !== exactId) return; // the mouse has moved on
    const samples = panels.map((panel, p) => {
      const row = typed(buffers[p], Float64Array);
      return { x: row[0] + msg.shift, values: row.subarray(1) };
    });
    const answer = { t: msg.t, samples };
    exactCache.set(`${msg.t}:${msg.shift}`, answer);
    if (exactCache.size > CACHED_EXACT) exactCache.delete(exactCache.keys().next().value);
    root.rbmExact.answered += 1;
    root.rbmExact.latencyMs.push(performance.now() - exactAskedAt);
    if (msg.t !== hoverT || msg.shift !== shift) return;
    exactAnswer = answer;
    showExact();
  }

  const onMessage = (msg, buffers) => {
    if (msg && msg.type === "exact" && msg.view === exactView) {
      takeExact(msg, buffers);
      return;
    }
    if (!msg || msg.type !== "window" || msg.view !== viewId) return;
    if (msg.id !== latest) return; // superseded by a later zoom
    const w = { start: msg.start, end: msg.end, rows: msg.rows, full: msg.full, width: msg.width, x: [], y: [] };
    let at = 0;
    panels.forEach((panel, p) => {
      w.x.push(typed(buffers[at++], Float64Array));
      w.y.push(panel.components.map(() => withMissing(typed(buffers[at++], Float64Array))));
    });
    if (msg.whole) {
      if (msg.shift === shift) takeOverview(w);
      askWindow();
      return;
    }
    const key = `${msg.start}:${msg.end}:${shift}:${msg.width}`;
    cache.set(key, w);
    if (cache.size > CACHED_WINDOWS) cache.delete(cache.keys().next().value);
    showWindow(key, w);
  };
  model.on("msg:custom", onMessage);
  if (detail && first) {
    first.hooks.setScale.push((u, key) => {
      if (key !== "x" || applying) return;
      clearTimeout(askTimer);
      askTimer = setTimeout(askWindow, WINDOW_DELAY_MS);
    });
    askWindow();
  }

  const stopFollowing = followPlayer(model, () => placeCursors(), {
    onPlayer: (p) => {
      player = p;
      placeCursors();
    },
  });

  const resize = new ResizeObserver(() => {
    const w = width();
    let resized = false;
    charts.forEach((u) => {
      if (Math.abs(u.width - w) > 1) {
        u.setSize({ width: w, height: u.height });
        resized = true;
      }
    });
    placeCursors();
    if (resized && detail) {
      // a new width: an overview (and window) at it
      clearTimeout(askTimer);
      askTimer = setTimeout(askWindow, WINDOW_DELAY_MS);
    }
  });
  resize.observe(body);

  // for tests and debugging: the uPlot instances of this view
  root.rbmCharts = charts;
  root.rbmErrors = errors;

  return () => {
    resize.disconnect();
    model.off("change:x_range", onRange);
    model.off("change:x_shift", onShift);
    model.off("msg:custom", onMessage);
    clearTimeout(askTimer);
    clearTimeout(exactTimer);
    model.off("change:time", onTime);
    model.off("change:t0_ns", onTime);
    stopFollowing();
    charts.forEach((u) => u.destroy());
  };
}

export default { render };
