// The HUD over the image: state, spp, paths/s, error estimate, time, size
// and device of the latest status or stats; with adaptive sampling, spp is
// the mean, and the HUD adds the spread (least, median and most samples of
// a pixel) and, with an error target, the tiles that reached it. The stream
// row (from the socket's stats): format and size of the last frame, frames
// delivered per second, the link's rate and the last frame's delivery time
// (the last two once the page's acknowledgements reach the server). Where
// the session denoises, the image row says whether the frame shown is
// denoised or raw (V switches).

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
  const adaptive = !!(s.quality && s.quality.adaptive);
  // A preview (the view at 1/k resolution, before the first sample) says so.
  const spp = s.preview ? `${s.spp} (preview 1/${s.preview})` : String(s.spp);
  setHud("hud-spp", adaptive ? `${s.spp} (mean)` : spp, s.spp);
  showSpread(adaptive ? s : null);
  setHud("hud-sps", `${fmtRate(s.samples_per_sec)}`, s.samples_per_sec);
  setHud("hud-error", s.error_estimate == null ? "–" : `${(100 * s.error_estimate).toPrecision(3)} %`, s.error_estimate);
  setHud("hud-elapsed", fmtTime(s.elapsed_ms), s.elapsed_ms);
  setHud("hud-res", `${s.width} × ${s.height}`);
  showDevice(s);
  if (s.type === "stats") {
    showStream(s);
    showDenoised(s);
  }
}

/** Whether the frame shown is denoised, where the session denoises. */
function showDenoised(s) {
  const mode = s.quality && s.quality.denoise;
  const row = $("hud-denoise-row");
  row.hidden = !mode || mode === "off";
  if (row.hidden) return;
  setHud("hud-denoise", s.denoised ? "denoised (V: raw)" : "raw (V: denoised)", s.denoised ? "denoised" : "raw");
}

/** Where the session renders; a session on every device (`backend: all`)
 *  lists each device's rate instead of their long names. */
function showDevice(s) {
  const devices = s.devices || [];
  if (s.backend !== "all" || devices.length === 0) {
    setHud("hud-device", `${s.backend}: ${s.device}`, s.backend);
    return;
  }
  const each = devices.map((d) => `${d.backend} ${d.failure ? "dropped out" : fmtRate(d.samples_per_sec)}`);
  setHud("hud-device", `all: ${each.join(" · ")}`, s.backend);
  $("hud-device").title = devices.map((d) => `${d.backend}: ${d.device}${d.failure ? ` (${d.failure})` : ""}`).join("\n");
  $("hud-device").dataset.devices = String(devices.length);
}

/** The stream row; a field the stats lack (null) is left out. */
function showStream(s) {
  const row = $("hud-stream-row");
  row.hidden = s.format == null;
  if (row.hidden) return;
  const parts = [s.format];
  if (s.frame_bytes != null) parts.push(`${Math.max(1, Math.round(s.frame_bytes / 1024))} KB`);
  const more = [];
  if (s.delivered_fps != null) more.push(`${Math.round(s.delivered_fps)} fps`);
  if (s.link_mbps != null) more.push(`${s.link_mbps.toPrecision(3)} Mbit/s`);
  if (s.delivery_ms != null) more.push(`${Math.round(s.delivery_ms)} ms`);
  setHud("hud-stream", [parts.join(" "), ...more].join(" · "), s.format);
  const d = $("hud-stream").dataset;
  d.format = s.format;
  d.frameBytes = s.frame_bytes ?? "";
  d.frameWidth = s.frame_width ?? "";
  d.fps = s.delivered_fps ?? "";
  d.linkMbps = s.link_mbps ?? "";
  d.deliveryMs = s.delivery_ms ?? "";
}

/** The adaptive rows: the spread (hidden when `s` is null or from a server
 *  without it) and the tiles done (only with an error target). */
function showSpread(s) {
  const spread = s && s.spp_spread;
  $("hud-spread-row").hidden = !spread;
  if (spread) {
    setHud("hud-spread", `${spread.min} / ${spread.median} / ${spread.max}`, `${spread.min},${spread.median},${spread.max}`);
    Object.assign($("hud-spread").dataset, { min: spread.min, median: spread.median, max: spread.max });
  }
  const tiles = !!spread && s.quality.target_error != null && s.tiles > 0;
  $("hud-tiles-row").hidden = !tiles;
  if (tiles) setHud("hud-tiles", `${s.tiles_done} / ${s.tiles}`, s.tiles_done);
}

on("status", showStatus);
