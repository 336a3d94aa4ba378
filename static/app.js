// pathstream browser client: one render session, its frame stream and its
// controls. Plain ES module, no build step, no dependencies.
//
// URL parameters (all optional): scene, width, height, px (screen pixels per
// image pixel when fitting the window), token (kept in sessionStorage, then
// dropped from the address bar).
//
// For tests and scripts the page exposes window.pathstream (sessionId, the
// last stats, frame count, the spp and generation of the frame on the canvas)
// and mirrors the essentials on <body> as data attributes: data-session-id,
// data-conn (starting, connecting, live, reconnecting), data-frames,
// data-generation, data-spp (latest stats), data-frame-spp and
// data-frame-generation (the image shown). Elements have stable ids.

const $ = (id) => document.getElementById(id);
const TOKEN_KEY = "pathstream.token";
const THESIS_SCENES = { Digit1: "cornell", Digit2: "cornell-glass" };
const RETRY_MAX_MS = 4000;
const QUIET_MS = 1000; // after a local edit, ignore the server's older view this long

const el = {
  body: document.body,
  view: $("view"),
  viewport: $("viewport"),
  placeholder: $("placeholder"),
  conn: $("conn"),
  scene: $("scene"),
  width: $("width"),
  height: $("height"),
  px: $("px"),
  chart: $("chart"),
  message: $("message"),
  messageText: $("message-text"),
  help: $("help"),
  tokenDialog: $("token-dialog"),
  tokenInput: $("token-input"),
  tokenReason: $("token-reason"),
  curlDialog: $("curl-dialog"),
  curlText: $("curl-text"),
  curlNote: $("curl-note"),
  touchpad: $("touchpad"),
  lColor: $("l-color"),
  lIntensity: $("l-intensity"),
  lPosition: $("l-position"),
};
const ctx = el.view.getContext("2d");

// ---------------------------------------------------------------- state

const params = new URLSearchParams(location.search);

const state = {
  token: null,
  sessionId: null,
  /** What a new session is opened with (also after the server lost ours). */
  want: {
    scene: params.get("scene") || "cornell-glass",
    width: intParam("width"),
    height: intParam("height"),
    quality: null,
  },
  status: null, // last status or stats from the server
  camera: null, // the camera as this page wants it
  defaultCamera: null, // the scene's own camera (R)
  light: null, // {position, color, intensity} as this page wants it
  defaultLight: null,
  moveStep: 1,
  cameraDirty: false,
  lightDirty: false,
  lastLocalEdit: 0,
  maxGeneration: 0, // newest generation seen from the server
  adoptFrom: 0, // stats older than this generation predate a change of ours
  failure: null,
  ws: null,
  conn: "starting",
  retry: 0,
  retryTimer: null,
  connecting: false,
  replacing: null, // promise of a scene change or new session in flight
  frames: 0,
  decoding: false,
  pendingFrame: null, // {blob, stats} waiting to be drawn
  lastReceived: null,
  displayed: null,
  chart: [], // [{generation, points: [[ms, err]]}]
};

function intParam(name) {
  const v = Number.parseInt(params.get(name) ?? "", 10);
  return Number.isFinite(v) && v > 0 ? v : null;
}

// The token: from ?token= (then hidden from the address bar) or this tab's storage.
{
  const fromUrl = params.get("token");
  try {
    if (fromUrl) sessionStorage.setItem(TOKEN_KEY, fromUrl);
    state.token = sessionStorage.getItem(TOKEN_KEY);
  } catch {
    state.token = fromUrl;
  }
  if (fromUrl) {
    params.delete("token");
    const q = params.toString();
    history.replaceState(null, "", location.pathname + (q ? `?${q}` : "") + location.hash);
  }
}

window.pathstream = {
  get sessionId() { return state.sessionId; },
  get status() { return state.status; },
  get camera() { return state.camera; },
  get light() { return state.light; },
  get conn() { return state.conn; },
  get frames() { return state.frames; },
  /** {spp, generation} of the image on the canvas. */
  get displayed() { return state.displayed && state.displayed.stats; },
  get moveStep() { return state.moveStep; },
};

// ---------------------------------------------------------------- messages

let messageTimer = null;

