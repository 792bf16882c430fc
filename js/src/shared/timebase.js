// One time base for every view (the browser twin of rbm_nb/widgets/_timebase.py):
// the recording's own time as seconds from its start, then the absolute time
// where the data has one, e.g. "12.345 s · 2020-02-02 00:27:26.345".
// tests/test_timebase.py runs these functions in node against the Python ones.

export const SEPARATOR = " \u00b7 ";

/** Seconds from the start with millisecond digits: "12.345 s". */
export function formatSeconds(t) {
  // toFixed rounds the exact binary value half away from zero, as the Python twin does
  return `${(t + 0).toFixed(3)} s`;
}

/** Absolute time t seconds after t0Ns (ns since the epoch), to the millisecond. */
export function formatAbsolute(t, t0Ns) {
  const ms = Math.floor(Number(t0Ns) / 1e6 + t * 1e3 + 0.5);
  const iso = new Date(ms).toISOString(); // 2020-02-02T00:27:26.345Z
  return iso.replace("T", " ").replace("Z", "");
}

/** The shared readout; t0Ns null/undefined for recordings in plain seconds. */
export function formatTime(t, t0Ns) {
  if (t === null || t === undefined || !Number.isFinite(t)) return "\u2014";
  let text = formatSeconds(t);
  if (t0Ns !== null && t0Ns !== undefined) text += SEPARATOR + formatAbsolute(t, t0Ns);
  return text;
}
