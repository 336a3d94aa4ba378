// Camera and light input: moving and turning the camera, moving,
// brightening and recolouring the light. Each edit changes the page's own
// camera or light and queues it for the server (session.requestFlush).

import { showMessage } from "./messages.js";
import { requestFlush, touchLocal } from "./session.js";
import { emit, state } from "./state.js";
import { add, cameraFrame, clone, dot, length, normalize, scale, sub } from "./vec.js";

export function moveCamera(forward, right, up) {
  if (!state.camera) return;
  const f = cameraFrame(state.camera);
  const by = add(add(scale(f.dir, forward), scale(f.right, right)), scale(f.up, up));
  const d = scale(by, state.moveStep);
  state.camera.position = add(state.camera.position, d);
  state.camera.look_at = add(state.camera.look_at, d);
  cameraChanged();
}

/** Turns the view: yaw around the camera's up, pitch toward it (degrees). */
export function look(yawDeg, pitchDeg) {
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

export function resetCamera() {
  if (!state.defaultCamera) return;
  state.camera = clone(state.defaultCamera);
  cameraChanged();
}

export function cameraChanged() {
  state.cameraDirty = true;
  touchLocal();
  requestFlush();
}

export function moveLight(forward, right, up) {
  if (!state.light || !state.camera) return noLight();
  const f = cameraFrame(state.camera);
  const by = add(add(scale(f.flat, forward), scale(f.right, right)), scale(f.up, up));
  state.light.position = add(state.light.position, scale(by, state.moveStep));
  lightChanged();
}

export function scaleLight(factor) {
  if (!state.light) return noLight();
  state.light.intensity = Math.max(0, state.light.intensity * factor);
  lightChanged();
}

export function randomLightColor() {
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

export function noLight() {
  showMessage("this scene has no light to change", "info", 3000);
}

export function lightChanged() {
  state.lightDirty = true;
  touchLocal();
  emit("light");
  requestFlush();
}

