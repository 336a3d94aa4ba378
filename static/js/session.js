// The session: opening it (again, with the same settings, when the server
// lost it), its WebSocket, the status it reports, and the changes this page
// sends (scene and size over HTTP; camera and light over the socket, at most
// once per animation frame).

import { api } from "./api.js";
import { el } from "./dom.js";
import { setConn, showMessage } from "./messages.js";
import { QUIET_MS, RETRY_MAX_MS, emit, state } from "./state.js";
import { streamQuery } from "./streamfmt.js";
import { clone, length, same } from "./vec.js";
import { drawFrames, markDisplayed, updateSizeInputs } from "./view.js";

export function applyScene(status) {
  state.camera = clone(status.camera);
  state.defaultCamera = clone(status.camera);
  state.light = status.light ? pickLight(status.light) : null;
  state.defaultLight = clone(state.light);
  // Step: 2% of the camera's distance from the origin (6 units in the
  // Cornell box), at least 0.05 (the unit-sphere furnace).
  state.moveStep = Math.max(0.05, 0.02 * length(status.camera.position));
  state.want.scene = status.scene;
  showScene(status.scene);
}

/** Shows the scene in the scene picker; an uploaded model ("custom") under
 *  its file name. */
export function showScene(name) {
  let option = [...el.scene.options].find((o) => o.value === name);
  if (!option) {
    option = document.createElement("option");
    option.value = name;
    el.scene.append(option);
  }
  if (name === "custom") option.textContent = state.want.sceneLabel || "custom";
  el.scene.value = name;
}

export function pickLight(l) {
  return { position: [...l.position], color: [...l.color], intensity: l.intensity };
}

/** Opens a session with what the page wants; restores camera and light when
 *  it replaces a lost one. */
export async function createSession({ restore = false } = {}) {
  const w = state.want;
  const body = { scene: w.scene === "custom" && w.sceneJson ? w.sceneJson : w.scene, width: w.width, height: w.height };
  if (w.quality) body.quality = w.quality;
  const camera = restore ? clone(state.camera) : null;
  const light = restore ? clone(state.light) : null;
  let status = await api("POST", "/sessions", body);
  state.sessionId = status.id;
  state.maxGeneration = 0;
  state.adoptFrom = 0;
  el.body.dataset.sessionId = status.id;
  const defaults = status;
  if (camera && !same(camera, status.camera)) {
    status = await api("PATCH", `/sessions/${status.id}/camera`, camera);
  }
  if (light && status.light && !same(light, pickLight(status.light))) {
    status = await api("PATCH", `/sessions/${status.id}/light`, light);
  }
  applyScene(defaults);
  state.camera = clone(status.camera);
  state.light = status.light ? pickLight(status.light) : null;
  state.cameraDirty = false;
  state.lightDirty = false;
  applyAnswer(status);
  updateSizeInputs();
  return status;
}

/** The session exists (made again when the server forgot it) and the socket is open. */
export async function connect() {
  if (state.connecting) return;
  state.connecting = true;
  clearTimeout(state.retryTimer);
  try {
    if (!state.sessionId) {
      await createSession();
    } else {
      try {
        const status = await api("GET", `/sessions/${state.sessionId}`);
        applyStatus(status);
      } catch (e) {
        if (e.status !== 404) throw e;
        const old = state.sessionId;
        await createSession({ restore: true });
        showMessage(`The server no longer had session ${old}; opened ${state.sessionId} with the same settings.`, "info", 6000);
      }
    }
    openSocket();
  } catch (e) {
    if (e.status === 0) {
      scheduleReconnect("server unreachable");
    } else {
      showMessage(e.message);
      scheduleReconnect("error");
    }
  } finally {
    state.connecting = false;
  }
}

export function scheduleReconnect(why) {
  clearTimeout(state.retryTimer);
  const delay = Math.min(RETRY_MAX_MS, 250 * 2 ** state.retry);
  state.retry += 1;
  setConn("reconnecting", `reconnecting (${why}, try ${state.retry})`);
  state.retryTimer = setTimeout(connect, delay);
}

