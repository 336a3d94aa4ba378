// What the page knows and wants: URL parameters, the token, the session and
// its settings as this page wants them, and a small event hub through which
// the session tells the views (HUD, chart, panels) what changed.
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
// data-frame-generation (the image shown), data-frame-width and
// data-narrow-frames (the last frame's width; frames sent narrower than the
// session, progressive), data-stream-format (the format the page asks for).

export const TOKEN_KEY = "pathstream.token";
export const THESIS_SCENES = { Digit1: "cornell", Digit2: "cornell-glass" };
export const RETRY_MAX_MS = 4000;
export const QUIET_MS = 1000; // after a local edit, ignore the server's older view this long

export const params = new URLSearchParams(location.search);

export const state = {
  token: null,
  sessionId: null,
  /** What a new session is opened with (also after the server lost ours). */
  want: {
    scene: params.get("scene") || "cornell-glass",
    /** The last uploaded model's scene JSON and file name (scene "custom"). */
    sceneJson: null,
    sceneLabel: null,
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
  /** The stream's format: chosen in the panel ("auto", "png", "jpeg"), the
   *  one streamed now, when it last switched, the last whole PNG's bytes. */
  stream: { choice: "auto", format: "png", lastSwitch: 0, pngBytes: null, raw: false },
  narrowFrames: 0, // frames narrower than the session (progressive)
};

export function intParam(name) {
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

// ---------------------------------------------------------------- events

// "status" (status, fromStream): every status or stats message of the session.
// "settings" (status): the server's settings, adopted by the page.
// "light": the page's own light changed (before the server has it).
const listeners = new Map();

export function on(event, fn) {
  if (!listeners.has(event)) listeners.set(event, []);
  listeners.get(event).push(fn);
}

export function emit(event, ...args) {
  for (const fn of listeners.get(event) || []) fn(...args);
}
