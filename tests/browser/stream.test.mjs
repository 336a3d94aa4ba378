// The frame stream in the browser: the page acknowledges frames (so the
// server measures the link and the HUD shows it), the stream format can be
// pinned in the quality panel, and progressive frames (narrower than the
// session, just after a change) are stretched over the whole canvas. Also,
// under node alone, the auto format's decision (static/js/streamfmt.js).
//
//   node --test tests/browser/stream.test.mjs

import assert from "node:assert/strict";
import { after, before, describe, it } from "node:test";
import { chooseFormat, neededMbps } from "../../static/js/streamfmt.js";
import {
  api, canvasStats, compareWithServerFrame, describeDiff, haltShown, openPage, resume, session, waitFor, waitFrame,
} from "./harness.mjs";

const W = 128;
const H = 96;
const T = { timeout: 90000 };
// How far a WebP frame's 8x8 block means (per channel, 0..255) may stray
// from the server's PNG of the same frame: on average, and at worst (the
// test's 8 spp frame measured 0.7 and 4.8; the same view at other spp, an
// old frame left on the canvas, differs by about as much, hence the light).
const WEBP_MEAN = 2;
const WEBP_WORST = 12;

describe("auto stream format (pure decision)", () => {
  const base = { current: "png", linkMbps: 40, frameBytes: 100_000, pngBytes: 100_000, sinceSwitchMs: 10_000 };

  it("needs 8 Mbit/s for 10 frames/s of 100 kB", () => {
    assert.equal(neededMbps(100_000), 8);
  });

  it("keeps PNG until the link is measured, and while it carries 10 fps", () => {
    assert.equal(chooseFormat({ ...base, linkMbps: null }), "png");
    assert.equal(chooseFormat({ ...base, linkMbps: 8 }), "png");
  });

  it("switches to JPEG when 10 fps of PNG need more than the link", () => {
    assert.equal(chooseFormat({ ...base, linkMbps: 7.9 }), "jpeg");
  });

  it("goes back to PNG only with a 2x margin (hysteresis)", () => {
    const jpeg = { ...base, current: "jpeg", frameBytes: 20_000 };
    assert.equal(chooseFormat({ ...jpeg, linkMbps: 12 }), "jpeg", "PNG would fit, but not twice");
    assert.equal(chooseFormat({ ...jpeg, linkMbps: 16 }), "png");
    assert.equal(chooseFormat({ ...jpeg, linkMbps: 100, pngBytes: null }), "jpeg", "no PNG size known");
  });

  it("switches at most once every 3 s", () => {
    assert.equal(chooseFormat({ ...base, linkMbps: 1, sinceSwitchMs: 2999 }), "png");
    assert.equal(chooseFormat({ ...base, linkMbps: 1, sinceSwitchMs: 3000 }), "jpeg");
  });
});