export function openSocket() {
  closeSocket();
  const proto = location.protocol === "https:" ? "wss" : "ws";
  // Progressive: the first frames after a change come small (sooner), and
  // the format the page streams now (streamfmt.js) survives a reconnect.
  let q = streamQuery(state.stream.format, state.stream.raw);
  if (state.token) q += `&token=${encodeURIComponent(state.token)}`;
  const ws = new WebSocket(`${proto}://${location.host}/api/sessions/${state.sessionId}/ws?${q}`);
  ws.binaryType = "blob";
  state.ws = ws;
  setConn("connecting", "connecting");
  ws.onopen = () => {
    if (state.ws !== ws) return;
    state.retry = 0;
    setConn("live", "live");
    // Anything changed while the socket was down goes now.
    if (state.cameraDirty || state.lightDirty) requestFlush();
  };
  ws.onmessage = (event) => {
    if (state.ws !== ws) return;
    if (typeof event.data === "string") {
      let m;
      try { m = JSON.parse(event.data); } catch { return; }
      if (m.type === "stats") {
        // The stats describe the frame sent just before them.
        const f = state.lastReceived;
        if (f && !f.stats) {
          f.stats = { spp: m.spp, generation: m.generation, frame: m.frame, format: m.format, preview: m.preview, denoised: Boolean(m.denoised) };
          if (state.displayed === f) markDisplayed(f);
          // The image is here and handed to drawing: the server may send
          // the next (it then keeps one frame in flight and measures the
          // link). A server whose stats lack link_mbps refuses acks.
          if (m.frame != null && "link_mbps" in m) send({ ack: m.frame });
          countFrame(m);
        }
        applyStatus(m, true);
      }
      else if (m.type === "error") {
        // The change was refused: the server's settings stand.
        state.adoptFrom = state.maxGeneration;
        state.lastLocalEdit = 0;
        showMessage(m.error);
      }
    } else {
      const f = { blob: event.data, stats: null };
      state.lastReceived = f;
      state.pendingFrame = f;
      drawFrames();
    }
  };
  ws.onclose = (event) => {
    if (state.ws !== ws) return;
    state.ws = null;
    const why = event.code === 1001 ? "server going away" : "socket closed";
    scheduleReconnect(why);
  };
}

/** For tests and scripts: the last frame's width and how many frames came
 *  narrower than the session (progressive ones). */
function countFrame(m) {
  if (m.frame_width == null) return;
  el.body.dataset.frameWidth = String(m.frame_width);
  if (m.frame_width < m.width) {
    state.narrowFrames += 1;
    el.body.dataset.narrowFrames = String(state.narrowFrames);
  }
}

export function closeSocket() {
  const ws = state.ws;
  state.ws = null;
  if (ws) {
    ws.onclose = null;
    ws.onmessage = null;
    try { ws.close(); } catch { /* already closed */ }
  }
}

export function send(message) {
  if (state.ws && state.ws.readyState === WebSocket.OPEN) {
    state.ws.send(JSON.stringify(message));
    return true;
  }
  return false;
}

/** Opens a new session at the resolution in the inputs (the old one is deleted). */
export async function resize() {
  const w = Number.parseInt(el.width.value, 10);
  const h = Number.parseInt(el.height.value, 10);
  if (!(w > 0 && h > 0)) {
    showMessage("width and height must be positive whole numbers");
    return;
  }
  const old = state.sessionId;
  state.want.width = w;
  state.want.height = h;
  await replacing(async () => {
    try {
      closeSocket();
      await createSession({ restore: true });
      state.chart = [];
      openSocket();
      if (old) api("DELETE", `/sessions/${old}`).catch(() => {});
    } catch (e) {
      showMessage(e.message);
      if (!state.ws) scheduleReconnect("error");
    }
  });
}

/** Switches the session to a built-in scene (a name) or to scene JSON (an
 *  object, shown as `label`). Resolves to the new status, or null when the
 *  server refused it (its message is shown). */
export function setScene(scene, label = null) {
  if (!state.sessionId) return Promise.resolve(null);
  return replacing(async () => {
    try {
      const status = await api("PUT", `/sessions/${state.sessionId}/scene`, scene);
      state.cameraDirty = false;
      state.lightDirty = false;
      if (typeof scene !== "string") {
        // The last model stays in the picker as "custom".
        state.want.sceneJson = scene;
        state.want.sceneLabel = label;
      }
      applyScene(status);
      applyAnswer(status);
      return status;
    } catch (e) {
      showMessage(e.message);
      if (state.status) el.scene.value = state.status.scene;
      return null;
    }
  });
}

