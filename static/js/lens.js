// The lens panel: the camera's thin-lens aperture (radius, 0 = pinhole)
// and focus distance (empty: the look-at point's), sent with the camera's
// next update; the server names a refused value and its own comes back.

import { $, el } from "./dom.js";
import { cameraChanged } from "./camera.js";
import { showMessage } from "./messages.js";
import { edit } from "./session.js";
import { on, state } from "./state.js";

function fillLens() {
  const c = state.camera;
  el.cAperture.disabled = !c;
  el.cFocus.disabled = !c;
  if (!c) return;
  if (document.activeElement !== el.cAperture) el.cAperture.value = String(+(c.aperture ?? 0).toPrecision(4));
  if (document.activeElement !== el.cFocus) {
    el.cFocus.value = c.focus_distance == null ? "" : String(+c.focus_distance.toPrecision(6));
  }
}

el.cAperture.addEventListener("change", () => {
  const n = Number(el.cAperture.value || 0);
  if (!(Number.isFinite(n) && n >= 0)) {
    showMessage("camera.aperture: enter a number >= 0 (0 is a pinhole)");
    fillLens();
    return;
  }
  edit(() => {
    if (!state.camera) return;
    state.camera.aperture = n;
    cameraChanged();
  });
});

el.cFocus.addEventListener("change", () => {
  const v = el.cFocus.value.trim();
  const n = Number(v);
  if (v !== "" && !(Number.isFinite(n) && n > 0)) {
    showMessage("camera.focus_distance: enter a number > 0, or leave it empty for the look-at point");
    fillLens();
    return;
  }
  edit(() => {
    if (!state.camera) return;
    // Empty: no value of the page's own (the server keeps the last one).
    if (v !== "") state.camera.focus_distance = n;
    cameraChanged();
  });
});

$("lens").addEventListener("submit", (e) => e.preventDefault());
on("settings", fillLens);
