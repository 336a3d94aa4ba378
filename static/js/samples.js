// The samples overlay: where the render put its samples, drawn over the
// image. GET /api/sessions/{id}/samples.png has one pixel per tile (the
// status's tile_size square of pixels; dark blue fewest samples, yellow most, green done); it is stretched over
// the canvas, crisp and half transparent. It follows the frames as they
// arrive, but at most once per REFRESH_MS and one request at a time (the
// frames may come far faster than anyone can read the map).
//
// For tests and scripts, #samples carries data-loads (maps shown so far).

import { api } from "./api.js";
import { $, el } from "./dom.js";
import { showMessage } from "./messages.js";
import { on, state } from "./state.js";

const REFRESH_MS = 500;

const toggle = $("show-samples");
const box = $("samples-overlay");
const img = $("samples");

let inFlight = false;
let wanted = false; // a newer frame than the map shown
let lastRequest = -Infinity;
let timer = null;
let url = null; // object URL of the map shown
let loads = 0;

/** Puts the overlay on the canvas. The map covers whole tiles; where the
 *  image's last column or row of tiles is cut short, the map is drawn
 *  larger than the image and clipped, so that tiles line up with pixels. */
function place() {
  if (box.hidden) return;
  const v = el.view;
  box.style.left = `${v.offsetLeft}px`;
  box.style.top = `${v.offsetTop}px`;
  box.style.width = `${v.offsetWidth}px`;
  box.style.height = `${v.offsetHeight}px`;
  const s = state.status;
  const tile = s?.tile_size;
  const cols = img.naturalWidth;
  const rows = img.naturalHeight;
  const fits = tile && cols === Math.ceil(s.width / tile) && rows === Math.ceil(s.height / tile);
  img.style.width = fits ? `${(100 * cols * tile) / s.width}%` : "100%";
  img.style.height = fits ? `${(100 * rows * tile) / s.height}%` : "100%";
}

function pump() {
  if (!wanted || inFlight || timer || !toggle.checked || !state.sessionId) return;
  const wait = lastRequest + REFRESH_MS - performance.now();
  if (wait > 0) {
    timer = setTimeout(() => {
      timer = null;
      pump();
    }, wait);
    return;
  }
  refresh();
}

async function refresh() {
  inFlight = true;
  wanted = false;
  lastRequest = performance.now();
  const id = state.sessionId;
  try {
    const blob = await api("GET", `/sessions/${id}/samples.png`, undefined, { as: "blob" });
    if (!toggle.checked || id !== state.sessionId) return;
    const next = URL.createObjectURL(blob);
    // Decoded before it replaces the map shown: no flicker.
    const probe = new Image();
    probe.src = next;
    try {
      await probe.decode();
    } catch {
      URL.revokeObjectURL(next);
      throw new Error("the map is not an image");
    }
    if (!toggle.checked) {
      URL.revokeObjectURL(next);
      return;
    }
    img.src = next;
    await img.decode().catch(() => {});
    if (url) URL.revokeObjectURL(url);
    url = next;
    loads += 1;
    img.dataset.loads = String(loads);
    box.hidden = false;
    place();
  } catch (e) {
    // No answer: the connection badge says so, and the next frame retries.
    if (e.status !== 0 && toggle.checked) {
      showMessage(`samples overlay: ${e.message}`);
      show(false);
    }
  } finally {
    inFlight = false;
    pump();
  }
}

function show(yes) {
  toggle.checked = yes;
  if (yes) {
    wanted = true;
    pump();
    return;
  }
  box.hidden = true;
  wanted = false;
  clearTimeout(timer);
  timer = null;
  img.removeAttribute("src");
  if (url) URL.revokeObjectURL(url);
  url = null;
}

toggle.addEventListener("change", () => show(toggle.checked));

// Each frame comes with its stats: a newer map is there to fetch.
on("status", (s, fromStream) => {
  if (!fromStream || !toggle.checked) return;
  wanted = true;
  pump();
});

new ResizeObserver(place).observe(el.viewport);
new ResizeObserver(place).observe(el.view);