function showMessage(text, kind = "error", ms = 10000) {
  el.messageText.textContent = text;
  el.message.dataset.kind = kind;
  el.message.hidden = false;
  clearTimeout(messageTimer);
  if (ms) messageTimer = setTimeout(() => { el.message.hidden = true; }, ms);
}

$("message-close").addEventListener("click", () => { el.message.hidden = true; });

function setConn(conn, text) {
  state.conn = conn;
  el.conn.dataset.state = conn;
  el.conn.textContent = text ?? conn;
  el.body.dataset.conn = conn;
}

// ---------------------------------------------------------------- HTTP API

class ApiError extends Error {
  constructor(status, message) {
    super(message);
    this.status = status; // 0 = no answer (network)
  }
}

let tokenPrompt = null;

/** Asks for the token once, however many requests are waiting for it. */
function askToken(reason) {
  if (!tokenPrompt) {
    tokenPrompt = new Promise((resolve) => {
      el.tokenReason.textContent = reason;
      el.tokenInput.value = "";
      el.tokenDialog.hidden = false;
      el.tokenInput.focus();
      const form = $("token-form");
      form.onsubmit = (e) => {
        e.preventDefault();
        const t = el.tokenInput.value.trim();
        if (!t) return;
        state.token = t;
        try { sessionStorage.setItem(TOKEN_KEY, t); } catch { /* private mode */ }
        el.tokenDialog.hidden = true;
        el.tokenInput.blur();
        tokenPrompt = null;
        resolve();
      };
    });
  }
  return tokenPrompt;
}

function authHeaders() {
  return state.token ? { authorization: `Bearer ${state.token}` } : {};
}

/** One API call; JSON in and out (or a Blob with as: "blob"). Asks for the
 *  token and retries on 401; throws ApiError with the server's message. */
async function api(method, path, body, { as = "json" } = {}) {
  for (;;) {
    const headers = authHeaders();
    if (body !== undefined) headers["content-type"] = "application/json";
    let res;
    try {
      res = await fetch(`/api${path}`, {
        method,
        headers,
        body: body === undefined ? undefined : JSON.stringify(body),
        cache: "no-store",
      });
    } catch (e) {
      throw new ApiError(0, `no answer from the server (${e.message})`);
    }
    if (res.status === 401) {
      const reason = state.token ? "The token was refused; enter the right one." : "This server needs a token.";
      await askToken(reason);
      continue;
    }
    if (!res.ok) {
      let message = `${res.status} ${res.statusText}`;
      try {
        const j = await res.json();
        if (j && j.error) message = j.error;
      } catch { /* not JSON */ }
      throw new ApiError(res.status, message);
    }
    if (res.status === 204) return null;
    return as === "blob" ? res.blob() : res.json();
  }
}

// ---------------------------------------------------------------- vectors

const add = (a, b) => a.map((x, i) => x + b[i]);
const sub = (a, b) => a.map((x, i) => x - b[i]);
const scale = (a, s) => a.map((x) => x * s);
const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
const length = (a) => Math.hypot(a[0], a[1], a[2]);
const normalize = (a) => { const l = length(a); return l > 0 ? scale(a, 1 / l) : [0, 0, 0]; };
const clone = (v) => (v == null ? v : JSON.parse(JSON.stringify(v)));
const same = (a, b) => JSON.stringify(a) === JSON.stringify(b);

/** The camera's frame: view direction, right, up (world up of the camera). */
function cameraFrame(cam) {
  const up = normalize(cam.up || [0, 1, 0]);
  const dir = normalize(sub(cam.look_at, cam.position));
  let right = cross(dir, up);
  if (length(right) < 1e-9) right = cross(dir, [0, 0, 1]);
  right = normalize(right);
  // Horizontal forward (for the light): the view direction without its up part.
  let flat = sub(dir, scale(up, dot(dir, up)));
  flat = length(flat) < 1e-9 ? cross(up, right) : normalize(flat);
  return { dir, right, up, flat };
}

// ---------------------------------------------------------------- session

function applyScene(status) {
  state.camera = clone(status.camera);
  state.defaultCamera = clone(status.camera);
  state.light = status.light ? pickLight(status.light) : null;
  state.defaultLight = clone(state.light);
  // Step: 2% of the camera's distance from the origin (6 units in the
  // Cornell box), at least 0.05 (the unit-sphere furnace).
  state.moveStep = Math.max(0.05, 0.02 * length(status.camera.position));
  state.want.scene = status.scene;
  el.scene.value = status.scene;
}

