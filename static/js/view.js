// The image: frames from the socket drawn on the canvas at the session's
// size (newest wins while one decodes; smaller progressive frames
// stretched over it), the canvas scaled to the render area, and the resolution
// that fits it.

import { ctx, el } from "./dom.js";
import { drawChart } from "./chart.js";
import { showMessage } from "./messages.js";
import { state } from "./state.js";

export async function drawFrames() {
  if (state.decoding) return;
  state.decoding = true;
  try {
    while (state.pendingFrame) {
      const frame = state.pendingFrame;
      state.pendingFrame = null;
      let bitmap;
      try {
        bitmap = await createImageBitmap(frame.blob);
      } catch (e) {
        showMessage(`could not decode a frame: ${e.message}`);
        continue;
      }
      // The canvas keeps the session's size; a smaller frame (progressive,
      // just after a change) is stretched over all of it.
      const w = state.want.width || bitmap.width;
      const h = state.want.height || bitmap.height;
      if (el.view.width !== w || el.view.height !== h) {
        el.view.width = w;
        el.view.height = h;
        fitCanvas();
      }
      ctx.imageSmoothingEnabled = bitmap.width !== w || bitmap.height !== h;
      ctx.drawImage(bitmap, 0, 0, w, h);
      bitmap.close();
      state.frames += 1;
      el.body.dataset.frames = String(state.frames);
      el.placeholder.hidden = true;
      state.displayed = frame;
      markDisplayed(frame);
    }
  } finally {
    state.decoding = false;
  }
}

/** The spp, generation, format, preview factor (empty: none) and whether
 *  it is denoised, of the image on the canvas, for tests and scripts. */
export function markDisplayed(frame) {
  if (!frame.stats) return;
  el.body.dataset.frameSpp = String(frame.stats.spp);
  el.body.dataset.frameGeneration = String(frame.stats.generation);
  el.body.dataset.frameFormat = String(frame.stats.format);
  el.body.dataset.framePreview = frame.stats.preview == null ? "" : String(frame.stats.preview);
  el.body.dataset.frameDenoised = String(Boolean(frame.stats.denoised));
}

/** Shows the image as large as fits: whole device pixels per image pixel
 *  (crisp) when it fits at least once, smooth downscaling otherwise. */
export function fitCanvas() {
  const r = el.viewport.getBoundingClientRect();
  const dpr = window.devicePixelRatio || 1;
  const w = el.view.width;
  const h = el.view.height;
  if (w < 2 || r.width < 2) return;
  let k = Math.min((r.width * dpr) / w, (r.height * dpr) / h);
  if (k >= 1) {
    k = Math.floor(k);
    el.view.style.imageRendering = "pixelated";
  } else {
    el.view.style.imageRendering = "auto";
  }
  el.view.style.width = `${(w * k) / dpr}px`;
  el.view.style.height = `${(h * k) / dpr}px`;
}

new ResizeObserver(() => { fitCanvas(); drawChart(); }).observe(el.viewport);

/** The resolution that fills the render area at the chosen pixel size. */
export function fitResolution() {
  const r = el.viewport.getBoundingClientRect();
  const dpr = window.devicePixelRatio || 1;
  const px = Number(el.px.value) || 2;
  const w = Math.max(16, Math.min(4096, Math.floor((r.width * dpr) / px)));
  const h = Math.max(16, Math.min(4096, Math.floor((r.height * dpr) / px)));
  return [w, h];
}

export function updateSizeInputs() {
  if (document.activeElement !== el.width) el.width.value = state.want.width ?? "";
  if (document.activeElement !== el.height) el.height.value = state.want.height ?? "";
}
