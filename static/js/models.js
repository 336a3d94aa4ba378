// Model files (.obj, .gltf, .glb, .ply): picked with the "open model" button
// or dropped on the page (a dropped .hdr or .exr goes to environment.js),
// uploaded as an asset (POST /api/assets, upload.js), and the
// session switched to them; the server frames a model without a camera and
// lights one without emitters by a default sky. What the server does not
// render as given comes back as warnings, shown in the message bar.

import { $, el } from "./dom.js";
import { MAP_FILE, openEnvironment } from "./environment.js";
import { showMessage } from "./messages.js";
import { setScene } from "./session.js";
import { uploadAsset } from "./upload.js";

const MODEL = /\.(obj|gltf|glb|ply)$/i;
const picker = $("model-file");

/** Uploads one model file and renders it; resolves to the session status
 *  (null when refused: the server's message is shown). */
export async function openModel(file) {
  if (!MODEL.test(file.name)) {
    showMessage(`${file.name}: not a model file (.obj, .gltf, .glb or .ply)`);
    return null;
  }
  const asset = await uploadAsset(file);
  if (!asset) return null;
  const status = await setScene({ objects: [{ type: "model", asset: asset.id }] }, file.name);
  el.body.dataset.upload = status ? "done" : "failed";
  if (!status) return null;
  const warnings = [...new Set([...(asset.warnings || []), ...(status.warnings || [])])];
  const what = `${file.name}: ${asset.triangles.toLocaleString("en")} triangles`;
  if (warnings.length) showMessage(`${what}. ${warnings.join("; ")}`, "info", 15000);
  else showMessage(what, "info", 4000);
  return status;
}

$("btn-model").addEventListener("click", () => picker.click());
picker.addEventListener("change", () => {
  const file = picker.files[0];
  picker.value = ""; // the same file again is a new pick
  if (file) openModel(file);
});

// Drop anywhere on the page; the render area shows where it goes.
const hasFiles = (e) => [...(e.dataTransfer?.types || [])].includes("Files");
let depth = 0;
document.addEventListener("dragenter", (e) => {
  if (!hasFiles(e)) return;
  depth += 1;
  el.viewport.classList.add("dropping");
});
document.addEventListener("dragleave", (e) => {
  if (!hasFiles(e)) return;
  depth = Math.max(0, depth - 1);
  if (!depth) el.viewport.classList.remove("dropping");
});
document.addEventListener("dragover", (e) => {
  if (!hasFiles(e)) return;
  e.preventDefault();
  e.dataTransfer.dropEffect = "copy";
});
document.addEventListener("drop", (e) => {
  if (!hasFiles(e)) return;
  e.preventDefault();
  depth = 0;
  el.viewport.classList.remove("dropping");
  const files = [...e.dataTransfer.files];
  const file = files.find((f) => MODEL.test(f.name) || MAP_FILE.test(f.name)) || files[0];
  if (files.length > 1) {
    showMessage(`${files.length} files dropped: opening ${file.name} (one model or map file at a time; a model's textures and .mtl are not read)`, "info", 6000);
  }
  // An .hdr or .exr lights the scene; anything else is read as a model.
  if (file && MAP_FILE.test(file.name)) openEnvironment(file);
  else if (file) openModel(file);
});
