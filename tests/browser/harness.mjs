// Shared pieces of the browser tests: a real pathstream server on 127.0.0.1,
// Debian's Chromium through playwright-core, small HTTP and polling helpers.

import { spawn } from "node:child_process";
import { once } from "node:events";
import fs from "node:fs";
import net from "node:net";
import path from "node:path";
import { fileURLToPath } from "node:url";
import { chromium } from "playwright-core";

export const REPO = path.resolve(path.dirname(fileURLToPath(import.meta.url)), "../..");
export const STATIC_DIR = path.join(REPO, "static");
export const BIN = process.env.PATHSTREAM_BIN || path.join(REPO, "target/release/pathstream");
export const CHROMIUM = process.env.CHROMIUM || "/usr/bin/chromium";
export const ARTIFACTS = path.join(REPO, "target/browser");
// Under CI (the variable set at all, any value: the Rust tests'
// `var_os("CI").is_some()`, and what .ci/run exports) a missing device
// fails a test instead of being passed over.
export const UNDER_CI = process.env.CI !== undefined;

export const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

// Servers still running when this process ends (a test that failed half-way)
// go with it.
const running = new Set();
process.on("exit", () => { for (const p of running) p.kill("SIGKILL"); });

/** A port nobody listens on right now. */
export async function freePort() {
  const s = net.createServer();
  s.listen(0, "127.0.0.1");
  await once(s, "listening");
  const { port } = s.address();
  s.close();
  await once(s, "close");
  return port;
}

/** An error that ends waitFor at once. */
export class Fatal extends Error {}

/** Polls fn until it returns a truthy value; throws with `what` after timeout
 *  (or at once when fn throws Fatal). */
export async function waitFor(what, fn, { timeout = 20000, interval = 100 } = {}) {
  const end = Date.now() + timeout;
  let last;
  for (;;) {
    try {
      const v = await fn();
      if (v) return v;
      last = v;
    } catch (e) {
      if (e instanceof Fatal) throw e;
      last = e;
    }
    if (Date.now() > end) {
      throw new Error(`timed out after ${timeout} ms waiting for ${what} (last: ${last instanceof Error ? last.message : JSON.stringify(last)})`);
    }
    await sleep(interval);
  }
}

/** Starts `pathstream serve` on the port, serving this checkout's static/. */
export async function startServer(port, { token, backend = "cpu" } = {}) {
  if (!fs.existsSync(BIN)) {
    throw new Error(`no server binary at ${BIN}: build it (cargo build --release) or set PATHSTREAM_BIN`);
  }
  const args = ["serve", "--addr", `127.0.0.1:${port}`, "--backend", backend];
  if (token) args.push("--token", token);
  const env = { ...process.env, PATHSTREAM_STATIC_DIR: STATIC_DIR, RUST_LOG: process.env.RUST_LOG || "warn" };
  delete env.PATHSTREAM_TOKEN;
  const proc = spawn(BIN, args, { env, stdio: ["ignore", "ignore", "pipe"] });
  let log = "";
  proc.stderr.on("data", (d) => { log = (log + d).slice(-8000); });
  running.add(proc);
  const exited = once(proc, "exit");
  exited.then(() => running.delete(proc));
  let died = null;
  proc.on("exit", (code, signal) => { died = `${BIN} exited (${code ?? signal})`; });
  proc.on("error", (e) => { died = `${BIN}: ${e.message}`; });
  const base = `http://127.0.0.1:${port}`;
  try {
    await waitFor(`the server on ${base}`, async () => {
      if (died) throw new Fatal(`${died} before answering; its log: ${log}`);
      const r = await fetch(`${base}/api/health`, { headers: token ? { authorization: `Bearer ${token}` } : {} });
      return r.ok;
    }, { timeout: 30000, interval: 100 });
  } catch (e) {
    proc.kill("SIGKILL");
    throw e;
  }
  return {
    proc,
    base,
    port,
    log: () => log,
    async stop(signal = "SIGTERM") {
      if (proc.exitCode === null && proc.signalCode === null) {
        proc.kill(signal);
        const t = setTimeout(() => proc.kill("SIGKILL"), 5000);
        await exited;
        clearTimeout(t);
      }
    },
  };
}

export async function launchBrowser() {
  if (!fs.existsSync(CHROMIUM)) {
    throw new Error(`no Chromium at ${CHROMIUM}: apt-get install chromium (scripts/browser-tests.sh does)`);
  }
  return chromium.launch({
    executablePath: CHROMIUM,
    args: [
      "--headless",
      "--no-sandbox",
      "--disable-gpu",
      "--disable-background-networking",
      "--disable-component-update",
      "--disable-sync",
      "--no-first-run",
    ],
    timeout: 30000,
  });
}

