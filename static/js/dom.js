// The page's elements, looked up once. Elements have stable ids (tests and
// scripts rely on them).

export const $ = (id) => document.getElementById(id);

export const el = {
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
  cAperture: $("c-aperture"),
  cFocus: $("c-focus"),
  cFNumber: $("c-fnumber"),
  cProjection: $("c-projection"),
  eMap: $("e-map"),
  eColor: $("e-color"),
  eIntensity: $("e-intensity"),
  eRotation: $("e-rotation"),
  eVisible: $("e-visible"),
  eSunElevation: $("e-sun-elevation"),
  eSunAzimuth: $("e-sun-azimuth"),
  eName: $("e-name"),
};
export const ctx = el.view.getContext("2d");
