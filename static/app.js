// Minimal viewer: opens a session, shows each frame as it arrives, prints the
// stats. (The full client with controls is the browser-client issue.)
const canvas = document.getElementById("view");
const hud = document.getElementById("hud");
const ctx = canvas.getContext("2d");

async function main() {
  const response = await fetch("/api/sessions", {
    method: "POST",
    headers: { "content-type": "application/json" },
    body: JSON.stringify({ scene: "cornell-glass", width: 512, height: 512 }),
  });
  const session = await response.json();
  if (!response.ok) {
    hud.textContent = `error: ${session.error}`;
    return;
  }
  const proto = location.protocol === "https:" ? "wss" : "ws";
  const socket = new WebSocket(`${proto}://${location.host}/api/sessions/${session.id}/ws`);
  socket.binaryType = "blob";
  socket.onmessage = async (event) => {
    if (typeof event.data === "string") {
      const s = JSON.parse(event.data);
      if (s.type === "error") {
        hud.textContent = `error: ${s.error}`;
        return;
      }
      const err = s.error_estimate == null ? "n/a" : `${(100 * s.error_estimate).toFixed(2)}%`;
      hud.textContent = `${s.scene} ${s.width}x${s.height}  ${s.spp} spp  error ${err}  ` +
        `${(s.samples_per_sec / 1e6).toFixed(2)} M paths/s  ${s.state}  ${s.backend}: ${s.device}`;
      return;
    }
    const bitmap = await createImageBitmap(event.data);
    canvas.width = bitmap.width;
    canvas.height = bitmap.height;
    ctx.drawImage(bitmap, 0, 0);
  };
  socket.onclose = () => { hud.textContent += "  (disconnected)"; };
}

main().catch((e) => { hud.textContent = `error: ${e}`; });