/** One JSON API call; returns {status, body}. */
/** A server on a free port (`options` as startServer's) and a 1280x720
 *  page in Chromium, with its console watched: what most browser tests
 *  start from. */
export async function openPage(options = {}) {
  const server = await startServer(await freePort(), options);
  const browser = await launchBrowser();
  const page = await browser.newPage({ viewport: { width: 1280, height: 720 } });
  page.setDefaultTimeout(30000);
  return { server, browser, page, errors: watchConsole(page) };
}

export async function api(base, method, route, body, token) {
  const headers = {};
  if (body !== undefined) headers["content-type"] = "application/json";
  if (token) headers.authorization = `Bearer ${token}`;
  const r = await fetch(`${base}/api${route}`, {
    method,
    headers,
    body: body === undefined ? undefined : JSON.stringify(body),
  });
  const text = await r.text();
  let json = null;
  try { json = text ? JSON.parse(text) : null; } catch { json = text; }
  return { status: r.status, body: json };
}

/** GET /api/sessions/{id}, which must succeed. */
export async function session(base, id, token) {
  const r = await api(base, "GET", `/sessions/${id}`, undefined, token);
  if (r.status !== 200) throw new Error(`GET /api/sessions/${id}: ${r.status} ${JSON.stringify(r.body)}`);
  return r.body;
}

/** Records console errors and uncaught exceptions of a page. */
export function watchConsole(page) {
  const errors = [];
  page.on("console", (m) => { if (m.type() === "error") errors.push(`console: ${m.text()}`); });
  page.on("pageerror", (e) => errors.push(`pageerror: ${e.message}`));
  return errors;
}

/** Numbers the page mirrors on <body> (data-frames, data-frame-spp, ...). */
export async function bodyData(page) {
  return page.evaluate(() => ({ ...document.body.dataset }));
}

/** Pins the stream format in the page's panel and, unless it is "auto",
 *  waits for a frame drawn in it. Exact comparisons pin "png": on a loaded
 *  machine auto may measure a slow link and switch to a lossy format
 *  between the frames a test compares. */
export async function pinFormat(page, format, { timeout = 20000 } = {}) {
  await page.selectOption("#stream-format", format);
  if (format === "auto") return;
  await page.waitForFunction((f) => document.body.dataset.frameFormat === f, format, { timeout, polling: 50 });
}

/** Waits until the canvas shows a frame of at least `spp` samples, from a
 *  generation above `after` when given. Returns {spp, generation}. */
export async function waitFrame(page, { spp = 1, after = -1, timeout = 30000 } = {}) {
  const handle = await page.waitForFunction(
    ([spp, after]) => {
      const d = document.body.dataset;
      const s = Number(d.frameSpp);
      const g = Number(d.frameGeneration);
      return d.frameSpp !== undefined && s >= spp && g > after ? { spp: s, generation: g } : null;
    },
    [spp, after],
    { timeout, polling: 50 },
  );
  return handle.jsonValue();
}

/** The canvas as a coarse grid of mean luminances (blocks of `block` px),
 *  whole-image statistics, and the spp and generation of the frame shown. */
export async function canvasStats(page, block = 8) {
  return page.evaluate((block) => {
    const c = document.getElementById("view");
    const { data } = c.getContext("2d").getImageData(0, 0, c.width, c.height);
    const bw = Math.floor(c.width / block);
    const bh = Math.floor(c.height / block);
    const blocks = new Array(bw * bh).fill(0);
    let sum = 0;
    let sum2 = 0;
    const levels = new Set();
    for (let y = 0; y < c.height; y++) {
      for (let x = 0; x < c.width; x++) {
        const i = 4 * (y * c.width + x);
        const l = 0.2126 * data[i] + 0.7152 * data[i + 1] + 0.0722 * data[i + 2];
        sum += l;
        sum2 += l * l;
        levels.add(data[i] << 16 | data[i + 1] << 8 | data[i + 2]);
        const bx = Math.floor(x / block);
        const by = Math.floor(y / block);
        if (bx < bw && by < bh) blocks[by * bw + bx] += l / (block * block);
      }
    }
    const n = c.width * c.height;
    const mean = sum / n;
    const d = document.body.dataset;
    return { spp: Number(d.frameSpp), generation: Number(d.frameGeneration), width: c.width, height: c.height, mean, std: Math.sqrt(Math.max(0, sum2 / n - mean * mean)), colours: levels.size, blocks };
  }, block);
}

/** Mean absolute difference of two block grids. */
export function blockDiff(a, b) {
  if (a.length !== b.length) throw new Error(`block grids differ in size: ${a.length} vs ${b.length}`);
  let d = 0;
  for (let i = 0; i < a.length; i++) d += Math.abs(a[i] - b[i]);
  return d / a.length;
}

