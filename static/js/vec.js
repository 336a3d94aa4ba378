// Small 3-vector helpers ([x, y, z] arrays) and the camera's frame.

export const add = (a, b) => a.map((x, i) => x + b[i]);
export const sub = (a, b) => a.map((x, i) => x - b[i]);
export const scale = (a, s) => a.map((x) => x * s);
export const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
export const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
export const length = (a) => Math.hypot(a[0], a[1], a[2]);
export const normalize = (a) => { const l = length(a); return l > 0 ? scale(a, 1 / l) : [0, 0, 0]; };
export const clone = (v) => (v == null ? v : JSON.parse(JSON.stringify(v)));
export const same = (a, b) => JSON.stringify(a) === JSON.stringify(b);

/** The camera's frame: view direction, right, up (world up of the camera). */
export function cameraFrame(cam) {
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
