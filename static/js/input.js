// Keys, mouse look, drag to look, the touch pad and the help overlay.

import { $, el } from "./dom.js";
import {
  look, moveCamera, moveLight, randomLightColor, resetCamera, scaleLight,
} from "./camera.js";
import { showMessage } from "./messages.js";
import { toggleRawView } from "./panels.js";
import { edit, setScene } from "./session.js";
import { THESIS_SCENES } from "./state.js";

function toggleHelp(show = el.help.hidden) {
  el.help.hidden = !show;
}

function togglePointerLock() {
  if (document.pointerLockElement === el.view) {
    document.exitPointerLock();
  } else {
    try {
      const p = el.view.requestPointerLock();
      if (p && p.catch) p.catch((e) => showMessage(`pointer lock: ${e.message}`, "info", 4000));
    } catch (e) {
      showMessage(`pointer lock: ${e.message}`, "info", 4000);
    }
  }
}

/** Runs the action of a key (KeyboardEvent.code); true when it was one. */
function keyAction(code, shift = false) {
  const k = shift ? 4 : 1;
  if (/^Key[WSADQERIKJLUOMNP]$/.test(code)) return edit(() => editAction(code, k));
  switch (code) {
    case "KeyX": togglePointerLock(); break;
    case "KeyH": toggleHelp(); break;
    case "KeyV": toggleRawView(); break;
    case "Digit1":
    case "Digit2":
      setScene(THESIS_SCENES[code]);
      break;
    default: return false;
  }
  return true;
}

/** The camera and light keys. */
function editAction(code, k) {
  switch (code) {
    case "KeyW": moveCamera(k, 0, 0); break;
    case "KeyS": moveCamera(-k, 0, 0); break;
    case "KeyA": moveCamera(0, -k, 0); break;
    case "KeyD": moveCamera(0, k, 0); break;
    case "KeyQ": moveCamera(0, 0, k); break;
    case "KeyE": moveCamera(0, 0, -k); break;
    case "KeyR": resetCamera(); break;
    case "KeyI": moveLight(k, 0, 0); break;
    case "KeyK": moveLight(-k, 0, 0); break;
    case "KeyJ": moveLight(0, -k, 0); break;
    case "KeyL": moveLight(0, k, 0); break;
    case "KeyU": moveLight(0, 0, k); break;
    case "KeyO": moveLight(0, 0, -k); break;
    case "KeyM": scaleLight(1.25); break;
    case "KeyN": scaleLight(1 / 1.25); break;
    case "KeyP": randomLightColor(); break;
    default: break;
  }
}

function typing(target) {
  return target instanceof HTMLElement && (target.isContentEditable || /^(INPUT|SELECT|TEXTAREA)$/.test(target.tagName));
}

window.addEventListener("keydown", (e) => {
  const dialogOpen = !el.tokenDialog.hidden || !el.curlDialog.hidden;
  if (e.key === "Escape") {
    if (!el.help.hidden) toggleHelp(false);
    else if (!el.curlDialog.hidden) el.curlDialog.hidden = true;
    else if (typing(e.target)) e.target.blur();
    return;
  }
  if (dialogOpen || typing(e.target) || e.ctrlKey || e.metaKey || e.altKey) return;
  if (e.key === "?") {
    toggleHelp();
    e.preventDefault();
    return;
  }
  if (!el.help.hidden && e.code !== "KeyH") return;
  // Digits by position too (shifted layouts), letters by position (WASD anywhere).
  let code = e.code;
  if (!code && /^[a-z0-9]$/i.test(e.key)) code = /\d/.test(e.key) ? `Digit${e.key}` : `Key${e.key.toUpperCase()}`;
  if (code === "Digit1" || code === "Digit2" || code === "KeyR" || code === "KeyX" || code === "KeyP" || code === "KeyH") {
    if (e.repeat) return; // one per press
  }
  if (keyAction(code, e.shiftKey)) e.preventDefault();
});

// Mouse look with pointer lock: the mouse turns the view like in a game.
document.addEventListener("mousemove", (e) => {
  if (document.pointerLockElement !== el.view) return;
  const [dx, dy] = [e.movementX, e.movementY];
  edit(() => look(dx * 0.15, -dy * 0.15));
});
document.addEventListener("pointerlockchange", () => {
  const locked = document.pointerLockElement === el.view;
  $("btn-look").setAttribute("aria-pressed", String(locked));
  el.viewport.classList.toggle("locked", locked);
});

// Drag to look (mouse or touch): the image follows the finger.
{
  let drag = null;
  el.view.addEventListener("pointerdown", (e) => {
    if (document.pointerLockElement === el.view) return;
    drag = { id: e.pointerId, x: e.clientX, y: e.clientY };
    el.view.setPointerCapture(e.pointerId);
    if (document.activeElement instanceof HTMLElement) document.activeElement.blur();
    e.preventDefault();
  });
  el.view.addEventListener("pointermove", (e) => {
    if (!drag || e.pointerId !== drag.id) return;
    const dx = e.clientX - drag.x;
    const dy = e.clientY - drag.y;
    drag.x = e.clientX;
    drag.y = e.clientY;
    if (dx || dy) edit(() => look(-dx * 0.2, dy * 0.2));
  });
  const end = (e) => { if (drag && e.pointerId === drag.id) drag = null; };
  el.view.addEventListener("pointerup", end);
  el.view.addEventListener("pointercancel", end);
}

// On-screen buttons: a press steps once, holding repeats.
for (const b of el.touchpad.querySelectorAll("button[data-key]")) {
  let timer = null;
  const stop = () => { clearTimeout(timer); clearInterval(timer); timer = null; };
  b.addEventListener("pointerdown", (e) => {
    e.preventDefault();
    stop();
    const code = b.dataset.key;
    keyAction(code);
    if (code === "KeyR" || code === "KeyP") return;
    timer = setTimeout(() => { timer = setInterval(() => keyAction(code), 60); }, 300);
  });
  b.addEventListener("pointerup", stop);
  b.addEventListener("pointerleave", stop);
  b.addEventListener("pointercancel", stop);
  b.addEventListener("contextmenu", (e) => e.preventDefault());
}

function setTouchpad(on) {
  el.touchpad.hidden = !on;
  $("btn-touch").setAttribute("aria-pressed", String(on));
}
$("btn-touch").addEventListener("click", () => setTouchpad(el.touchpad.hidden));
if (window.matchMedia && window.matchMedia("(pointer: coarse)").matches) setTouchpad(true);

$("btn-look").addEventListener("click", togglePointerLock);
$("btn-help").addEventListener("click", () => toggleHelp());
$("help-close").addEventListener("click", () => toggleHelp(false));
el.help.addEventListener("click", (e) => { if (e.target === el.help) toggleHelp(false); });
