// The Player widget: transport controls whose clock runs in the browser.
// See timeline.js for the contract other views rely on.
import { clampTime, formatTime, seek } from "./timeline.js";
import { Clock } from "./lib/clock.js";

const SPEEDS = [0.1, 0.25, 0.5, 1, 2, 4, 8];

const CSS = `
.rbm-player { display: flex; flex-wrap: wrap; align-items: center; gap: 4px;
  font: 13px sans-serif; padding: 4px 2px; outline: none; }
.rbm-player:focus-visible { box-shadow: 0 0 0 2px #4a90d9; border-radius: 3px; }
.rbm-player button { min-width: 34px; height: 28px; cursor: pointer; border: 1px solid #bbb;
  background: #f4f4f4; border-radius: 3px; padding: 0 6px; }
.rbm-player button:hover { background: #e6e6e6; }
.rbm-player .rbm-play { min-width: 44px; font-weight: bold; }
.rbm-player input[type=range] { flex: 1 1 200px; min-width: 120px; }
.rbm-player .rbm-readout { font-variant-numeric: tabular-nums; min-width: 15em; white-space: pre; }
.rbm-player .rbm-error { color: #b00; flex-basis: 100%; }
`;

function injectStyle() {
  if (document.getElementById("rbm-player-style")) {
    return;
  }
  const style = document.createElement("style");
  style.id = "rbm-player-style";
  style.textContent = CSS;
  document.head.appendChild(style);
}

function button(text, title, cls) {
  const b = document.createElement("button");
  b.type = "button";
  b.textContent = text;
  b.title = title;
  if (cls) {
    b.className = cls;
  }
  return b;
}

// one clock per model, shared by every view of it
const CLOCKS = new Map();

function skipBy(model, seconds) {
  const duration = Number(model.get("duration")) || 0;
  let t = Number(model.get("time")) + seconds;
  if (model.get("loop") && duration > 0 && (t < 0 || t > duration)) {
    t = ((t % duration) + duration) % duration;
  }
  seek(model, clampTime(model, t));
}

function initialize({ model }) {
  const key = model.get("_uid");
  const clock = new Clock(model);
  CLOCKS.set(key, clock);
  return () => {
    clock.dispose();
    CLOCKS.delete(key);
  };
}

function render({ model, el }) {
  injectStyle();
  const root = document.createElement("div");
  root.className = "rbm-player";
  root.tabIndex = 0;
  root.setAttribute("role", "group");
  root.setAttribute("aria-label", "rbm_nb player (space: play/pause, arrows: skip, shift+arrows: big skip)");
  const back10 = button("", "", "rbm-big-back");
  const back1 = button("", "", "rbm-back");
  const play = button("\u25b6", "Play / pause (space)", "rbm-play");
  const fwd1 = button("", "", "rbm-fwd");
  const fwd10 = button("", "", "rbm-big-fwd");
  const slider = document.createElement("input");
  slider.type = "range";
  slider.min = "0";
  slider.step = "any";
  slider.className = "rbm-slider";
  slider.title = "Time";
  const readout = document.createElement("span");
  readout.className = "rbm-readout";
  const speed = document.createElement("select");
  speed.className = "rbm-speed";
  speed.title = "Playback speed";
  const loopLabel = document.createElement("label");
  const loop = document.createElement("input");
  loop.type = "checkbox";
  loop.className = "rbm-loop";
  loopLabel.append(loop, " loop");
  const error = document.createElement("div");
  error.className = "rbm-error";
  root.append(back10, back1, play, fwd1, fwd10, slider, readout, speed, loopLabel, error);
  el.appendChild(root);

  let dragging = false;
  function showTime() {
    const t = Number(model.get("time")) || 0;
    if (!dragging) {
      slider.value = String(t);
    }
    readout.textContent = formatTime(t, model.get("t0_ns"));
  }
  function showState() {
    const playing = Boolean(model.get("playing"));
    play.textContent = playing ? "\u275a\u275a" : "\u25b6";
    play.setAttribute("aria-pressed", String(playing));
    slider.max = String(Number(model.get("duration")) || 0);
    loop.checked = Boolean(model.get("loop"));
    const small = Number(model.get("skip"));
    const big = Number(model.get("big_skip"));
    back1.textContent = `\u2212${small}s`;
    fwd1.textContent = `+${small}s`;
    back10.textContent = `\u2212${big}s`;
    fwd10.textContent = `+${big}s`;
    back1.title = `Back ${small} s (\u2190)`;
    fwd1.title = `Forward ${small} s (\u2192)`;
    back10.title = `Back ${big} s (shift+\u2190)`;
    fwd10.title = `Forward ${big} s (shift+\u2192)`;
    const current = Number(model.get("speed"));
    const options = SPEEDS.includes(current) ? SPEEDS : [...SPEEDS, current].sort((a, b) => a - b);
    speed.replaceChildren(
      ...options.map((s) => {
        const o = document.createElement("option");
        o.value = String(s);
        o.textContent = `${s}\u00d7`;
        o.selected = s === current;
        return o;
      }),
    );
    error.textContent = model.get("error") || "";
    error.style.display = error.textContent ? "" : "none";
  }
  function toggle() {
    model.set("playing", !model.get("playing"));
    model.save_changes();
  }
  play.addEventListener("click", toggle);
  back1.addEventListener("click", () => skipBy(model, -Number(model.get("skip"))));
  fwd1.addEventListener("click", () => skipBy(model, Number(model.get("skip"))));
  back10.addEventListener("click", () => skipBy(model, -Number(model.get("big_skip"))));
  fwd10.addEventListener("click", () => skipBy(model, Number(model.get("big_skip"))));
  slider.addEventListener("input", () => {
    dragging = true;
    seek(model, Number(slider.value));
  });
  slider.addEventListener("change", () => {
    dragging = false;
  });
  speed.addEventListener("change", () => {
    model.set("speed", Number(speed.value));
    model.save_changes();
  });
  loop.addEventListener("change", () => {
    model.set("loop", loop.checked);
    model.save_changes();
  });
  root.addEventListener("keydown", (event) => {
    if (event.target instanceof HTMLSelectElement) {
      return;
    }
    const big = event.shiftKey ? Number(model.get("big_skip")) : Number(model.get("skip"));
    if (event.key === " " || event.code === "Space") {
      toggle();
    } else if (event.key === "ArrowRight") {
      skipBy(model, big);
    } else if (event.key === "ArrowLeft") {
      skipBy(model, -big);
    } else {
      return;
    }
    event.preventDefault();
    event.stopPropagation();
  });
  // clicking a control keeps the keyboard shortcuts on the player
  root.addEventListener("pointerdown", (event) => {
    if (!(event.target instanceof HTMLSelectElement)) {
      setTimeout(() => root.focus({ preventScroll: true }), 0);
    }
  });
  model.on("change:time", showTime);
  for (const name of ["playing", "duration", "loop", "speed", "skip", "big_skip", "error", "t0_ns"]) {
    model.on(`change:${name}`, showState);
  }
  showState();
  showTime();
  return () => {
    root.remove();
  };
}

export default { initialize, render };
