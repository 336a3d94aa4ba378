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
