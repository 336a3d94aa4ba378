// The HUD over the image: state, spp, paths/s, error estimate, time, size
// and device of the latest status or stats.

import { $ } from "./dom.js";
import { fmtRate, fmtTime } from "./format.js";
import { on } from "./state.js";

function setHud(id, text, value) {
  const d = $(id);
  d.textContent = text;
  if (value !== undefined) d.dataset.value = value == null ? "" : String(value);
}

/** Shows a status or stats message. */
function showStatus(s) {
  setHud("hud-state", s.failure ? `failed: ${s.failure}` : s.state, s.state);
  setHud("hud-spp", String(s.spp), s.spp);
  setHud("hud-sps", `${fmtRate(s.samples_per_sec)}`, s.samples_per_sec);
  setHud("hud-error", s.error_estimate == null ? "–" : `${(100 * s.error_estimate).toPrecision(3)} %`, s.error_estimate);
  setHud("hud-elapsed", fmtTime(s.elapsed_ms), s.elapsed_ms);
  setHud("hud-res", `${s.width} × ${s.height}`);
  setHud("hud-device", `${s.backend}: ${s.device}`);
}

on("status", showStatus);
