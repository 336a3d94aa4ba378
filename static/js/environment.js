// The environment panel: the light from outside the scene, a uniform
// colour, an HDR map (the server's built-in maps, the maps uploaded to
// it, or an .hdr/.exr file opened or dropped here and uploaded) or a
// computed sun & sky (with the sun's elevation and azimuth), with its
// intensity, rotation and visibility. Each change is one
// PUT /api/sessions/{id}/environment; the server names a refused value and
// its own settings come back. The HUD names the map.

import { api } from "./api.js";
import { $, el } from "./dom.js";
import { showMessage } from "./messages.js";
import { change, edit } from "./session.js";
import { on, state } from "./state.js";
import { uploadAsset } from "./upload.js";

export const MAP_FILE = /\.(hdr|exr)$/i;
const picker = $("env-file");
const OPEN = "open";
/** The menu's entry for a computed sky (no map id looks like it). */
const SKY = "sun & sky";
const DEFAULT_SKY = { sun_elevation_deg: 45, sun_azimuth_deg: 135 };

const hex = (v) => Math.round(Math.max(0, Math.min(1, v)) * 255).toString(16).padStart(2, "0");
const fmt = (n) => String(+n.toPrecision(4));

/** The status's environment as {map?, color, intensity, rotation_deg, visible}. */
function current() {
  const e = state.status?.environment;
  if (Array.isArray(e)) {
    const top = Math.max(...e);
    return { map: null, color: top > 0 ? e.map((c) => c / top) : [0, 0, 0], intensity: top, rotation_deg: 0, visible: true };
  }
  if (e && e.sky) {
    return { map: SKY, sky: e.sky, color: [0, 0, 0], intensity: e.intensity ?? 1, rotation_deg: e.rotation_deg ?? 0, visible: e.visible ?? true, background: e.background };
  }
  if (e && e.map) {
    return { map: e.map, color: [0, 0, 0], intensity: e.intensity ?? 1, rotation_deg: e.rotation_deg ?? 0, visible: e.visible ?? true, background: e.background };
  }
  return null;
}

/** Fills the map menu: none, sun & sky, the built-in maps, the uploaded ones. */
async function listMaps() {
  const options = [["", "none (colour)"], [SKY, "sun & sky"]];
  try {
    const builtin = await api("GET", "/environments");
    for (const m of builtin.maps || []) options.push([m.id, m.name]);
  } catch { /* an older server: no built-in maps */ }
  try {
    const assets = await api("GET", "/assets");
    for (const a of assets.assets || []) if (a.map_size) options.push([a.id, `${a.name} (uploaded)`]);
  } catch { /* none */ }
  const e = current();
  if (e?.map && !options.some(([id]) => id === e.map)) options.push([e.map, state.status?.environment_name || e.map.slice(0, 12)]);
  options.push([OPEN, "open .hdr / .exr…"]);
  el.eMap.replaceChildren(...options.map(([value, label]) => new Option(label, value)));
  fillEnvironment();
}

function fillEnvironment() {
  const e = current();
  const sunInputs = [el.eSunElevation, el.eSunAzimuth];
  for (const input of [el.eMap, el.eColor, el.eIntensity, el.eRotation, el.eVisible, ...sunInputs]) input.disabled = !e;
  if (!e) return;
  const withMap = e.map != null;
  el.eColor.disabled = withMap;
  el.eRotation.disabled = el.eVisible.disabled = !withMap;
  for (const input of sunInputs) input.disabled = !e.sky;
  const sunAngle = (v) => (v == null ? "" : fmt(v));
  if (document.activeElement !== el.eSunElevation) el.eSunElevation.value = sunAngle(e.sky?.sun_elevation_deg);
  if (document.activeElement !== el.eSunAzimuth) el.eSunAzimuth.value = sunAngle(e.sky?.sun_azimuth_deg);
  const focused = document.activeElement;
  if (focused !== el.eMap && [...el.eMap.options].some((o) => o.value === (e.map ?? ""))) el.eMap.value = e.map ?? "";
  if (focused !== el.eColor) el.eColor.value = `#${e.color.map(hex).join("")}`;
  if (focused !== el.eIntensity) el.eIntensity.value = fmt(e.intensity);
  if (focused !== el.eRotation) el.eRotation.value = fmt(e.rotation_deg);
  el.eVisible.checked = e.visible;
  const name = state.status?.environment_name;
  el.eName.textContent = withMap ? `${name ?? "map"}${e.visible ? "" : " (hidden behind the scene)"}` : "uniform colour";
  const row = $("hud-env-row");
  row.hidden = !withMap;
  if (withMap) {
    const hud = $("hud-env");
    hud.textContent = name ?? "map";
    hud.dataset.value = e.map;
  }
}

