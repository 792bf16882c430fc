// The one timeline of rbm_nb's widgets: how a view follows a Player.
//
// Contract (the Python side is rbm_nb/widgets/player.py, class Player):
//
// The Player is an anywidget whose model has these synced traits:
//   time      float   seconds from the start of the recording, 0 .. duration.
//                     While playing, the browser clock (requestAnimationFrame,
//                     in the Player's own JS) sets it locally every animation
//                     frame and pushes it to the kernel at most every
//                     THROTTLE_MS (and at once on pause and seek). The kernel
//                     sets it too (player.time = 3.0 in Python); the clock
//                     then continues from there.
//   playing   bool    whether the browser clock runs.
//   speed     float   playback speed relative to the recording.
//   loop      bool    start over at the end instead of stopping.
//   duration  float   seconds from the first to the last sample.
//   t0_ns     int or null   absolute time of second 0 in ns since the Unix
//                     epoch, or null when the data has no absolute time
//                     (JS numbers round it to ~0.3 us; use it for display).
//   origin    float   second 0 on the data's own float-seconds axis (epoch
//                     seconds for datetime data, the first float timestamp
//                     otherwise): data_seconds = origin + time.
//
// A linked view holds, in Python,
//     player = Instance(Player, allow_none=True).tag(sync=True, **widget_serialization)
// and in JS resolves it with `await model.widget_manager.get_model(id)` (the
// trait's value is "IPY_MODEL_<id>"), then listens to "change:time".
// followPlayer() below does both and follows the trait when it changes.
// To move every view to a time, call seek(player, t): it sets `time` locally
// (every view and the clock see it within the same frame) and sends it to
// the kernel.

export const THROTTLE_MS = 200;

/** The model id inside a widget reference ("IPY_MODEL_<id>" -> "<id>"). */
export function modelId(ref) {
  if (typeof ref !== "string" || ref.length === 0) {
    return null;
  }
  return ref.startsWith("IPY_MODEL_") ? ref.slice("IPY_MODEL_".length) : ref;
}

/** The Player model referenced by `model`'s trait `trait`, or null. */
export async function resolvePlayer(model, trait = "player") {
  const id = modelId(model.get(trait));
  if (id === null) {
    return null;
  }
  return await model.widget_manager.get_model(id);
}

/**
 * Call onTime(player, time) now and whenever the linked player's time changes.
 *
 * Follows changes of the `trait` (a view can be linked to another Player
 * later). onPlayer(player or null) is called when the player changes.
 * Returns a function that stops following.
 */
export function followPlayer(model, onTime, { trait = "player", onPlayer = null } = {}) {
  let current = null;
  let stopped = false;
  let generation = 0;
  const handler = () => onTime(current, current.get("time"));
  function detach() {
    if (current !== null) {
      current.off("change:time", handler);
      current = null;
    }
  }
  async function attach() {
    const mine = ++generation;
    let player = null;
    try {
      player = await resolvePlayer(model, trait);
    } catch (err) {
      console.error("rbm_nb: could not resolve the linked player", err);
    }
    if (stopped || mine !== generation) {
      return;
    }
    detach();
    current = player;
    if (onPlayer) {
      onPlayer(player);
    }
    if (player !== null) {
      player.on("change:time", handler);
      handler();
    }
  }
  const onTrait = () => attach();
  model.on(`change:${trait}`, onTrait);
  attach();
  return () => {
    stopped = true;
    model.off(`change:${trait}`, onTrait);
    detach();
  };
}

/** Clamp t to [0, duration] of the player. */
export function clampTime(player, t) {
  const duration = Number(player.get("duration")) || 0;
  return Math.min(Math.max(Number(t) || 0, 0), duration);
}

/** Move the player (and every view following it) to t seconds from the start. */
export function seek(player, t) {
  player.set("time", clampTime(player, t));
  player.save_changes();
}

/** Seconds on the data's own axis for player time t (origin + t). */
export function dataSeconds(player, t) {
  return Number(player.get("origin")) + t;
}

/**
 * "12.345 s", plus the absolute UTC time when t0_ns is known:
 * "12.345 s \u00b7 2020-02-02 00:27:26.345" (the same text as the Python readout).
 */
export function formatTime(t, t0_ns = null) {
  if (t === null || t === undefined || !Number.isFinite(t)) {
    return "\u2014";
  }
  const seconds = `${(t + 0).toFixed(3)} s`;
  if (t0_ns === null || t0_ns === undefined) {
    return seconds;
  }
  const ms = Math.floor(Number(t0_ns) / 1e6 + t * 1e3 + 0.5);
  const iso = new Date(ms).toISOString();
  return `${seconds} \u00b7 ${iso.replace("T", " ").replace("Z", "")}`;
}
