// A file uploaded as an asset (POST /api/assets), for model files and
// environment maps alike: the message bar says what is on the way and
// <body data-upload> says "uploading", then "failed" (the caller sets
// "done" once it has used the asset).

import { api } from "./api.js";
import { el } from "./dom.js";
import { showMessage } from "./messages.js";

function size(bytes) {
  if (bytes < 1024 * 1024) return `${(bytes / 1024).toFixed(1)} KiB`;
  return `${(bytes / 1024 / 1024).toFixed(1)} MiB`;
}

/** Uploads `file`; resolves to the asset, or null when it was refused
 *  (the server's message is shown). */
export async function uploadAsset(file) {
  el.body.dataset.upload = "uploading";
  showMessage(`uploading ${file.name} (${size(file.size)})…`, "info", 0);
  try {
    return await api("POST", `/assets?name=${encodeURIComponent(file.name)}`, file);
  } catch (e) {
    el.body.dataset.upload = "failed";
    showMessage(`${file.name}: ${e.message}`);
    return null;
  }
}
