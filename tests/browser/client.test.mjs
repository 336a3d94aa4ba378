// The browser client in a real browser (Debian's Chromium via playwright-core)
// against a real `pathstream serve` on 127.0.0.1. Renders are small (128x96)
// so that everything stays quick on a CPU with two cores.
//
//   node --test tests/browser/            (or scripts/browser-tests.sh)
//
// Environment: PATHSTREAM_BIN (server binary, default target/release/pathstream),
// CHROMIUM (default /usr/bin/chromium).

import assert from "node:assert/strict";
import fs from "node:fs";
import path from "node:path";
import { after, before, describe, it } from "node:test";
import {
  ARTIFACTS, STATIC_DIR, api, blockDiff, bodyData, canvasStats, compareWithServerFrame, describeDiff,
  freePort, haltShown, launchBrowser, pinFormat, resume, session, showsRate, sleep, startServer, unreachableControls,
  waitFor, waitFrame, watchConsole,
} from "./harness.mjs";

const SMALL = "width=128&height=96";
const T = { timeout: 60000 };

describe("browser client", { timeout: 600000 }, () => {
  let server;
  let browser;
  let context;
  let page;
  let errors;
  let port;

  const id = () => page.evaluate(() => window.pathstream.sessionId);
  const status = async () => session(server.base, await id());

  before(async () => {
    port = await freePort();
    server = await startServer(port);
    browser = await launchBrowser();
    context = await browser.newContext({ viewport: { width: 1280, height: 720 } });
    page = await context.newPage();
    page.setDefaultTimeout(30000);
    errors = watchConsole(page);
  });

  after(async () => {
    await browser?.close();
    await server?.stop();
  });

  it("serves this checkout's static files, the page's modules included", T, async () => {
    const names = fs.readdirSync(STATIC_DIR, { recursive: true })
      .filter((n) => fs.statSync(path.join(STATIC_DIR, n)).isFile())
      .map((n) => n.split(path.sep).join("/"));
    assert.ok(names.includes("app.js") && names.some((n) => n.startsWith("js/")), `${names}`);
    for (const name of names) {
      const r = await fetch(`${server.base}/${name}`);
      assert.equal(r.status, 200, name);
      if (name.endsWith(".js")) assert.match(r.headers.get("content-type"), /javascript/, name);
      assert.equal(await r.text(), fs.readFileSync(path.join(STATIC_DIR, name), "utf8"),
        `${name} differs from static/${name}: does the server binary support PATHSTREAM_STATIC_DIR?`);
    }
  });

  it("loads without console errors and shows the server's frame; the HUD its figures", T, async (t) => {
    await page.goto(`${server.base}/?scene=cornell&${SMALL}`);
    const f = await waitFrame(page, { spp: 4 });
    assert.ok(f.spp >= 4);
    // Halted, the frame shown stays: the canvas must be the server's own
    // frame.png of it, block for block (PNG both ways: exact), and the HUD
    // must say what the status says of it.
    await pinFormat(page, "png");
    const halted = await haltShown(page, server.base, await id(), 8);
    assert.equal(await page.$eval("body", (b) => b.dataset.frameFormat), "png");
    const c = await compareWithServerFrame(page, server.base, await id());
    t.diagnostic(describeDiff(c));
    assert.deepEqual([c.width, c.height, c.frameWidth, c.frameHeight], [128, 96, 128, 96]);
    assert.ok(c.sentStd > 5, `the server's frame is flat: luminance std ${c.sentStd}`);
    assert.ok(c.worst <= 1, describeDiff(c));
    const hud = async (k) => [await page.textContent(`#hud-${k}`), await page.getAttribute(`#hud-${k}`, "data-value")];
    assert.deepEqual(await hud("spp"), [String(halted.spp), String(halted.spp)]);
    assert.deepEqual(await hud("state"), ["halted", "halted"]);
    const [spsText, sps] = await hud("sps");
    assert.equal(Number(sps), halted.samples_per_sec);
    assert.ok(halted.samples_per_sec > 0 && showsRate(spsText, halted.samples_per_sec), `HUD ${spsText} paths/s, status ${halted.samples_per_sec}`);
    const [errText, err] = await hud("error");
    assert.equal(Number(err), halted.error_estimate);
    assert.equal(errText, `${(100 * halted.error_estimate).toPrecision(3)} %`);
    await resume(server.base, await id());
    await pinFormat(page, "auto");
    const d = await bodyData(page);
    assert.match(d.sessionId, /^[0-9a-f]{16}$/);
    assert.equal(d.conn, "live");
    assert.equal(await page.textContent("#conn"), "live");
    const s = await status();
    assert.equal(s.scene, "cornell");
    assert.equal(s.width, 128);
    assert.equal(s.height, 96);
    assert.equal(await page.inputValue("#scene"), "cornell");
    // The canvas is scaled up by a whole factor, crisply.
    const box = await page.locator("#view").boundingBox();
    assert.ok(box.width >= 128 * 2 && Number.isInteger(box.width / 128), `canvas shown ${box.width} px wide`);
    assert.equal(box.width / 128, box.height / 96);
    assert.equal(await page.$eval("#view", (c) => c.style.imageRendering), "pixelated");
    assert.deepEqual(errors, []);
  });

  it("HUD: spp rises and the error estimate falls", T, async (t) => {
    const read = async () => ({
      spp: Number(await page.getAttribute("#hud-spp", "data-value")),
      err: Number(await page.getAttribute("#hud-error", "data-value")),
      sps: Number(await page.getAttribute("#hud-sps", "data-value")),
      elapsed: Number(await page.getAttribute("#hud-elapsed", "data-value")),
    });
    const first = await waitFor("an error estimate in the HUD", async () => {
      const r = await read();
      return r.spp >= 2 && r.err > 0 ? r : null;
    });
    const later = await waitFor("4x the samples", async () => {
      const r = await read();
      return r.spp >= 4 * first.spp ? r : null;
    }, { timeout: 40000 });
    t.diagnostic(`spp ${first.spp} -> ${later.spp}, error estimate ${first.err.toFixed(4)} -> ${later.err.toFixed(4)}`);
    assert.ok(later.spp > first.spp, `spp ${first.spp} -> ${later.spp}`);
    assert.ok(later.err < first.err, `error estimate ${first.err} -> ${later.err}`);
    assert.ok(later.sps > 0, `samples per second ${later.sps}`);
    assert.ok(later.elapsed > first.elapsed, `elapsed ${first.elapsed} -> ${later.elapsed}`);
    assert.equal(await page.textContent("#hud-state"), "rendering");
    assert.equal(await page.textContent("#hud-res"), "128 × 96");
    assert.match(await page.textContent("#hud-device"), /^cpu: /);
    assert.match(await page.textContent("#hud-error"), /^[0-9.]+ %$/);
    // The chart has drawn something.
    const inked = await page.$eval("#chart", (c) => {
      const d = c.getContext("2d").getImageData(0, 0, c.width, c.height).data;
      let n = 0;
      for (let i = 3; i < d.length; i += 4) if (d[i] > 0) n++;
      return n;
    });
    assert.ok(inked > 200, `chart has ${inked} painted pixels`);
  });

  it("W moves the camera (position and look_at) and changes the image", T, async (t) => {
    await waitFrame(page, { spp: 16 });
    const before = await status();
    const a = await canvasStats(page);
    assert.equal(a.generation, before.generation);
    await waitFrame(page, { spp: 4 * a.spp });
    const a2 = await canvasStats(page);
    assert.equal(a2.generation, a.generation);
    const noise = blockDiff(a.blocks, a2.blocks); // same camera, 4x the samples
    const g0 = before.generation;

    await page.keyboard.press("w");
    const after = await waitFor("the camera to move", async () => {
      const s = await status();
      return s.generation > g0 && s.camera.position[2] !== before.camera.position[2] ? s : null;
    });
    const step = await page.evaluate(() => window.pathstream.moveStep);
    const dp = after.camera.position.map((v, i) => v - before.camera.position[i]);
    const dl = after.camera.look_at.map((v, i) => v - before.camera.look_at[i]);
    assert.ok(dp[2] < 0, `moved toward -z (the view direction): ${dp}`);
    assert.ok(Math.abs(Math.hypot(...dp) - step) < 1e-6 * step, `moved ${Math.hypot(...dp)}, step ${step}`);
    dp.forEach((v, i) => assert.ok(Math.abs(v - dl[i]) < 1e-9, `look_at moved with the position: ${dp} vs ${dl}`));
    assert.equal(after.camera.near_clip, before.camera.near_clip);

    await waitFrame(page, { spp: a2.spp, after: g0 });
    const b = await canvasStats(page);
    assert.ok(b.generation > g0);
    const moved = blockDiff(a2.blocks, b.blocks);
    t.diagnostic(`image change after W: ${moved.toFixed(2)} (8x8 block means, 0..255); noise at the same camera: ${noise.toFixed(2)}`);
    // Two renders of one camera differ by less than `noise` (measured at
    // fewer samples than b has); the moved camera must differ by far more.
    assert.ok(moved > 2 * noise + 1, `image change ${moved.toFixed(2)} vs noise ${noise.toFixed(2)}`);
  });

  it("2 switches to the glass scene, 1 back", T, async () => {
    await page.keyboard.press("2");
    await waitFor("scene cornell-glass", async () => (await status()).scene === "cornell-glass");
    await waitFor("the scene list to follow", async () => (await page.inputValue("#scene")) === "cornell-glass");
    await page.keyboard.press("1");
    await waitFor("scene cornell", async () => (await status()).scene === "cornell");
    // A scene from the list (not a thesis key).
    const names = await page.$$eval("#scene option", (os) => os.map((o) => o.value));
    assert.deepEqual(names, ["cornell", "cornell-glass", "cornell-quads", "smallpt", "furnace"]);
    await page.selectOption("#scene", "smallpt");
    await waitFor("scene smallpt", async () => (await status()).scene === "smallpt");
    // A light key pressed while the scene change is on its way applies to the
    // new scene's light, not to the old one's (smallpt's light is elsewhere).
    const cornellLight = [50, 66.6, 81.6];
    await page.keyboard.press("1");
    await page.keyboard.press("p");
    const s = await waitFor("cornell with a coloured light", async () => {
      const s = await status();
      return s.scene === "cornell" && s.light.color.some((c) => c < 0.99) ? s : null;
    });
    assert.deepEqual(s.light.position, cornellLight);
    assert.equal(s.light.intensity, 12);
    await waitFor("the page to show the same colour", async () => {
      const shown = await page.inputValue("#l-color");
      const want = "#" + s.light.color.map((c) => Math.round(c * 255).toString(16).padStart(2, "0")).join("");
      return shown === want;
    });
    // Choosing a scene again restores its light.
    await page.selectOption("#scene", "cornell");
    await waitFor("cornell's white light again", async () => {
      const s = await status();
      return s.scene === "cornell" && s.light.color.every((c) => c === 1);
    });
  });

  it("P changes the light colour, M raises the intensity, I/U move the light", T, async () => {
    const before = await status();
    assert.deepEqual(before.light.color, [1, 1, 1]);
    await page.keyboard.press("p");
    const after = await waitFor("a new light colour", async () => {
      const s = await status();
      return s.light.color.some((c, i) => Math.abs(c - before.light.color[i]) > 1e-3) ? s : null;
    });
    assert.ok(Math.abs(Math.max(...after.light.color) - 1) < 1e-6, `colour ${after.light.color}`);
    assert.ok(Math.abs(after.light.intensity - before.light.intensity) < 1e-6);
    const shown = await page.inputValue("#l-color");
    assert.notEqual(shown, "#ffffff");

    await page.keyboard.press("m");
    const brighter = await waitFor("a brighter light", async () => {
      const s = await status();
      return s.light.intensity > after.light.intensity * 1.1 ? s : null;
    });
    assert.ok(Math.abs(brighter.light.intensity / after.light.intensity - 1.25) < 1e-6);

    await page.keyboard.press("u");
    const up = await waitFor("the light to rise", async () => {
      const s = await status();
      return s.light.position[1] > before.light.position[1] ? s : null;
    });
    assert.equal(up.light.position[0], before.light.position[0]);
    await page.keyboard.press("o");
    await waitFor("the light back down", async () => {
      const s = await status();
      return Math.abs(s.light.position[1] - before.light.position[1]) < 1e-9 ? s : null;
    });
  });

  it("lens panel: aperture and focus reach the server's camera; a bad value is named", T, async () => {
    const before = await status();
    assert.equal(before.camera.aperture ?? 0, 0, "a pinhole to begin with");
    assert.equal(await page.inputValue("#c-aperture"), "0");
    await page.fill("#c-aperture", "1.5");
    await page.press("#c-aperture", "Tab");
    await waitFor("aperture 1.5 on the server", async () => (await status()).camera.aperture === 1.5);
    await page.fill("#c-focus", "120");
    await page.press("#c-focus", "Tab");
    await waitFor("focus 120 on the server", async () => (await status()).camera.focus_distance === 120);
    await page.fill("#c-aperture", "-1");
    await page.press("#c-aperture", "Tab");
    await page.waitForSelector("#message:not([hidden])");
    assert.match(await page.textContent("#message-text"), /camera\.aperture/);
    await page.click("#message-close");
    assert.equal((await status()).camera.aperture, 1.5, "a refused value changes nothing");
    assert.equal(await page.inputValue("#c-aperture"), "1.5", "the panel shows the kept value");
    await page.fill("#c-aperture", "0");
    await page.press("#c-aperture", "Tab");
    await waitFor("a pinhole again", async () => (await status()).camera.aperture === 0);
  });

  it("lens panel: a double-click focuses on the surface under the cursor; f-number and projection reach the server", T, async () => {
    // The server's own answer for the image's centre (cornell: the back
    // wall, one depth across it).
    const s0 = await status();
    const r = await fetch(`${server.base}/api/sessions/${await id()}/pick?x=${s0.width / 2}&y=${s0.height / 2}`);
    const centre = await r.json();
    assert.equal(centre.hit, true, "the centre shows a surface");
    await page.dblclick("#view");
    await waitFor("the focus on the surface under the cursor", async () => {
      const f = (await status()).camera.focus_distance;
      return f != null && Math.abs(f - centre.focus_distance) < 1e-3 * centre.focus_distance;
    });
    assert.match(await page.textContent("#c-pick"), /focused at/);
    const bad = await fetch(`${server.base}/api/sessions/${await id()}/pick?x=-5&y=1`);
    assert.equal(bad.status, 400);
    assert.match((await bad.json()).error, /^x: /);

    await page.fill("#c-fnumber", "2.8");
    await page.press("#c-fnumber", "Tab");
    await waitFor("f/2.8 on the server", async () => (await status()).camera.f_number === 2.8);
    await page.fill("#c-aperture", "0.5");
    await page.press("#c-aperture", "Tab");
    await waitFor("the aperture replacing it", async () => {
      const c = (await status()).camera;
      return c.aperture === 0.5 && c.f_number == null;
    });
    await page.selectOption("#c-projection", "panorama");
    await waitFor("a panorama on the server", async () => (await status()).camera.projection === "panorama");
    assert.equal((await status()).camera.aperture, 0, "a panorama has no lens");
    await waitFor("the panel to offer no lens either", async () => page.isDisabled("#c-aperture"));
    await page.selectOption("#c-projection", "orthographic");
    await waitFor("orthographic on the server", async () => (await status()).camera.projection === "orthographic");
    assert.ok((await status()).camera.ortho_height > 0, "with the server's default height");
    await page.selectOption("#c-projection", "perspective");
    await waitFor("perspective again", async () => {
      const c = (await status()).camera;
      return c.projection == null && c.ortho_height == null;
    });
  });

  it("quality panel: max depth reaches the server, a bad value shows the server's error", T, async () => {
    const before = await status();
    assert.notEqual(before.quality.max_depth, 3);
    await page.fill("#q-max-depth", "3");
    await page.press("#q-max-depth", "Tab");
    await waitFor("max_depth 3 on the server", async () => (await status()).quality.max_depth === 3);

    await page.selectOption("#q-filter", "box");
    await waitFor("filter box on the server", async () => (await status()).quality.filter === "box");
    assert.equal(await page.inputValue("#q-sampler"), "sobol", "the default sampler shows");
    await page.selectOption("#q-sampler", "random");
    await waitFor("sampler random on the server", async () => (await status()).quality.sampler === "random");
    await page.selectOption("#q-sampler", "sobol");
    await waitFor("sampler sobol again", async () => (await status()).quality.sampler === "sobol");
    await page.uncheck("#q-nee");
    await waitFor("nee off on the server", async () => (await status()).quality.nee === false);
    await page.check("#q-nee");
    await waitFor("nee on again", async () => (await status()).quality.nee === true);

    // A halt condition: the HUD says halted.
    await page.fill("#q-spp", "16");
    await page.press("#q-spp", "Tab");
    await waitFor("spp halt on the server", async () => (await status()).quality.spp === 16);
    await waitFor("the HUD to say halted", async () => (await page.textContent("#hud-state")) === "halted");
    assert.equal(Number(await page.getAttribute("#hud-spp", "data-value")), 16);
    await page.fill("#q-spp", "");
    await page.press("#q-spp", "Tab");
    await waitFor("no spp halt", async () => (await status()).quality.spp === null);
    await waitFor("rendering again", async () => (await page.textContent("#hud-state")) === "rendering");

    await page.fill("#q-rr-depth", "200000");
    await page.press("#q-rr-depth", "Tab");
    await page.waitForSelector("#message:not([hidden])");
    assert.match(await page.textContent("#message-text"), /rr_depth/);
    const s = await status();
    assert.equal(s.quality.rr_depth, before.quality.rr_depth, "a refused value changes nothing");
    await waitFor("the panel to show the server's value again",
      async () => (await page.inputValue("#q-rr-depth")) === String(before.quality.rr_depth));
    await page.click("#message-close");
    // Chromium logs the refused request; that one is expected.
    const refused = errors.filter((e) => /status of 400/.test(e));
    assert.equal(refused.length, 1, JSON.stringify(errors));
    errors.splice(errors.indexOf(refused[0]), 1);
  });

  it("quality panel: a preset sets the knobs; editing one shows custom", T, async () => {
    const presets = (await (await fetch(`${server.base}/api/presets`)).json()).presets;
    const reference = presets.find((p) => p.name === "reference");
    await page.waitForSelector("#q-preset option[value=reference]", { state: "attached" });
    await page.selectOption("#q-preset", "reference");
    await waitFor("the reference preset on the server", async () => {
      const q = (await status()).quality;
      return q.max_depth === reference.quality.max_depth && q.clamp === reference.quality.clamp;
    });
    await waitFor("the panel to show the preset's depth",
      async () => (await page.inputValue("#q-max-depth")) === String(reference.quality.max_depth));
    assert.equal(await page.inputValue("#q-preset"), "reference");
    await page.fill("#q-max-depth", "3");
    await page.press("#q-max-depth", "Tab");
    await waitFor("max_depth 3 on the server", async () => (await status()).quality.max_depth === 3);
    await waitFor("the preset to read custom", async () => (await page.inputValue("#q-preset")) === "");
    await page.evaluate(() => document.activeElement.blur()); // keys go to the view again
  });

  it("help overlay opens with ? and H, closes with Escape", T, async () => {
    assert.equal(await page.isVisible("#help"), false);
    await page.keyboard.press("?");
    assert.equal(await page.isVisible("#help"), true);
    assert.match(await page.textContent("#help"), /random light colour/);
    await page.keyboard.press("Escape");
    assert.equal(await page.isVisible("#help"), false);
    await page.keyboard.press("h");
    assert.equal(await page.isVisible("#help"), true);
    await page.keyboard.press("h");
    assert.equal(await page.isVisible("#help"), false);
  });

  it("touch pad buttons and dragging the image move and turn the camera", T, async () => {
    await page.click("#btn-touch");
    assert.equal(await page.isVisible("#touchpad"), true);
    const before = await status();
    await page.click('#touchpad [data-key="KeyW"]');
    const moved = await waitFor("the camera to move", async () => {
      const s = await status();
      return s.camera.position[2] < before.camera.position[2] ? s : null;
    });
    const box = await page.locator("#view").boundingBox();
    const cx = box.x + box.width / 2;
    const cy = box.y + box.height / 2;
    await page.mouse.move(cx, cy);
    await page.mouse.down();
    for (let i = 1; i <= 5; i++) await page.mouse.move(cx + 20 * i, cy, { steps: 2 });
    await page.mouse.up();
    const turned = await waitFor("the view to turn", async () => {
      const s = await status();
      return s.camera.look_at[0] !== moved.camera.look_at[0] ? s : null;
    });
    assert.deepEqual(turned.camera.position, moved.camera.position, "looking does not move the camera");
    assert.ok(turned.camera.look_at[0] < moved.camera.look_at[0], "dragging right turns left (the image follows the finger)");
    // R: back to the scene's camera (the test starts from it: the last
    // scene change reset the camera).
    await page.keyboard.press("r");
    await waitFor("the camera reset", async () => {
      const s = await status();
      return JSON.stringify(s.camera) === JSON.stringify(before.camera);
    });
    await page.click("#btn-touch");
    assert.equal(await page.isVisible("#touchpad"), false);
  });

  it("copy curl gives a script that makes the same session", T, async () => {
    await page.click("#btn-curl");
    await page.waitForSelector("#curl-dialog:not([hidden])");
    const script = await page.inputValue("#curl-text");
    const s = await status();
    assert.match(script, /-X POST '.*\/api\/sessions'/);
    const create = JSON.parse(script.match(/ -d '(\{"scene".*?\})' \|/)[1]);
    assert.equal(create.scene, s.scene);
    assert.equal(create.width, 128);
    assert.deepEqual(create.quality, s.quality);
    assert.match(script, /\/camera"/);
    assert.match(script, /frame\.png\?min_spp=/);
    await page.click("#curl-close");
    assert.equal(await page.isVisible("#curl-dialog"), false);
  });

  it("PNG and PFM buttons download the current frame", T, async () => {
    for (const [button, magic] of [["#btn-png", "\x89PNG"], ["#btn-pfm", "PF\n"]]) {
      const [download] = await Promise.all([page.waitForEvent("download"), page.click(button)]);
      const file = await download.path();
      const head = fs.readFileSync(file).subarray(0, magic.length).toString("latin1");
      assert.equal(head, magic, `${button} downloaded ${download.suggestedFilename()}`);
    }
  });

  it("reconnects after the server is killed and restarted on the same port", T, async () => {
    const oldId = await id();
    const frames = Number((await bodyData(page)).frames);
    assert.deepEqual(errors, [], "no console errors before the restart");
    await server.stop("SIGKILL");
    await page.waitForFunction(() => document.body.dataset.conn === "reconnecting", null, { timeout: 10000 });
    assert.match(await page.textContent("#conn"), /reconnecting/);
    await sleep(1500); // a few failed attempts while the server is down
    server = await startServer(port);
    await page.waitForFunction(() => document.body.dataset.conn === "live", null, { timeout: 20000 });
    const newId = await id();
    assert.notEqual(newId, oldId, "the restarted server has forgotten the old session; the page opened a new one");
    assert.match(await page.textContent("#message-text"), /no longer had session/);
    await page.waitForFunction((n) => Number(document.body.dataset.frames) > n, frames, { timeout: 20000 });
    const s = await status();
    assert.equal(s.scene, "cornell");
    assert.equal(s.width, 128);
    assert.equal(s.quality.max_depth, 3, "settings carried over to the new session");
    // What it shows is the new session's frames. PNG pinned: on a loaded
    // machine the link measured just after the restart can be slow enough
    // that auto picks a lossy format, and this check is exact.
    await pinFormat(page, "png");
    await haltShown(page, server.base, newId, 8);
    assert.equal(await page.$eval("body", (b) => b.dataset.frameFormat), "png");
    const c = await compareWithServerFrame(page, server.base, newId);
    assert.ok(c.sentStd > 5 && c.worst <= 1, `renders again: ${describeDiff(c)}`);
    await pinFormat(page, "auto");
    // Only the connection failures while the server was down were logged.
    const unexpected = errors.filter((e) => !/ERR_CONNECTION_REFUSED|WebSocket connection to .* failed|Failed to load resource/.test(e));
    assert.deepEqual(unexpected, []);
  });
});

describe("browser client with a token", { timeout: 120000 }, () => {
  const TOKEN = "s3cret-token";
  let server;
  let browser;

  before(async () => {
    server = await startServer(await freePort(), { token: TOKEN });
    browser = await launchBrowser();
  });
  after(async () => {
    await browser?.close();
    await server?.stop();
  });

  it("asks for the token once and keeps it for the tab", T, async () => {
    const context = await browser.newContext({ viewport: { width: 1280, height: 720 } });
    const page = await context.newPage();
    await page.goto(`${server.base}/?${SMALL}`);
    await page.waitForSelector("#token-dialog:not([hidden])");
    await page.fill("#token-input", "wrong");
    await page.press("#token-input", "Enter");
    await page.waitForSelector("#token-dialog:not([hidden])");
    await waitFor("the refused token to be noticed", async () => /refused/.test(await page.textContent("#token-reason")));
    await page.fill("#token-input", TOKEN);
    await page.press("#token-input", "Enter");
    await waitFrame(page, { spp: 1 });
    const id = await page.evaluate(() => window.pathstream.sessionId);
    const s = await session(server.base, id, TOKEN);
    assert.equal(s.scene, "cornell-glass", "the default scene");
    assert.equal((await api(server.base, "GET", `/sessions/${id}`)).status, 401, "the server does want the token");
    assert.equal(await page.evaluate(() => sessionStorage.getItem("pathstream.token")), TOKEN);
    await page.reload();
    await waitFrame(page, { spp: 1 });
    assert.equal(await page.isVisible("#token-dialog"), false, "not asked again in the same tab");
    await context.close();
  });
});

describe("layout and screenshots", { timeout: 300000 }, () => {
  let server;
  let browser;

  before(async () => {
    server = await startServer(await freePort());
    browser = await launchBrowser();
  });
  after(async () => {
    await browser?.close();
    await server?.stop();
  });

  it("at 1280x720 the default resolution fits the window; saves target/browser/page.png", T, async () => {
    const page = await browser.newPage({ viewport: { width: 1280, height: 720 } });
    const errors = watchConsole(page);
    await page.goto(server.base);
    await waitFrame(page, { spp: 1 });
    const id = await page.evaluate(() => window.pathstream.sessionId);
    const s = await session(server.base, id);
    assert.equal(s.scene, "cornell-glass");
    const area = await page.locator("#viewport").boundingBox();
    const px = Number(await page.inputValue("#px"));
    assert.ok(Math.abs(s.width * px - area.width) <= px && Math.abs(s.height * px - area.height) <= px,
      `${s.width}x${s.height} at 1:${px} in a ${area.width}x${area.height} area`);
    const bar = await page.locator("#bar").boundingBox();
    assert.ok(bar.height < 60, `the top bar fits on one line (${bar.height} px)`);
    await waitFor("a few seconds of samples", async () => Number((await bodyData(page)).frameSpp) >= 24, { timeout: 60000 });
    fs.mkdirSync(ARTIFACTS, { recursive: true });
    await page.screenshot({ path: path.join(ARTIFACTS, "page.png") });
    assert.ok(fs.statSync(path.join(ARTIFACTS, "page.png")).size > 10000);
    assert.deepEqual(errors, []);
    await page.close();
  });

  const sizes = [
    { width: 1920, height: 1080 },
    { width: 1280, height: 720 },
    // A phone: touch, a coarse pointer (larger controls, the touch pad on).
    { width: 390, height: 844, phone: true },
  ];
  for (const size of sizes) {
    const label = `${size.width}x${size.height}`;
    it(`at ${label} every control is on screen or in a scrollable panel; saves target/browser/page-${label}.png`, T, async () => {
      const context = await browser.newContext({
        viewport: { width: size.width, height: size.height },
        ...(size.phone ? { isMobile: true, hasTouch: true, deviceScaleFactor: 3 } : {}),
      });
      const page = await context.newPage();
      const errors = watchConsole(page);
      await page.goto(`${server.base}/?scene=cornell&${SMALL}`);
      await waitFrame(page, { spp: 4 });
      await page.waitForSelector("#q-preset option[value=reference]", { state: "attached" });
      if (size.phone) assert.equal(await page.isVisible("#touchpad"), true, "a phone gets the touch pad");
      fs.mkdirSync(ARTIFACTS, { recursive: true });
      await page.screenshot({ path: path.join(ARTIFACTS, `page-${label}.png`) });
      const { count, problems } = await unreachableControls(page);
      // Top bar 9, quality 11, light 2, export 3; the touch pad's 16 on a phone.
      assert.ok(count >= (size.phone ? 41 : 25), `only ${count} controls found`);
      assert.deepEqual(problems, [], `${label}: ${problems.join("; ")}`);
      if (!size.phone) {
        const bar = await page.locator("#bar").boundingBox();
        assert.ok(bar.height < 60, `the top bar fits on one line (${bar.height} px)`);
      }
      assert.deepEqual(errors, []);
      await context.close();
    });
  }
});