/** Sends `environment` (scene JSON's form); the server's answer wins. */
async function setEnvironment(environment) {
  if (!state.sessionId) return null;
  try {
    return await change("PUT", `/sessions/${state.sessionId}/environment`, environment);
  } catch (e) {
    showMessage(e.message);
    fillEnvironment();
    return null;
  }
}

/** The current settings with `changes`, as scene JSON. */
function withChanges(changes) {
  const e = { ...current(), ...changes };
  if (e.map == null) return e.color.map((c) => c * e.intensity);
  const out = e.map === SKY ? { sky: e.sky } : { map: e.map };
  Object.assign(out, { intensity: e.intensity, rotation_deg: e.rotation_deg, visible: e.visible });
  if (e.background) out.background = e.background;
  return out;
}

/** Uploads an .hdr or .exr file and lights the scene with it. */
export async function openEnvironment(file) {
  if (!MAP_FILE.test(file.name)) {
    showMessage(`${file.name}: not an environment map (.hdr or .exr)`);
    return null;
  }
  const asset = await uploadAsset(file);
  if (!asset) return null;
  const status = await setEnvironment(withChanges({ map: asset.id, intensity: 1, rotation_deg: 0, visible: true, background: undefined }));
  el.body.dataset.upload = status ? "done" : "failed";
  if (status) {
    const size = asset.map_size ? ` (${asset.map_size[0]}x${asset.map_size[1]})` : "";
    showMessage(`${file.name}${size}${(asset.warnings || []).length ? `: ${asset.warnings.join("; ")}` : ""}`, "info", 4000);
    await listMaps();
  }
  return status;
}

el.eMap.addEventListener("focus", listMaps);
el.eMap.addEventListener("change", () => {
  const v = el.eMap.value;
  if (v === OPEN) {
    fillEnvironment();
    picker.click();
    return;
  }
  if (v === SKY) return edit(() => setEnvironment(withChanges({ map: SKY, sky: { ...DEFAULT_SKY }, intensity: 1 })));
  edit(() => setEnvironment(v === "" ? withChanges({ map: null, intensity: 1, color: [1, 1, 1] }) : withChanges({ map: v, intensity: 1 })));
});
picker.addEventListener("change", () => {
  const file = picker.files[0];
  picker.value = "";
  if (file) openEnvironment(file);
});
el.eColor.addEventListener("change", () => {
  const v = el.eColor.value;
  const color = [1, 3, 5].map((i) => parseInt(v.slice(i, i + 2), 16) / 255);
  edit(() => setEnvironment(withChanges({ color })));
});
el.eIntensity.addEventListener("change", () => {
  const n = Number(el.eIntensity.value);
  if (!(el.eIntensity.value.trim() !== "" && Number.isFinite(n) && n >= 0)) {
    showMessage("environment.intensity: enter a number >= 0");
    return fillEnvironment();
  }
  edit(() => setEnvironment(withChanges({ intensity: n })));
});
el.eRotation.addEventListener("change", () => {
  const n = Number(el.eRotation.value);
  if (!(el.eRotation.value.trim() !== "" && Number.isFinite(n))) {
    showMessage("environment.rotation_deg: enter an angle in degrees");
    return fillEnvironment();
  }
  edit(() => setEnvironment(withChanges({ rotation_deg: n })));
});
el.eVisible.addEventListener("change", () => {
  const visible = el.eVisible.checked;
  edit(() => setEnvironment(withChanges({ visible })));
});
/** The sun placed by its angles (any other way of placing it dropped). */
function moveSun(input, field) {
  const n = Number(input.value);
  if (!(input.value.trim() !== "" && Number.isFinite(n))) {
    showMessage(`environment.sky.${field}: enter an angle in degrees`);
    return fillEnvironment();
  }
  const { sun_direction, time, latitude_deg, longitude_deg, ...sky } = current()?.sky ?? {};
  edit(() => setEnvironment(withChanges({ sky: { ...DEFAULT_SKY, ...sky, [field]: n } })));
}
el.eSunElevation.addEventListener("change", () => moveSun(el.eSunElevation, "sun_elevation_deg"));
el.eSunAzimuth.addEventListener("change", () => moveSun(el.eSunAzimuth, "sun_azimuth_deg"));
$("env").addEventListener("submit", (e) => e.preventDefault());

on("settings", fillEnvironment);
listMaps();