function pickLight(l) {
  return { position: [...l.position], color: [...l.color], intensity: l.intensity };
}

/** Opens a session with what the page wants; restores camera and light when
 *  it replaces a lost one. */
async function createSession({ restore = false } = {}) {
  const w = state.want;
  const body = { scene: w.scene, width: w.width, height: w.height };
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
async function connect() {
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

function scheduleReconnect(why) {
  clearTimeout(state.retryTimer);
  const delay = Math.min(RETRY_MAX_MS, 250 * 2 ** state.retry);
  state.retry += 1;
  setConn("reconnecting", `reconnecting (${why}, try ${state.retry})`);
  state.retryTimer = setTimeout(connect, delay);
}

function openSocket() {
  closeSocket();
  const proto = location.protocol === "https:" ? "wss" : "ws";
  const q = state.token ? `?token=${encodeURIComponent(state.token)}` : "";
  const ws = new WebSocket(`${proto}://${location.host}/api/sessions/${state.sessionId}/ws${q}`);
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
          f.stats = { spp: m.spp, generation: m.generation };
          if (state.displayed === f) markDisplayed(f);
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

function closeSocket() {
  const ws = state.ws;
  state.ws = null;
  if (ws) {
    ws.onclose = null;
    ws.onmessage = null;
    try { ws.close(); } catch { /* already closed */ }
  }
}

function send(message) {
  if (state.ws && state.ws.readyState === WebSocket.OPEN) {
    state.ws.send(JSON.stringify(message));
    return true;
  }
  return false;
}

/** Opens a new session at the resolution in the inputs (the old one is deleted). */
async function resize() {
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

function setScene(name) {
  if (!state.sessionId) return;
  return replacing(async () => {
    try {
      const status = await api("PUT", `/sessions/${state.sessionId}/scene`, name);
      state.cameraDirty = false;
      state.lightDirty = false;
      applyScene(status);
      applyAnswer(status);
    } catch (e) {
      showMessage(e.message);
      if (state.status) el.scene.value = state.status.scene;
    }
  });
}

/** Runs fn, which replaces the scene or session; camera and light edits made
 *  meanwhile wait for it (they must apply to the new scene's camera and light,
 *  not to the old one's). */
function replacing(fn) {
  const run = (state.replacing || Promise.resolve()).then(fn);
  const done = run.catch(() => {}).then(() => {
    if (state.replacing === done) state.replacing = null;
  });
  state.replacing = done;
  return run;
}

/** Runs an edit now, or once a scene change or new session is in place. */
function edit(fn) {
  if (state.replacing) {
    const p = state.replacing;
    p.then(() => (state.replacing && state.replacing !== p ? edit(fn) : fn()));
    return true;
  }
  fn();
  return true;
}

// ---------------------------------------------------------------- status, HUD

function fmtTime(ms) {
  if (!(ms >= 0)) return "–";
  const s = ms / 1000;
  if (s < 60) return `${s.toFixed(1)} s`;
  const m = Math.floor(s / 60);
  return `${m} min ${Math.floor(s % 60)} s`;
}

function fmtRate(r) {
  if (!(r > 0)) return "0";
  if (r >= 1e9) return `${(r / 1e9).toFixed(2)} G`;
  if (r >= 1e6) return `${(r / 1e6).toFixed(2)} M`;
  if (r >= 1e3) return `${(r / 1e3).toFixed(1)} k`;
  return r.toFixed(0);
}

function setHud(id, text, value) {
  const d = $(id);
  d.textContent = text;
  if (value !== undefined) d.dataset.value = value == null ? "" : String(value);
}

function applyStatus(s, fromStream = false) {
  if (s.id && state.sessionId && s.id !== state.sessionId) return; // an old session's
  state.status = s;
  state.maxGeneration = Math.max(state.maxGeneration, s.generation);
  el.body.dataset.generation = String(s.generation);
  el.body.dataset.spp = String(s.spp);
  setHud("hud-state", s.failure ? `failed: ${s.failure}` : s.state, s.state);
  el.viewport.dataset.state = s.state;
  setHud("hud-spp", String(s.spp), s.spp);
  setHud("hud-sps", `${fmtRate(s.samples_per_sec)}`, s.samples_per_sec);
  setHud("hud-error", s.error_estimate == null ? "–" : `${(100 * s.error_estimate).toPrecision(3)} %`, s.error_estimate);
  setHud("hud-elapsed", fmtTime(s.elapsed_ms), s.elapsed_ms);
  setHud("hud-res", `${s.width} × ${s.height}`);
  setHud("hud-device", `${s.backend}: ${s.device}`);
  if (s.failure && s.failure !== state.failure) showMessage(`rendering stopped: ${s.failure}`);
  state.failure = s.failure;
  state.want.width = s.width;
  state.want.height = s.height;
  if (fromStream) addChartPoint(s);

  // Settings from before this page's last change (stats sent before the
  // server saw it) must not undo it.
  if (s.generation < state.adoptFrom) return;
  state.want.quality = clone(s.quality);
  fillQuality(s.quality);
  // The server's camera, light and scene win (someone else may have changed
  // them) unless this page has changes of its own on the way.
  const quiet = !state.cameraDirty && !state.lightDirty && performance.now() - state.lastLocalEdit > QUIET_MS;
  if (quiet) {
    if (s.scene !== state.want.scene) applyScene(s);
    if (!same(s.camera, state.camera)) state.camera = clone(s.camera);
    const l = s.light ? pickLight(s.light) : null;
    if (!same(l, state.light)) state.light = l;
    if (s.scene !== el.scene.value && document.activeElement !== el.scene) el.scene.value = s.scene;
  }
  fillLight();
}

/** A change the server has answered: older stats are out of date. */
function applyAnswer(status) {
  state.adoptFrom = Math.max(state.adoptFrom, status.generation);
  applyStatus(status);
}

// ---------------------------------------------------------------- frames

async function drawFrames() {
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
      if (el.view.width !== bitmap.width || el.view.height !== bitmap.height) {
        el.view.width = bitmap.width;
        el.view.height = bitmap.height;
        fitCanvas();
      }
      ctx.drawImage(bitmap, 0, 0);
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

/** The spp and generation of the image on the canvas, for tests and scripts. */
function markDisplayed(frame) {
  if (!frame.stats) return;
  el.body.dataset.frameSpp = String(frame.stats.spp);
  el.body.dataset.frameGeneration = String(frame.stats.generation);
}

/** Shows the image as large as fits: whole device pixels per image pixel
 *  (crisp) when it fits at least once, smooth downscaling otherwise. */
function fitCanvas() {
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
function fitResolution() {
  const r = el.viewport.getBoundingClientRect();
  const dpr = window.devicePixelRatio || 1;
  const px = Number(el.px.value) || 2;
  const w = Math.max(16, Math.min(4096, Math.floor((r.width * dpr) / px)));
  const h = Math.max(16, Math.min(4096, Math.floor((r.height * dpr) / px)));
  return [w, h];
}

function updateSizeInputs() {
  if (document.activeElement !== el.width) el.width.value = state.want.width ?? "";
  if (document.activeElement !== el.height) el.height.value = state.want.height ?? "";
}

// ---------------------------------------------------------------- chart

function addChartPoint(s) {
  if (s.error_estimate == null || !(s.error_estimate > 0) || !(s.elapsed_ms >= 0)) return;
  let series = state.chart[state.chart.length - 1];
  if (!series || series.generation !== s.generation || series.session !== s.id) {
    series = { generation: s.generation, session: s.id, points: [] };
    state.chart.push(series);
    // Keep the last few runs with more than a point or two, to compare settings.
    state.chart = state.chart.filter((c, i, all) => i === all.length - 1 || c.points.length > 2).slice(-4);
  }
  const last = series.points[series.points.length - 1];
  if (!last || s.elapsed_ms > last[0]) series.points.push([s.elapsed_ms, s.error_estimate]);
  if (series.points.length > 2000) series.points.splice(0, series.points.length - 2000);
  scheduleChart();
}

let chartQueued = false;
function scheduleChart() {
  if (chartQueued) return;
  chartQueued = true;
  requestAnimationFrame(() => { chartQueued = false; drawChart(); });
}

function drawChart() {
  const c = el.chart;
  const dpr = window.devicePixelRatio || 1;
  const cw = c.clientWidth;
  const ch = c.clientHeight;
  if (!cw || !ch) return;
  if (c.width !== Math.round(cw * dpr) || c.height !== Math.round(ch * dpr)) {
    c.width = Math.round(cw * dpr);
    c.height = Math.round(ch * dpr);
  }
  const g = c.getContext("2d");
  g.setTransform(dpr, 0, 0, dpr, 0, 0);
  g.clearRect(0, 0, cw, ch);
  const styles = getComputedStyle(c);
  const fg = styles.color;
  g.font = "10px ui-monospace, monospace";
  g.fillStyle = fg;
  const series = state.chart.filter((s) => s.points.length > 0);
  const pad = { l: 42, r: 8, t: 6, b: 16 };
  const pw = cw - pad.l - pad.r;
  const ph = ch - pad.t - pad.b;
  if (!series.length) {
    g.globalAlpha = 0.6;
    g.fillText("waiting for an error estimate", pad.l, pad.t + ph / 2);
    g.globalAlpha = 1;
    return;
  }
  let tMax = 0;
  let eMin = Infinity;
  let eMax = 0;
  for (const s of series) {
    for (const [t, e] of s.points) {
      tMax = Math.max(tMax, t);
      eMin = Math.min(eMin, e);
      eMax = Math.max(eMax, e);
    }
  }
  tMax = Math.max(tMax, 1000);
  let lo = Math.floor(Math.log10(eMin) * 2) / 2;
  let hi = Math.ceil(Math.log10(eMax) * 2) / 2;
  if (hi - lo < 1) { hi = lo + 1; }
  const x = (t) => pad.l + (t / tMax) * pw;
  const y = (e) => pad.t + ((hi - Math.log10(e)) / (hi - lo)) * ph;
  // Grid: decades (labelled in percent) and the time axis.
  g.strokeStyle = fg;
  g.lineWidth = 1;
  g.globalAlpha = 0.25;
  g.strokeRect(pad.l, pad.t, pw, ph);
  g.globalAlpha = 1;
  g.textAlign = "right";
  g.textBaseline = "middle";
  for (let d = Math.ceil(lo); d <= Math.floor(hi); d++) {
    const yy = y(10 ** d);
    g.globalAlpha = 0.25;
    g.beginPath(); g.moveTo(pad.l, yy); g.lineTo(pad.l + pw, yy); g.stroke();
    g.globalAlpha = 0.8;
    const pct = 100 * 10 ** d;
    g.fillText(`${pct >= 1 ? pct.toFixed(0) : pct.toPrecision(1)}%`, pad.l - 4, yy);
  }
  g.textAlign = "left";
  g.textBaseline = "alphabetic";
  g.globalAlpha = 0.8;
  g.fillText("0", pad.l, ch - 3);
  g.textAlign = "right";
  g.fillText(fmtTime(tMax), pad.l + pw, ch - 3);
  g.textAlign = "left";
  // 1/sqrt(t) from the current run's first point: where the curve flattens
  // out above this line, more time buys less than Monte Carlo promises.
  const cur = series[series.length - 1];
  const [t0, e0] = cur.points[0];
  if (t0 > 0) {
    g.setLineDash([3, 3]);
    g.globalAlpha = 0.4;
    g.beginPath();
    for (let i = 0; i <= 40; i++) {
      const t = t0 + ((tMax - t0) * i) / 40;
      const e = e0 * Math.sqrt(t0 / t);
      if (i === 0) g.moveTo(x(t), y(e)); else g.lineTo(x(t), y(e));
    }
    g.stroke();
    g.setLineDash([]);
  }
  const accent = styles.getPropertyValue("--accent").trim() || "#4cc3ff";
  series.forEach((s, i) => {
    const current = i === series.length - 1;
    g.globalAlpha = current ? 1 : 0.35;
    g.strokeStyle = current ? accent : fg;
    g.lineWidth = current ? 1.5 : 1;
    g.beginPath();
    s.points.forEach(([t, e], j) => {
      if (j === 0) g.moveTo(x(t), y(e)); else g.lineTo(x(t), y(e));
    });
    g.stroke();
  });
  g.globalAlpha = 1;
}

// ---------------------------------------------------------------- camera and light

function touchLocal() {
  state.lastLocalEdit = performance.now();
}

function moveCamera(forward, right, up) {
  if (!state.camera) return;
  const f = cameraFrame(state.camera);
  const by = add(add(scale(f.dir, forward), scale(f.right, right)), scale(f.up, up));
  const d = scale(by, state.moveStep);
  state.camera.position = add(state.camera.position, d);
  state.camera.look_at = add(state.camera.look_at, d);
  cameraChanged();
}

/** Turns the view: yaw around the camera's up, pitch toward it (degrees). */
function look(yawDeg, pitchDeg) {
  if (!state.camera) return;
  const cam = state.camera;
  const f = cameraFrame(cam);
  const dist = length(sub(cam.look_at, cam.position)) || 1;
  const yaw = (yawDeg * Math.PI) / 180;
  let pitch = Math.asin(Math.max(-1, Math.min(1, dot(f.dir, f.up))));
  pitch = Math.max(-1.5, Math.min(1.5, pitch + (pitchDeg * Math.PI) / 180));
  const flat = normalize(add(scale(f.flat, Math.cos(yaw)), scale(f.right, Math.sin(yaw))));
  const dir = add(scale(flat, Math.cos(pitch)), scale(f.up, Math.sin(pitch)));
  cam.look_at = add(cam.position, scale(dir, dist));
  cameraChanged();
}

function resetCamera() {
  if (!state.defaultCamera) return;
  state.camera = clone(state.defaultCamera);
  cameraChanged();
}

function cameraChanged() {
  state.cameraDirty = true;
  touchLocal();
  requestFlush();
}

function moveLight(forward, right, up) {
  if (!state.light || !state.camera) return noLight();
  const f = cameraFrame(state.camera);
  const by = add(add(scale(f.flat, forward), scale(f.right, right)), scale(f.up, up));
  state.light.position = add(state.light.position, scale(by, state.moveStep));
  lightChanged();
}

function scaleLight(factor) {
  if (!state.light) return noLight();
  state.light.intensity = Math.max(0, state.light.intensity * factor);
  lightChanged();
}

function randomLightColor() {
  if (!state.light) return noLight();
  // A saturated hue at full value (the server normalises the colour by its
  // largest component, so this keeps the intensity where it was).
  const h = Math.random() * 6;
  const s = 0.4 + 0.6 * Math.random();
  const c = [0, 0, 0];
  const i = Math.floor(h);
  const fr = h - i;
  const [p, q, t] = [1 - s, 1 - s * fr, 1 - s * (1 - fr)];
  const rgb = [[1, t, p], [q, 1, p], [p, 1, t], [p, q, 1], [t, p, 1], [1, p, q]][i % 6];
  for (let k = 0; k < 3; k++) c[k] = Math.round(rgb[k] * 1000) / 1000;
  state.light.color = c;
  lightChanged();
}

function noLight() {
  showMessage("this scene has no light to change", "info", 3000);
}

function lightChanged() {
  state.lightDirty = true;
  touchLocal();
  fillLight();
  requestFlush();
}

// At most one camera and one light update per animation frame.
let flushQueued = false;
function requestFlush() {
  if (flushQueued) return;
  flushQueued = true;
  requestAnimationFrame(flush);
}

function flush() {
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

// ---------------------------------------------------------------- panels

// Presets from GET /api/presets, loaded once a session answers (the token
// may be needed first).
let presets = null;
let presetsLoading = false;
const PRESET_KNOBS = ["max_depth", "rr_depth", "nee", "filter", "clamp"];

async function loadPresets() {
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

/** The preset whose knobs `q` has, or "" (custom). */
function presetOf(q) {
  const p = (presets || []).find((p) => PRESET_KNOBS.every((k) => same(p.quality[k], q[k])));
  return p ? p.name : "";
}

$("q-preset").addEventListener("change", async () => {
  const name = $("q-preset").value;
  if (!name || !state.sessionId) return;
  try {
    applyAnswer(await api("PATCH", `/sessions/${state.sessionId}/quality`, { preset: name }));
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
  set("q-filter", q.filter);
  set("q-clamp", q.clamp);
  set("q-spp", q.spp);
  set("q-time", q.time_ms == null ? null : +(q.time_ms / 1000).toPrecision(6));
  set("q-target", q.target_error == null ? null : +(q.target_error * 100).toPrecision(6));
}

function readQualityField(input) {
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

async function qualityChanged(input) {
  const [field, value] = readQualityField(input);
  if (value === undefined) {
    showMessage(`quality.${field}: enter a number`);
    fillQuality(state.status && state.status.quality);
    return;
  }
  if (!state.sessionId) return;
  try {
    const status = await api("PATCH", `/sessions/${state.sessionId}/quality`, { [field]: value });
    applyAnswer(status);
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

// ---------------------------------------------------------------- export

function download(blob, name) {
  const url = URL.createObjectURL(blob);
  const a = document.createElement("a");
  a.href = url;
  a.download = name;
  document.body.append(a);
  a.click();
  a.remove();
  setTimeout(() => URL.revokeObjectURL(url), 10000);
}

async function downloadFrame(ext) {
  if (!state.sessionId) return;
  try {
    const blob = await api("GET", `/sessions/${state.sessionId}/frame.${ext}`, undefined, { as: "blob" });
    const s = state.status;
    const name = `pathstream-${s ? s.scene : "frame"}-${s ? `${s.spp}spp` : ""}.${ext}`;
    download(blob, name);
  } catch (e) {
    showMessage(`download: ${e.message}`);
  }
}

const shq = (s) => `'${String(s).replace(/'/g, "'\\''")}'`;

/** A shell script that makes the same session and fetches its image. */
function curlCommand() {
  const s = state.status;
  if (!s) return null;
  const base = `${location.origin}/api`;
  const auth = state.token ? ` -H "Authorization: Bearer $PATHSTREAM_TOKEN"` : "";
  const json = ` -H 'content-type: application/json'`;
  const create = { scene: s.scene, width: s.width, height: s.height, quality: s.quality };
  const lines = [];
  if (state.token) lines.push("# export PATHSTREAM_TOKEN=...   (the token this page was given)");
  lines.push(`ID=$(curl -sSf -X POST ${shq(`${base}/sessions`)}${auth}${json} -d ${shq(JSON.stringify(create))} | sed -n 's/^{"id":"\\([^"]*\\)".*/\\1/p')`);
  lines.push(`curl -sSf -o /dev/null -X PATCH "${base}/sessions/$ID/camera"${auth}${json} -d ${shq(JSON.stringify(state.camera ?? s.camera))}`);
  const light = state.light ?? (s.light ? pickLight(s.light) : null);
  if (light) {
    lines.push(`curl -sSf -o /dev/null -X PATCH "${base}/sessions/$ID/light"${auth}${json} -d ${shq(JSON.stringify(light))}`);
  }
  const spp = Math.max(1, s.spp);
  lines.push(`curl -sSf -o frame.png "${base}/sessions/$ID/frame.png?min_spp=${spp}&timeout_ms=600000"${auth}`);
  lines.push(`curl -sSf -o frame.pfm "${base}/sessions/$ID/frame.pfm"${auth}`);
  lines.push(`curl -sSf -X DELETE "${base}/sessions/$ID"${auth}`);
  return lines.join("\n");
}

async function copyCurl() {
  const text = curlCommand();
  if (!text) {
    showMessage("no session yet");
    return;
  }
  el.curlText.value = text;
  let copied = false;
  try {
    await navigator.clipboard.writeText(text);
    copied = true;
  } catch {
    // Not a secure context, or no permission: the dialog below lets the user copy.
  }
  el.curlNote.textContent = copied ? "Copied to the clipboard." : "Select and copy (the clipboard is not available here).";
  el.curlDialog.hidden = false;
  el.curlText.focus();
  el.curlText.select();
}

$("btn-png").addEventListener("click", () => downloadFrame("png"));
$("btn-pfm").addEventListener("click", () => downloadFrame("pfm"));
$("btn-curl").addEventListener("click", copyCurl);
$("curl-close").addEventListener("click", () => { el.curlDialog.hidden = true; });

// ---------------------------------------------------------------- keys, mouse, touch

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

el.scene.addEventListener("change", () => {
  setScene(el.scene.value);
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
