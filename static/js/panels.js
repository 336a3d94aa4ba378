// The side panels: quality (a preset or each knob, sent over HTTP; the
// server's refusal shown and the server's value restored), the stream format
// (pinned, or chosen from the measured link: streamfmt.js; sent over the
// socket) and light (colour and intensity, sent with the camera and light
// updates).

import { api } from "./api.js";
import { $, el } from "./dom.js";
import { lightChanged } from "./camera.js";
import { showMessage } from "./messages.js";
import { change, edit, send } from "./session.js";
import { chooseFormat, streamSettings } from "./streamfmt.js";
import { on, state } from "./state.js";
import { same } from "./vec.js";

// Presets from GET /api/presets, loaded once a session answers (the token
// may be needed first).
let presets = null;
let presetsLoading = false;
const PRESET_KNOBS = ["max_depth", "rr_depth", "nee", "filter", "sampler", "clamp", "adaptive"];

export async function loadPresets() {
  if (presets || presetsLoading) return;
  presetsLoading = true;
  try {
    presets = (await api("GET", "/presets")).presets;
    const select = $("q-preset");
    for (const p of presets) {
      const option = document.createElement("option");
      option.value = p.name;
      option.textContent = p.name;
      option.title = p.description;
      select.appendChild(option);
    }
    fillQuality(state.status && state.status.quality);
  } catch (e) {
    showMessage(`presets: ${e.message}`);
  } finally {
    presetsLoading = false;
  }
}

/** The preset whose knobs `q` has, or "" (custom). A knob the server does
 *  not list for its presets is not compared. */
export function presetOf(q) {
  const p = (presets || []).find((p) => PRESET_KNOBS.every((k) => !(k in p.quality) || same(p.quality[k], q[k])));
  return p ? p.name : "";
}

$("q-preset").addEventListener("change", async () => {
  const name = $("q-preset").value;
  if (!name || !state.sessionId) return;
  try {
    await change("PATCH", `/sessions/${state.sessionId}/quality`, { preset: name });
  } catch (e) {
    showMessage(e.message);
    fillQuality(state.status && state.status.quality);
  }
});

function fillQuality(q) {
  if (!q) return;
  loadPresets();
  if (document.activeElement !== $("q-preset")) $("q-preset").value = presetOf(q);
  const set = (id, v) => {
    const input = $(id);
    if (document.activeElement === input) return;
    if (input.type === "checkbox") input.checked = !!v;
    else input.value = v == null ? "" : String(v);
  };
  set("q-max-depth", q.max_depth);
  set("q-rr-depth", q.rr_depth);
  set("q-nee", q.nee);
  set("q-adaptive", q.adaptive);
  $("q-adaptive").disabled = !("adaptive" in q); // a server without adaptive sampling
  set("q-filter", q.filter);
  set("q-sampler", q.sampler || "random");
  $("q-sampler").disabled = !("sampler" in q); // a server before Sobol sampling
  set("q-clamp", q.clamp);
  set("q-denoise", q.denoise || "off");
  $("q-denoise").disabled = !("denoise" in q); // a server without a denoiser's setting
  set("q-spp", q.spp);
  set("q-time", q.time_ms == null ? null : +(q.time_ms / 1000).toPrecision(6));
  set("q-target", q.target_error == null ? null : +(q.target_error * 100).toPrecision(6));
}

export function readQualityField(input) {
  const field = input.dataset.field;
  if (input.type === "checkbox") return [field, input.checked];
  if (input.tagName === "SELECT") return [field, input.value];
  const raw = input.value.trim();
  const halt = field === "spp" || field === "time_ms" || field === "target_error";
  if (raw === "") return halt ? [field, null] : [field, undefined];
  const n = Number(raw);
  if (!Number.isFinite(n)) return [field, undefined];
  switch (field) {
    case "time_ms": return [field, Math.max(1, Math.round(n * 1000))];
    case "target_error": return [field, n / 100];
    case "clamp": return [field, n];
    default: return [field, Math.round(n)];
  }
}