describe("the frame stream in the browser", { timeout: 300000 }, () => {
  let server;
  let browser;
  let page;
  let errors;

  const id = () => page.evaluate(() => window.pathstream.sessionId);
  const status = async () => session(server.base, await id());
  // The server measures the link (stats with `link_mbps`, null or not) and
  // sends progressive frames; a binary built before them is a failure here,
  // never a quiet skip.
  const serverMeasuresLink = () => page.evaluate(async () => {
    const ws = new WebSocket(`ws://${location.host}/api/sessions/${window.pathstream.sessionId}/ws`);
    const stats = await new Promise((resolve, reject) => {
      ws.onmessage = (e) => { if (typeof e.data === "string") resolve(JSON.parse(e.data)); };
      ws.onerror = () => reject(new Error("probe socket failed"));
    });
    ws.close();
    return "link_mbps" in stats;
  });
  const streamData = () => page.$eval("#hud-stream", (e) => ({ ...e.dataset, text: e.textContent }));

  before(async () => {
    ({ server, browser, page, errors } = await openPage());
    await page.goto(`${server.base}/?scene=cornell&width=${W}&height=${H}`);
    await waitFrame(page, { spp: 1 });
    assert.ok(
      await serverMeasuresLink(),
      `the server binary (${process.env.PATHSTREAM_BIN || "target/release/pathstream"}) predates acknowledgements and progressive frames: rebuild it`,
    );
  });

  after(async () => {
    await browser?.close();
    await server?.stop();
  });

  it("acknowledges frames: the HUD shows the link's rate", T, async (t) => {
    const d = await waitFor("a link rate in the HUD", async () => {
      const d = await streamData();
      return d.linkMbps !== "" && Number(d.linkMbps) > 0 ? d : null;
    });
    t.diagnostic(`HUD stream: ${d.text}`);
    assert.equal(await page.isVisible("#hud-stream"), true);
    assert.match(d.text, /^png \d+ KB · \d+ fps · [0-9.e+]+ Mbit\/s · \d+ ms$/);
    assert.ok(Number(d.deliveryMs) >= 0, `delivery ${d.deliveryMs} ms`);
    // Over loopback PNG at this size fits: auto keeps it.
    assert.equal(d.format, "png");
  });

  it("pinning jpeg or webp in the panel streams it; png brings it back", T, async (t) => {
    await page.selectOption("#stream-format", "jpeg");
    await waitFor("a JPEG frame", async () => (await streamData()).format === "jpeg");
    assert.equal(await page.$eval("body", (b) => b.dataset.streamFormat), "jpeg");
    await page.selectOption("#stream-format", "webp");
    await waitFor("a WebP frame on the canvas", async () =>
      (await page.$eval("body", (b) => b.dataset.frameFormat)) === "webp");
    // The WebP frame drawn is the server's image: halted, the canvas shows
    // the last frame, which must match the server's PNG of it block for
    // block, up to what lossy WebP (quality 85, 4:2:0) moves an 8x8 mean.
    // An orange light first: no frame shown before looks like this one (an
    // old PNG frame of the same view left on the canvas would pass).
    const sid = await id();
    const white = (await status()).light.color;
    const lit = await api(server.base, "PATCH", `/sessions/${sid}/light`, { color: [1, 0.5, 0.1] });
    assert.equal(lit.status, 200, JSON.stringify(lit.body));
    await haltShown(page, server.base, sid, 8);
    assert.equal(await page.$eval("body", (b) => b.dataset.frameFormat), "webp");
    const c = await compareWithServerFrame(page, server.base, sid);
    t.diagnostic(describeDiff(c));
    assert.deepEqual([c.width, c.height, c.frameWidth, c.frameHeight], [W, H, W, H]);
    assert.ok(c.sentStd > 5, `the server's frame is flat: luminance std ${c.sentStd}`);
    assert.ok(c.mean <= WEBP_MEAN && c.worst <= WEBP_WORST, describeDiff(c));
    assert.equal((await api(server.base, "PATCH", `/sessions/${sid}/light`, { color: white })).status, 200);
    await resume(server.base, sid);
    await page.selectOption("#stream-format", "png");
    await waitFor("a PNG frame", async () => (await streamData()).format === "png");
    await page.selectOption("#stream-format", "auto");
  });

  it("after a camera move, progressive frames arrive and fill the canvas", T, async (t) => {
    const narrow0 = Number((await page.$eval("body", (b) => b.dataset.narrowFrames)) || 0);
    const g0 = (await status()).generation;
    await page.keyboard.press("w");
    await waitFor("a progressive frame (narrower than the session)", async () => {
      const n = Number((await page.$eval("body", (b) => b.dataset.narrowFrames)) || 0);
      return n > narrow0;
    });
    const shown = await waitFrame(page, { spp: 1, after: g0 });
    const c = await canvasStats(page);
    t.diagnostic(`generation ${shown.generation}: canvas ${c.width}x${c.height}, mean ${c.mean.toFixed(1)}`);
    assert.equal(c.width, W, "the canvas keeps the session's width");
    assert.equal(c.height, H, "the canvas keeps the session's height");
    // Stretched, not drawn small in a corner: every side of the canvas has
    // image, not a blank band (the Cornell box is lit wall to wall).
    const bw = Math.floor(W / 8);
    const bh = Math.floor(H / 8);
    const right = c.blocks.filter((_, i) => i % bw === bw - 1);
    const bottom = c.blocks.slice((bh - 1) * bw);
    assert.ok(Math.max(...right) > 5, `right column of blocks is blank: ${right.map((v) => v.toFixed(0))}`);
    assert.ok(Math.max(...bottom) > 5, `bottom row of blocks is blank: ${bottom.map((v) => v.toFixed(0))}`);
    // The frames end whole: the last one is the session's width.
    await waitFor("a whole-width frame", async () => Number(await page.$eval("body", (b) => b.dataset.frameWidth)) === W);
  });

  it("a frame smaller than the session is stretched over the whole canvas", T, async () => {
    // The live stream must be quiet first: a frame arriving while the test's
    // own frame is drawn (or a draw already in flight) would cover it. A
    // halted session publishes no more frames.
    const sid = await id();
    const r0 = await api(server.base, "PATCH", `/sessions/${sid}/quality`, { spp: 2 });
    assert.equal(r0.status, 200, `PATCH quality: ${JSON.stringify(r0.body)}`);
    await waitFor("the session halted", async () => (await status()).state === "halted");
    await waitFor("the page idle (no frame being drawn or waiting)", () => page.evaluate(async () => {
      const { state } = await import("/js/state.js");
      return !state.decoding && !state.pendingFrame;
    }));
    // A quarter-width frame, as progressive streaming sends first, handed to
    // the page's own drawing (the same module instances as the page's).
    const r = await page.evaluate(async ([w, h]) => {
      const { state } = await import("/js/state.js");
      const { drawFrames } = await import("/js/view.js");
      const small = new OffscreenCanvas(w / 4, h / 4);
      const g = small.getContext("2d");
      g.fillStyle = "#ff0000";
      g.fillRect(0, 0, small.width, small.height);
      const blob = await small.convertToBlob({ type: "image/png" });
      state.pendingFrame = { blob, stats: null };
      await drawFrames();
      const c = document.getElementById("view");
      const d = c.getContext("2d").getImageData(0, 0, c.width, c.height).data;
      let red = 0;
      for (let i = 0; i < d.length; i += 4) if (d[i] > 200 && d[i + 1] < 50 && d[i + 2] < 50) red++;
      return { width: c.width, height: c.height, red, pixels: d.length / 4 };
    }, [W, H]);
    assert.equal(r.width, W, "the canvas keeps the session's width");
    assert.equal(r.height, H, "the canvas keeps the session's height");
    assert.equal(r.red, r.pixels, `the small frame covers ${r.red} of ${r.pixels} pixels`);
  });

  it("no console errors", () => {
    assert.deepEqual(errors, []);
  });
});
