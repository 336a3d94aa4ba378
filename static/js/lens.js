// The lens panel: the camera's thin-lens aperture (radius, 0 = pinhole) or
// f-number, its focus distance (empty: the look-at point's) and projection,
// sent with the camera's next update; the server names a refused value and
// its own comes back. A double-click on the image asks the server what
// surface is under the cursor and focuses on it.

import { $, el } from "./dom.js";
import { api } from "./api.js";
import { cameraChanged } from "./camera.js";
import { showMessage } from "./messages.js";
import { edit } from "./session.js";
import { on, state } from "./state.js";

const fmt = (n, digits) => String(+n.toPrecision(digits));

function fillLens() {
  const c = state.camera;
  for (const input of [el.cAperture, el.cFNumber, el.cFocus, el.cProjection]) input.disabled = !c;
  if (!c) return;
  const projection = c.projection ?? "perspective";
  // Only a perspective camera has a lens.
  el.cAperture.disabled = el.cFNumber.disabled = projection !== "perspective";
  const focused = document.activeElement;
  if (focused !== el.cAperture) el.cAperture.value = fmt(c.aperture ?? 0, 4);
  if (focused !== el.cFNumber) el.cFNumber.value = c.f_number == null ? "" : fmt(c.f_number, 3);
  if (focused !== el.cFocus) el.cFocus.value = c.focus_distance == null ? "" : fmt(c.focus_distance, 6);
  if (focused !== el.cProjection) el.cProjection.value = projection;
}

/** A number from `input` that `ok` accepts, else a message and the old value. */
function read(input, ok, message) {
  const v = input.value.trim();
  const n = Number(v);
  if (v !== "" && !(Number.isFinite(n) && ok(n))) {
    showMessage(message);
    fillLens();
    return undefined;
  }
  return v === "" ? null : n;
}

el.cAperture.addEventListener("change", () => {
  const n = read(el.cAperture, (x) => x >= 0, "camera.aperture: enter a number >= 0 (0 is a pinhole)");
  if (n === undefined) return;
  edit(() => {
    if (!state.camera) return;
    state.camera.aperture = n ?? 0;
    delete state.camera.f_number;
    cameraChanged();
  });
});

el.cFNumber.addEventListener("change", () => {
  const n = read(el.cFNumber, (x) => x > 0, "camera.f_number: enter a number > 0, or leave it empty");
  if (n === undefined) return;
  edit(() => {
    if (!state.camera) return;
    // Empty: back to the aperture the f-number gave (a pinhole).
    if (n === null) delete state.camera.f_number;
    else state.camera.f_number = n;
    state.camera.aperture = 0;
    cameraChanged();
  });
});

el.cFocus.addEventListener("change", () => {
  const n = read(el.cFocus, (x) => x > 0, "camera.focus_distance: enter a number > 0, or leave it empty for the look-at point");
  if (n === undefined) return;
  // Empty: no value of the page's own (the server keeps the last one).
  if (n !== null) setFocus(n);
});

el.cProjection.addEventListener("change", () => {
  const p = el.cProjection.value;
  edit(() => {
    if (!state.camera) return;
    state.camera.projection = p;
    // The server's default height (the perspective view's at the look-at
    // point) and no lens, as the new projection wants.
    delete state.camera.ortho_height;
    if (p !== "perspective") {
      state.camera.aperture = 0;
      delete state.camera.f_number;
    }
    cameraChanged();
  });
});

function setFocus(distance) {
  edit(() => {
    if (!state.camera) return;
    state.camera.focus_distance = distance;
    cameraChanged();
  });
}

/** Focuses on the surface under a point of the canvas (client pixels). */
export async function focusAt(clientX, clientY) {
  if (!state.sessionId || !state.camera) return;
  const r = el.view.getBoundingClientRect();
  if (!(r.width > 0 && r.height > 0)) return;
  const x = ((clientX - r.left) / r.width) * el.view.width;
  const y = ((clientY - r.top) / r.height) * el.view.height;
  const q = `x=${x.toFixed(2)}&y=${y.toFixed(2)}`;
  try {
    const p = await api("GET", `/sessions/${state.sessionId}/pick?${q}`);
    if (!p.hit) return showMessage("focus: nothing there (the ray leaves the scene)");
    if (p.focus_distance == null) return showMessage("focus: that point is behind the camera");
    setFocus(p.focus_distance);
    $("c-pick").textContent = `focused at ${fmt(p.focus_distance, 4)} (double-click to refocus)`;
  } catch (e) {
    showMessage(`focus: ${e.message}`);
  }
}

el.view.addEventListener("dblclick", (e) => {
  if (document.pointerLockElement === el.view) return;
  e.preventDefault();
  focusAt(e.clientX, e.clientY);
});

$("lens").addEventListener("submit", (e) => e.preventDefault());
on("settings", fillLens);
