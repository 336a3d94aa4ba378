// The export panel: the frame as PNG or PFM, and a curl script that makes
// the same session.

import { api } from "./api.js";
import { $, el } from "./dom.js";
import { showMessage } from "./messages.js";
import { pickLight } from "./session.js";
import { state } from "./state.js";

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