/** Halts the session at `spp` samples and waits until the page shows its
 *  last frame. A PATCH of quality.spp restarts the film, which then stops
 *  at exactly `spp` (the mean, with adaptive sampling) and publishes no
 *  more frames: what the page shows then stays, and the server's own
 *  frame.png is that same frame. Returns the halted status. */
export async function haltShown(page, base, id, spp = 8) {
  const r = await api(base, "PATCH", `/sessions/${id}/quality`, { spp });
  if (r.status !== 200) throw new Error(`PATCH quality spp ${spp}: ${r.status} ${JSON.stringify(r.body)}`);
  const s = await waitFor(`the session halted at ${spp} spp`, async () => {
    const s = await session(base, id);
    return s.state === "halted" && s.generation >= r.body.generation ? s : null;
  });
  await waitFor(`the page to show the halted frame (spp ${s.spp}, generation ${s.generation})`, async () => {
    const d = await bodyData(page);
    return Number(d.frameSpp) === s.spp && Number(d.frameGeneration) === s.generation;
  }, { interval: 50 });
  return s;
}

/** Lets a halted session render again (no spp limit); waits until it does. */
export async function resume(base, id) {
  const r = await api(base, "PATCH", `/sessions/${id}/quality`, { spp: null });
  if (r.status !== 200) throw new Error(`PATCH quality spp null: ${r.status} ${JSON.stringify(r.body)}`);
  await waitFor("the session rendering again", async () => (await session(base, id)).state === "rendering");
}

/** What the canvas shows against what the server sent: GET frame.png (which
 *  must be the frame shown: same spp and generation, so halt the session
 *  first), decoded by the browser and drawn at the canvas's size as the page
 *  draws a frame, then each colour channel's mean over `block`x`block`
 *  blocks (the last ones cut short) of both. Returns the worst and mean
 *  absolute difference of those means (0..255), where the worst is, both
 *  images' sizes, and the luminance spread of the server's frame (an image,
 *  not a blank: else a blank canvas would match a blank frame). */
export async function compareWithServerFrame(page, base, id, { block = 8 } = {}) {
  const shown = await bodyData(page);
  const r = await fetch(`${base}/api/sessions/${id}/frame.png`);
  if (r.status !== 200) throw new Error(`GET frame.png: ${r.status} ${await r.text()}`);
  const sent = { spp: Number(r.headers.get("x-pathstream-spp")), generation: Number(r.headers.get("x-pathstream-generation")) };
  if (sent.spp !== Number(shown.frameSpp) || sent.generation !== Number(shown.frameGeneration)) {
    throw new Error(`the server's frame (spp ${sent.spp}, generation ${sent.generation}) is not the one the page says it shows (spp ${shown.frameSpp}, generation ${shown.frameGeneration})`);
  }
  const png = Buffer.from(await r.arrayBuffer()).toString("base64");
  const c = await page.evaluate(async ([png, block]) => {
    const bytes = Uint8Array.from(atob(png), (ch) => ch.charCodeAt(0));
    const bitmap = await createImageBitmap(new Blob([bytes], { type: "image/png" }));
    const view = document.getElementById("view");
    const w = view.width;
    const h = view.height;
    const ref = new OffscreenCanvas(w, h).getContext("2d");
    ref.imageSmoothingEnabled = bitmap.width !== w || bitmap.height !== h;
    ref.drawImage(bitmap, 0, 0, w, h);
    const bw = Math.ceil(w / block);
    const bh = Math.ceil(h / block);
    const means = (data) => {
      const sums = new Float64Array(bw * bh * 3);
      const counts = new Float64Array(bw * bh);
      for (let y = 0; y < h; y++) {
        for (let x = 0; x < w; x++) {
          const b = Math.floor(y / block) * bw + Math.floor(x / block);
          const i = 4 * (y * w + x);
          for (let k = 0; k < 3; k++) sums[3 * b + k] += data[i + k];
          counts[b] += 1;
        }
      }
      return sums.map((s, j) => s / counts[Math.floor(j / 3)]);
    };
    const refData = ref.getImageData(0, 0, w, h).data;
    const a = means(view.getContext("2d").getImageData(0, 0, w, h).data);
    const b = means(refData);
    let worst = 0;
    let at = null;
    let sum = 0;
    for (let j = 0; j < a.length; j++) {
      const d = Math.abs(a[j] - b[j]);
      sum += d;
      if (d > worst) {
        worst = d;
        const k = Math.floor(j / 3);
        at = { x: (k % bw) * block, y: Math.floor(k / bw) * block, channel: "rgb"[j % 3], shown: a[j], sent: b[j] };
      }
    }
    let l1 = 0;
    let l2 = 0;
    for (let i = 0; i < refData.length; i += 4) {
      const l = 0.2126 * refData[i] + 0.7152 * refData[i + 1] + 0.0722 * refData[i + 2];
      l1 += l;
      l2 += l * l;
    }
    const n = w * h;
    return {
      width: w, height: h, frameWidth: bitmap.width, frameHeight: bitmap.height,
      worst, mean: sum / a.length, at, sentStd: Math.sqrt(Math.max(0, l2 / n - (l1 / n) ** 2)),
    };
  }, [png, block]);
  return { ...c, ...sent };
}

