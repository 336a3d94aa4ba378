// pathstream browser client: one render session, its frame stream and its
// controls. Plain ES modules, no build step, no dependencies. This entry
// wires the top bar and starts; the parts live in js/:
//
//   state.js     URL parameters, token, the page's state, events
//   dom.js       the page's elements
//   api.js       HTTP API calls (token prompt, error messages)
//   session.js   the session, its WebSocket, status, camera/light updates
//   view.js      frames on the canvas, fitting the render area
//   hud.js       the HUD;  chart.js  the error chart
//   samples.js   the samples overlay (where an adaptive render sampled)
//   camera.js    camera and light input (moves, turns, colours)
//   input.js     keys, mouse and touch
//   panels.js    quality, stream format and light panels;  export.js  downloads, curl
//   streamfmt.js the stream's format in auto (a pure decision)
//   models.js    model files: picked or dropped, uploaded, rendered
//   messages.js  the message bar and connection badge
//   vec.js, format.js  small helpers

import { api, authHeaders } from "./js/api.js";
import { $, el } from "./js/dom.js";
import "./js/environment.js";
import "./js/export.js";
import "./js/hud.js";
import "./js/input.js";
import "./js/lens.js";
import { showMessage } from "./js/messages.js";
import "./js/models.js";
import "./js/panels.js";
import "./js/samples.js";
import { connect, resize, setScene } from "./js/session.js";
import { intParam, state } from "./js/state.js";
import { fitResolution, updateSizeInputs } from "./js/view.js";
import { drawChart } from "./js/chart.js";

// ---------------------------------------------------------------- top bar

el.scene.addEventListener("change", () => {
  const w = state.want;
  if (el.scene.value === "custom" && w.sceneJson) setScene(w.sceneJson, w.sceneLabel);
  else setScene(el.scene.value);
  el.scene.blur(); // keys drive the view again
});
$("btn-resize").addEventListener("click", resize);
$("btn-fit").addEventListener("click", () => {
  const [w, h] = fitResolution();
  el.width.value = w;
  el.height.value = h;
  resize();
});
for (const input of [el.width, el.height]) {
  input.addEventListener("keydown", (e) => { if (e.key === "Enter") resize(); });
}

// Leaving the page frees its session on the server (it would expire anyway).
window.addEventListener("pagehide", () => {
  if (!state.sessionId) return;
  try {
    fetch(`/api/sessions/${state.sessionId}`, { method: "DELETE", headers: authHeaders(), keepalive: true });
  } catch { /* leaving anyway */ }
});

// ---------------------------------------------------------------- start

async function loadScenes() {
  let names = ["cornell", "cornell-glass", "cornell-quads", "smallpt", "furnace"];
  try {
    const j = await api("GET", "/scenes");
    if (Array.isArray(j.scenes) && j.scenes.length) names = j.scenes;
  } catch (e) {
    if (e.status !== 0) showMessage(`scene list: ${e.message}`);
  }
  el.scene.replaceChildren(...names.map((n) => {
    const o = document.createElement("option");
    o.value = n;
    o.textContent = n;
    return o;
  }));
  if (!names.includes(state.want.scene)) {
    const o = document.createElement("option");
    o.value = o.textContent = state.want.scene;
    el.scene.append(o);
  }
  el.scene.value = state.want.scene;
}

async function start() {
  const px = intParam("px");
  if (px && px <= 4) el.px.value = String(px);
  else el.px.value = (window.devicePixelRatio || 1) >= 2 ? "3" : "2";
  if (!state.want.width || !state.want.height) {
    const [w, h] = fitResolution();
    state.want.width = state.want.width || w;
    state.want.height = state.want.height || h;
  }
  updateSizeInputs();
  drawChart();
  await loadScenes();
  await connect();
}

start().catch((e) => showMessage(`start: ${e.message}`));
