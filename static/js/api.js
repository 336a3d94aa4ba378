// The HTTP API: one JSON call at a time, with the token (asked for once when
// the server wants one) and the server's error message on failure.

import { $, el } from "./dom.js";
import { TOKEN_KEY, state } from "./state.js";

export class ApiError extends Error {
  constructor(status, message) {
    super(message);
    this.status = status; // 0 = no answer (network)
  }
}

let tokenPrompt = null;

/** Asks for the token once, however many requests are waiting for it. */
export function askToken(reason) {
  if (!tokenPrompt) {
    tokenPrompt = new Promise((resolve) => {
      el.tokenReason.textContent = reason;
      el.tokenInput.value = "";
      el.tokenDialog.hidden = false;
      el.tokenInput.focus();
      const form = $("token-form");
      form.onsubmit = (e) => {
        e.preventDefault();
        const t = el.tokenInput.value.trim();
        if (!t) return;
        state.token = t;
        try { sessionStorage.setItem(TOKEN_KEY, t); } catch { /* private mode */ }
        el.tokenDialog.hidden = true;
        el.tokenInput.blur();
        tokenPrompt = null;
        resolve();
      };
    });
  }
  return tokenPrompt;
}

export function authHeaders() {
  return state.token ? { authorization: `Bearer ${state.token}` } : {};
}

/** One API call; JSON in and out (or a Blob with as: "blob"); a Blob or File
 *  body goes as raw bytes. Asks for the token and retries on 401; throws
 *  ApiError with the server's message. */
export async function api(method, path, body, { as = "json" } = {}) {
  const raw = body instanceof Blob;
  for (;;) {
    const headers = authHeaders();
    if (body !== undefined) headers["content-type"] = raw ? "application/octet-stream" : "application/json";
    let res;
    try {
      res = await fetch(`/api${path}`, {
        method,
        headers,
        body: body === undefined || raw ? body : JSON.stringify(body),
        cache: "no-store",
      });
    } catch (e) {
      throw new ApiError(0, `no answer from the server (${e.message})`);
    }
    if (res.status === 401) {
      const reason = state.token ? "The token was refused; enter the right one." : "This server needs a token.";
      await askToken(reason);
      continue;
    }
    if (!res.ok) {
      let message = `${res.status} ${res.statusText}`;
      try {
        const j = await res.json();
        if (j && j.error) message = j.error;
      } catch { /* not JSON */ }
      throw new ApiError(res.status, message);
    }
    if (res.status === 204) return null;
    return as === "blob" ? res.blob() : res.json();
  }
}
