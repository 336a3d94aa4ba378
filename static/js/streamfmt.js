// The stream's image format when the page picks it ("auto"): PNG (exact)
// while the link carries it, JPEG when it does not. No imports, no page:
// the decision is a pure function (tested under node as well).
//
// The rule, from the frames' own stats (`link_mbps` is measured from the
// page's acknowledgements; only whole-width frames count, the progressive
// ones after a change are smaller than the stream's real need):
//   PNG -> JPEG when 10 frames/s of the last frame's bytes need more than
//     the link's rate;
//   JPEG -> PNG when 10 frames/s of the last PNG frame's bytes need at most
//     half the link's rate (the margin keeps it from flapping);
//   at most one switch every SWITCH_MS.

export const TARGET_FPS = 10;
export const PNG_MARGIN = 2;
export const SWITCH_MS = 3000;
export const JPEG_QUALITY = 85;

/** Mbit/s that `bytes` per frame need at TARGET_FPS. */
export function neededMbps(bytes) {
  return (bytes * 8 * TARGET_FPS) / 1e6;
}

/**
 * The format to stream next, "png" or "jpeg".
 * @param {object} a
 * @param {"png"|"jpeg"} a.current   the format streamed now
 * @param {number|null} a.linkMbps   the link's measured rate (null: not yet)
 * @param {number} a.frameBytes      bytes of the last whole-width frame
 * @param {number|null} a.pngBytes   bytes of the last whole-width PNG frame
 * @param {number} a.sinceSwitchMs   time since the last switch
 */
export function chooseFormat({ current, linkMbps, frameBytes, pngBytes, sinceSwitchMs }) {
  if (linkMbps == null || !(linkMbps > 0) || sinceSwitchMs < SWITCH_MS) return current;
  if (current === "png") {
    return frameBytes > 0 && neededMbps(frameBytes) > linkMbps ? "jpeg" : "png";
  }
  return pngBytes > 0 && PNG_MARGIN * neededMbps(pngBytes) <= linkMbps ? "png" : "jpeg";
}

/** The `stream` settings of a format, "png", "jpeg" or "webp" (pinned in
 * the panel only: smaller than JPEG, slower to encode); progressive always on. */
export function streamSettings(format, raw = false) {
  const settings = format === "jpeg" || format === "webp"
    ? { format, quality: JPEG_QUALITY, progressive: true }
    : { format: "png", progressive: true };
  // The raw image where the session denoises (V); said only when asked.
  return raw ? { ...settings, raw: true } : settings;
}

/** The same settings as stream URL parameters. */
export function streamQuery(format, raw = false) {
  return new URLSearchParams(Object.entries(streamSettings(format, raw)).map(([k, v]) => [k, String(v)])).toString();
}
