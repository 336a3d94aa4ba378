// Adaptive sampling in the browser: the quality panel's toggle reaches the
// server, the HUD shows how the samples spread over the pixels, and the
// samples overlay shows the server's map (one pixel per 2x2 tile) over the
// image, refreshed with the frames but throttled.
//
//   node --test tests/browser/adaptive.test.mjs

import assert from "node:assert/strict";
import { after, before, describe, it } from "node:test";
import { bodyData, haltShown, openPage, resume, session, sleep, waitFor, waitFrame } from "./harness.mjs";

// Not multiples of the tile: the last column and row of tiles are cut short.
// Odd sizes: the last column and row of tiles are cut short.
const W = 101;
const H = 61;
const TILE = 2;
const T = { timeout: 90000 };

describe("adaptive sampling in the browser", { timeout: 300000 }, () => {
  let server;
  let browser;
  let page;
  let errors;

  const id = () => page.evaluate(() => window.pathstream.sessionId);
  const status = async () => session(server.base, await id());

  before(async () => {
    ({ server, browser, page, errors } = await openPage());
  });

  after(async () => {
    await browser?.close();
    await server?.stop();
  });

  it("the adaptive toggle reaches the server; the HUD shows the spread", T, async (t) => {
    await page.goto(`${server.base}/?scene=cornell&width=${W}&height=${H}`);
    await waitFrame(page, { spp: 2 });
    const before = await status();
    assert.equal(before.quality.adaptive, false);
    assert.equal(await page.isChecked("#q-adaptive"), false);
    assert.equal(await page.isVisible("#hud-spread"), false, "no spread while sampling is uniform");

    await page.check("#q-adaptive");
    const on = await waitFor("adaptive on the server", async () => {
      const s = await status();
      return s.quality.adaptive === true ? s : null;
    });
    assert.ok(on.generation > before.generation, "the change restarted the film");
    assert.equal(on.tile_size, TILE);
    assert.equal(on.tiles, Math.ceil(W / TILE) * Math.ceil(H / TILE));

    // After the uniform warm-up (16 spp everywhere) the tiles' counts part.
    const spread = await waitFor("a spread in the HUD", async () => {
      if (!(await page.isVisible("#hud-spread"))) return null;
      const d = await page.$eval("#hud-spread", (e) => ({ ...e.dataset, text: e.textContent }));
      const [min, median, max] = [d.min, d.median, d.max].map(Number);
      return min >= 16 && max > min ? { min, median, max, text: d.text } : null;
    }, { timeout: 40000 });
    t.diagnostic(`HUD spread: ${spread.text}`);
    assert.ok(spread.min <= spread.median && spread.median <= spread.max, JSON.stringify(spread));
    assert.equal(spread.text, `${spread.min} / ${spread.median} / ${spread.max}`);
    assert.match(await page.textContent("#hud-spp"), /^\d+ \(mean\)$/);
    const s = await status();
    assert.ok(s.spp_spread.min >= 16 && s.spp_spread.max > s.spp_spread.min, JSON.stringify(s.spp_spread));
    assert.equal(await page.isVisible("#hud-tiles"), false, "no error target: no tiles to count");

    // With an error target, the HUD counts the tiles that reached their share.
    await page.fill("#q-target", "5");
    await page.press("#q-target", "Tab");
    await waitFor("the target on the server", async () => (await status()).quality.target_error === 0.05);
    const tiles = await waitFor("tiles in the HUD", async () => {
      if (!(await page.isVisible("#hud-tiles"))) return null;
      return page.textContent("#hud-tiles");
    });
    assert.match(tiles, new RegExp(`^\\d+ / ${on.tiles}$`));
    await page.fill("#q-target", "");
    await page.press("#q-target", "Tab");
    await waitFor("no target", async () => (await status()).quality.target_error === null);
    await page.evaluate(() => document.activeElement.blur());
  });

  it("show samples: the server's map over the image, one pixel per tile, refreshed at most every 500 ms", T, async (t) => {
    const starts = [];
    let open = 0;
    let mostOpen = 0;
    const isMap = (r) => new URL(r.url()).pathname.endsWith("/samples.png");
    page.on("request", (r) => {
      if (!isMap(r)) return;
      starts.push(Date.now());
      open += 1;
      mostOpen = Math.max(mostOpen, open);
    });
    const finished = (r) => { if (isMap(r)) open -= 1; };
    page.on("requestfinished", finished);
    page.on("requestfailed", finished);

    assert.equal(await page.isVisible("#samples-overlay"), false);
    await page.check("#show-samples");
    await waitFor("the map to load", () => page.$eval("#samples", (i) => i.complete && i.naturalWidth > 0 && Number(i.dataset.loads) >= 1));
    const size = await page.$eval("#samples", (i) => [i.naturalWidth, i.naturalHeight]);
    assert.deepEqual(size, [Math.ceil(W / TILE), Math.ceil(H / TILE)]);

    // Over the image: the overlay's box is the canvas's; the map inside it
    // is whole tiles, clipped where the image's last tiles are cut short.
    const view = await page.locator("#view").boundingBox();
    const box = await page.locator("#samples-overlay").boundingBox();
    for (const k of ["x", "y", "width", "height"]) {
      assert.ok(Math.abs(view[k] - box[k]) <= 1, `overlay ${k} ${box[k]}, image ${view[k]}`);
    }
    const map = await page.$eval("#samples", (i) => ({ width: i.offsetWidth, height: i.offsetHeight }));
    const scale = view.width / W;
    assert.ok(Math.abs(map.width - size[0] * TILE * scale) <= 1, `map ${map.width} px wide at ${scale} px per pixel`);
    assert.ok(Math.abs(map.height - size[1] * TILE * scale) <= 1, `map ${map.height} px high`);
    const look = await page.$eval("#samples", (i) => {
      const c = getComputedStyle(i);
      return { rendering: c.imageRendering, opacity: Number(c.opacity), pointer: getComputedStyle(i.parentElement).pointerEvents };
    });
    assert.equal(look.rendering, "pixelated");
    assert.ok(look.opacity > 0.2 && look.opacity < 0.9, `opacity ${look.opacity}`);
    assert.equal(look.pointer, "none", "the overlay lets the mouse through to the image");

    // New frames bring new maps, but no more than one per 500 ms and one
    // request at a time: watched over the next three maps, however long
    // this machine takes to render the frames they follow.
    const loads = () => page.$eval("#samples", (i) => Number(i.dataset.loads));
    const frames = async () => Number((await bodyData(page)).frames);
    const [loads0, frames0, n0, t0] = [await loads(), await frames(), starts.length, Date.now()];
    await waitFor("three more maps as frames arrive", async () => (await loads()) >= loads0 + 3, { timeout: 30000 });
    t.diagnostic(`in ${Date.now() - t0} ms: ${(await frames()) - frames0} frames, ${starts.length - n0} map requests, ${(await loads()) - loads0} maps shown`);
    const gaps = starts.slice(1).map((s, i) => s - starts[i]);
    assert.ok(Math.min(...gaps) >= 400, `requests ${gaps.join(", ")} ms apart`);
    assert.equal(mostOpen, 1, "one request at a time");

    // Halted, the map shown must be the server's samples.png of the last
    // frame, pixel for pixel (the page asks again after the last frame),
    // and the HUD's spread the status's. Past the warm-up the tiles' counts
    // differ: more than one colour.
    const sid = await id();
    const halted = await haltShown(page, server.base, sid, 40);
    const r = await fetch(`${server.base}/api/sessions/${sid}/samples.png`);
    assert.equal(r.status, 200);
    assert.deepEqual([r.headers.get("x-pathstream-spp"), r.headers.get("x-pathstream-generation")].map(Number), [halted.spp, halted.generation]);
    const png = Buffer.from(await r.arrayBuffer()).toString("base64");
    let seen = null;
    const same = await waitFor("the overlay to show the server's map of the halted frame", async () => {
      seen = await page.$eval("#samples", async (i, png) => {
        const pixels = async (src) => {
          const b = await createImageBitmap(src);
          const g = new OffscreenCanvas(b.width, b.height).getContext("2d");
          g.drawImage(b, 0, 0);
          return { size: [b.width, b.height], data: g.getImageData(0, 0, b.width, b.height).data };
        };
        const bytes = Uint8Array.from(atob(png), (ch) => ch.charCodeAt(0));
        const sent = await pixels(new Blob([bytes], { type: "image/png" }));
        const shown = await pixels(i);
        const colours = new Set();
        let differ = 0;
        for (let k = 0; k < sent.data.length; k += 4) {
          colours.add((sent.data[k] << 16) | (sent.data[k + 1] << 8) | sent.data[k + 2]);
          if ([0, 1, 2, 3].some((c) => sent.data[k + c] !== shown.data[k + c])) differ += 1;
        }
        return { sent: sent.size, shown: shown.size, differ, colours: colours.size };
      }, png);
      return seen.differ === 0 && String(seen.shown) === String(seen.sent) ? seen : null;
    }, { timeout: 5000 }).catch((e) => { throw new Error(`${e.message}; last seen: ${JSON.stringify(seen)}`); });
    assert.deepEqual(same.sent, [Math.ceil(W / TILE), Math.ceil(H / TILE)]);
    const spread = halted.spp_spread;
    assert.ok(spread.max > spread.min && same.colours > 1, `spread ${JSON.stringify(spread)}, ${same.colours} colours in the map`);
    assert.equal(await page.textContent("#hud-spread"), `${spread.min} / ${spread.median} / ${spread.max}`);
    assert.equal(await page.textContent("#hud-spp"), `${halted.spp} (mean)`);
    // No new frame, no new map: the requests stop once the last frame's
    // is done (it may wait up to 500 ms behind the one before).
    await waitFor("the map requests to stop with the frames (none for 800 ms)",
      () => open === 0 && Date.now() - starts.at(-1) >= 800, { timeout: 5000 });
    const nHalted = starts.length;
    await sleep(700);
    assert.equal(starts.length, nHalted, "no map requests while no frames come");
    await resume(server.base, sid);

    // Off: hidden, and no more requests.
    await page.uncheck("#show-samples");
    assert.equal(await page.isVisible("#samples-overlay"), false);
    await sleep(200);
    const n1 = starts.length;
    await sleep(1500);
    assert.equal(starts.length, n1, "no requests with the overlay off");
    await page.evaluate(() => document.activeElement.blur());
  });

  it("a preset sets adaptive, and the toggle follows", T, async () => {
    await page.waitForSelector("#q-preset option[value=final]", { state: "attached" });
    await page.selectOption("#q-preset", "preview");
    await waitFor("preview on the server", async () => {
      const q = (await status()).quality;
      return q.adaptive === false && q.max_depth === 2;
    });
    await waitFor("the toggle off", async () => !(await page.isChecked("#q-adaptive")));
    await waitFor("no spread in the HUD", async () => !(await page.isVisible("#hud-spread")));
    assert.equal(await page.textContent("#hud-spread-row dt"), "min/med/max");

    await page.selectOption("#q-preset", "final");
    await waitFor("final on the server", async () => {
      const q = (await status()).quality;
      return q.adaptive === true && q.max_depth === 0;
    });
    await waitFor("the toggle on", async () => page.isChecked("#q-adaptive"));
    assert.equal(await page.inputValue("#q-preset"), "final");
    await page.evaluate(() => document.activeElement.blur());
    assert.deepEqual(errors, []);
  });
});