/** One line of a comparison for messages and diagnostics. */
export function describeDiff(c) {
  const at = c.at ? ` (worst at block ${c.at.x},${c.at.y} ${c.at.channel}: shown ${c.at.shown.toFixed(1)}, sent ${c.at.sent.toFixed(1)})` : "";
  return `canvas vs the server's frame (spp ${c.spp}, generation ${c.generation}): block means differ by ${c.mean.toFixed(2)} on average, ${c.worst.toFixed(2)} at worst${at}`;
}

/** A rate as the HUD writes it ("0", "950", "12.3 k", "1.85 M"; fmtRate)
 *  read back: its value and how far rounding to the digits shown may have
 *  moved it from the rate it shows. */
export function readRate(text) {
  const m = /^([0-9]+(?:\.([0-9]+))?) ?([kMG]?)$/.exec(text.trim());
  if (!m) throw new Error(`not a rate: ${JSON.stringify(text)}`);
  const unit = { "": 1, k: 1e3, M: 1e6, G: 1e9 }[m[3]];
  return { value: Number(m[1]) * unit, slack: 0.5 * 10 ** -(m[2] ? m[2].length : 0) * unit };
}

/** Whether the HUD's `text` shows the rate `rate` (to the digits shown). */
export function showsRate(text, rate) {
  const { value, slack } = readRate(text);
  return Math.abs(value - rate) <= slack * (1 + 1e-9) + 1e-9;
}

/** Every visible control of the page (top bar, panels, touch pad) that a
 *  user cannot reach: cut off at the sides, hidden under something else, or
 *  outside the viewport with no scrollable panel to bring it in. Scrolls
 *  each control into view as a user would; returns what failed and why. */
export async function unreachableControls(page) {
  return page.evaluate(() => {
    const vw = window.innerWidth;
    const vh = window.innerHeight;
    const slack = 0.5;
    const problems = [];
    const name = (c) => `${c.tagName.toLowerCase()}#${c.id || c.dataset.key || c.textContent.trim()}`;
    const clips = (a) => ["overflow", "overflowX", "overflowY"].some((k) => getComputedStyle(a)[k] !== "visible");
    if (document.scrollingElement.scrollWidth > vw + slack) {
      problems.push(`the page scrolls sideways (${document.scrollingElement.scrollWidth} px wide in ${vw})`);
    }
    const controls = [...document.querySelectorAll("#bar :is(button, input, select), #panels :is(button, input, select), #touchpad button")]
      .filter((c) => c.getClientRects().length > 0); // displayed (not in a hidden element)
    for (const c of controls) {
      c.scrollIntoView({ block: "nearest", inline: "nearest" });
      const r = c.getBoundingClientRect();
      if (r.left < -slack || r.right > vw + slack || r.top < -slack || r.bottom > vh + slack) {
        problems.push(`${name(c)} at ${Math.round(r.left)},${Math.round(r.top)}-${Math.round(r.right)},${Math.round(r.bottom)} is outside the ${vw}x${vh} viewport`);
        continue;
      }
      for (let a = c.parentElement; a && a !== document.body; a = a.parentElement) {
        if (!clips(a)) continue;
        const b = a.getBoundingClientRect();
        const left = b.left + a.clientLeft;
        const top = b.top + a.clientTop;
        if (a.scrollLeft !== 0 || a.scrollWidth > a.clientWidth + 1) {
          problems.push(`#${a.id || a.tagName} scrolls sideways (${a.scrollWidth} px of content in ${a.clientWidth})`);
        }
        if (r.left < left - slack || r.right > left + a.clientWidth + slack || r.top < top - slack || r.bottom > top + a.clientHeight + slack) {
          problems.push(`${name(c)} is cut off by #${a.id || a.tagName}`);
        }
      }
      const x = Math.min(Math.max(r.left + r.width / 2, 0), vw - 1);
      const y = Math.min(Math.max(r.top + r.height / 2, 0), vh - 1);
      const hit = document.elementFromPoint(x, y);
      if (!(hit === c || c.contains(hit) || (hit && hit.control === c) || (hit && hit.tagName === "LABEL" && hit.contains(c)))) {
        problems.push(`${name(c)} is covered by ${hit ? name(hit) : "nothing"}`);
      }
    }
    return { count: controls.length, problems: [...new Set(problems)] };
  });
}
