// The message bar and the connection badge.

import { $, el } from "./dom.js";
import { state } from "./state.js";

let messageTimer = null;

export function showMessage(text, kind = "error", ms = 10000) {
  el.messageText.textContent = text;
  el.message.dataset.kind = kind;
  el.message.hidden = false;
  clearTimeout(messageTimer);
  if (ms) messageTimer = setTimeout(() => { el.message.hidden = true; }, ms);
}

$("message-close").addEventListener("click", () => { el.message.hidden = true; });

export function setConn(conn, text) {
  state.conn = conn;
  el.conn.dataset.state = conn;
  el.conn.textContent = text ?? conn;
  el.body.dataset.conn = conn;
}