export async function qualityChanged(input) {
  const [field, value] = readQualityField(input);
  if (value === undefined) {
    showMessage(`quality.${field}: enter a number`);
    fillQuality(state.status && state.status.quality);
    return;
  }
  if (!state.sessionId) return;
  try {
    await change("PATCH", `/sessions/${state.sessionId}/quality`, { [field]: value });
  } catch (e) {
    showMessage(e.message);
    const active = document.activeElement;
    if (active === input) input.blur();
    fillQuality(state.status && state.status.quality);
  }
}

for (const input of document.querySelectorAll("#quality [data-field]")) {
  input.addEventListener("change", () => qualityChanged(input));
}
$("quality").addEventListener("submit", (e) => e.preventDefault());
$("light").addEventListener("submit", (e) => e.preventDefault());

// ---------------------------------------------------------------- stream format

function setStreamFormat(format) {
  const st = state.stream;
  st.format = format;
  st.lastSwitch = performance.now();
  el.body.dataset.streamFormat = format;
  // With the socket down, the next one opens with it (session.js).
  send({ stream: streamSettings(format, st.raw) });
}

/** Switches the stream between the denoised and the raw image (V): only
 *  how this page's frames are made, not the session. */
export function toggleRawView() {
  const st = state.stream;
  st.raw = !st.raw;
  send({ stream: streamSettings(st.format, st.raw) });
}

$("stream-format").addEventListener("change", () => {
  const choice = $("stream-format").value;
  state.stream.choice = choice;
  if (choice !== "auto") setStreamFormat(choice);
  $("stream-format").blur(); // keys drive the view again
});

on("status", (s, fromStream) => {
  if (!fromStream || s.type !== "stats" || s.format == null) return;
  const st = state.stream;
  // Only whole frames tell the stream's need; progressive ones are smaller.
  const whole = s.frame_width >= s.width;
  if (whole && s.format === "png") st.pngBytes = s.frame_bytes;
  // A frame sent before the last switch reached the server says nothing.
  if (st.choice !== "auto" || !whole || s.format !== st.format) return;
  const next = chooseFormat({
    current: st.format,
    linkMbps: s.link_mbps,
    frameBytes: s.frame_bytes,
    pngBytes: st.pngBytes,
    sinceSwitchMs: performance.now() - st.lastSwitch,
  });
  if (next !== st.format) setStreamFormat(next);
});

// ---------------------------------------------------------------- light

const hex = (v) => Math.round(Math.max(0, Math.min(1, v)) * 255).toString(16).padStart(2, "0");

function fillLight() {
  const l = state.light;
  const disabled = !l;
  el.lColor.disabled = disabled;
  el.lIntensity.disabled = disabled;
  if (!l) {
    el.lPosition.textContent = "this scene has no light";
    return;
  }
  const color = `#${l.color.map(hex).join("")}`;
  if (document.activeElement !== el.lColor) el.lColor.value = color;
  if (document.activeElement !== el.lIntensity) el.lIntensity.value = String(+l.intensity.toPrecision(4));
  el.lPosition.textContent = `at (${l.position.map((v) => v.toFixed(1)).join(", ")})`;
}

el.lColor.addEventListener("input", () => {
  if (!state.light) return;
  const v = el.lColor.value;
  const c = [1, 3, 5].map((i) => Number.parseInt(v.slice(i, i + 2), 16) / 255);
  const max = Math.max(...c);
  if (max === 0) {
    showMessage("light colour: pick a colour that is not black (use the intensity to dim it)", "info", 4000);
    return;
  }
  // The server keeps the colour with its largest component at 1.
  edit(() => {
    if (!state.light) return;
    state.light.color = c.map((x) => Math.round((x / max) * 1000) / 1000);
    lightChanged();
  });
});

el.lIntensity.addEventListener("change", () => {
  if (!state.light) return;
  const n = Number(el.lIntensity.value);
  if (!(Number.isFinite(n) && n >= 0)) {
    showMessage("light.intensity: enter a number >= 0");
    fillLight();
    return;
  }
  edit(() => {
    if (!state.light) return;
    state.light.intensity = n;
    lightChanged();
  });
});

on("settings", (s) => {
  fillQuality(s.quality);
  fillLight();
});
on("light", fillLight);