/** Runs fn, which replaces the scene or session; camera and light edits made
 *  meanwhile wait for it (they must apply to the new scene's camera and light,
 *  not to the old one's). */
export function replacing(fn) {
  const run = (state.replacing || Promise.resolve()).then(fn);
  const done = run.catch(() => {}).then(() => {
    if (state.replacing === done) state.replacing = null;
  });
  state.replacing = done;
  return run;
}

/** Runs an edit now, or once a scene change or new session is in place. */
export function edit(fn) {
  if (state.replacing) {
    const p = state.replacing;
    p.then(() => (state.replacing && state.replacing !== p ? edit(fn) : fn()));
    return true;
  }
  fn();
  return true;
}

// ---------------------------------------------------------------- status

/** What a status says of the session's settings (the rest is progress). */
const SETTINGS = ["scene", "camera", "light", "quality", "environment", "environment_name"];

export function applyStatus(s, fromStream = false) {
  if (s.id && state.sessionId && s.id !== state.sessionId) return; // an old session's
  // A status sent before the server saw this page's last change keeps the
  // settings the change's answer brought (else a later edit would send
  // them back: an environment's intensity reverting to the old one).
  const stale = state.status && s.generation < state.adoptFrom;
  state.status = stale ? { ...s, ...Object.fromEntries(SETTINGS.map((k) => [k, state.status[k]])) } : s;
  state.maxGeneration = Math.max(state.maxGeneration, s.generation);
  el.body.dataset.generation = String(s.generation);
  el.body.dataset.spp = String(s.spp);
  el.viewport.dataset.state = s.state;
  emit("status", s, fromStream);
  if (s.failure && s.failure !== state.failure) showMessage(`rendering stopped: ${s.failure}`);
  state.failure = s.failure;
  state.want.width = s.width;
  state.want.height = s.height;

  // Settings from before this page's last change (stats sent before the
  // server saw it) must not undo it.
  if (s.generation < state.adoptFrom) return;
  state.want.quality = clone(s.quality);
  // The server's camera, light and scene win (someone else may have changed
  // them) unless this page has changes of its own on the way.
  const quiet = !state.cameraDirty && !state.lightDirty && performance.now() - state.lastLocalEdit > QUIET_MS;
  if (quiet) {
    if (s.scene !== state.want.scene) applyScene(s);
    if (!same(s.camera, state.camera)) state.camera = clone(s.camera);
    const l = s.light ? pickLight(s.light) : null;
    if (!same(l, state.light)) state.light = l;
    if (s.scene !== el.scene.value && document.activeElement !== el.scene) showScene(s.scene);
  }
  emit("settings", s);
}

/** A change the server has answered: older stats are out of date. */
export function applyAnswer(status) {
  state.adoptFrom = Math.max(state.adoptFrom, status.generation);
  applyStatus(status);
}

/** Sends a settings change over HTTP and adopts the server's answer. While
 *  it is on the way, stats from the stream predate it: they must not put
 *  the old settings back into the panel (a checkbox just unticked would
 *  tick itself again). A refused change lets the server's settings stand. */
export async function change(method, path, body) {
  const before = state.adoptFrom;
  state.adoptFrom = Math.max(before, state.maxGeneration + 1);
  try {
    const status = await api(method, path, body);
    state.adoptFrom = before;
    applyAnswer(status);
    return status;
  } catch (e) {
    state.adoptFrom = before;
    throw e;
  }
}

// ---------------------------------------------------------------- camera and light updates

export function touchLocal() {
  state.lastLocalEdit = performance.now();
}

// At most one camera and one light update per animation frame.
let flushQueued = false;
export function requestFlush() {
  if (flushQueued) return;
  flushQueued = true;
  requestAnimationFrame(flush);
}

export function flush() {
  flushQueued = false;
  if (!state.sessionId) return;
  const message = {};
  if (state.cameraDirty && state.camera) message.camera = clone(state.camera);
  if (state.lightDirty && state.light) message.light = clone(state.light);
  if (!Object.keys(message).length) return;
  if (send(message)) {
    state.cameraDirty = false;
    state.lightDirty = false;
    state.adoptFrom = state.maxGeneration + 1;
    touchLocal();
  }
  // Otherwise the socket is down: the change stays dirty and goes when it
  // reopens (or with the new session, which restores camera and light).
}
