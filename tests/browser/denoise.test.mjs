// Denoising in the browser: the quality panel's toggle reaches the server,
// the HUD says whether the frame shown is denoised, V shows the raw image
// and back, and the denoised image is smoother than the raw one at the
// same samples (pixel-to-pixel differences, measured on the canvas).
//
//   node --test tests/browser/denoise.test.mjs
//
// Needs Open Image Denoise where the server runs (PATHSTREAM_OIDN, which
// scripts/test.sh sets); under CI its absence fails the test.

import assert from "node:assert/strict";
import { after, before, describe, it } from "node:test";
import { UNDER_CI, api, openPage, pinFormat, session, waitFor } from "./harness.mjs";

/** Mean absolute luminance difference of horizontally adjacent pixels on
 *  the canvas (0..255): the image's pixel noise; the spp shown and whether
 *  the frame drawn is denoised (the HUD's status may come a frame ahead of
 *  the canvas). */
function roughness(page) {
  return page.evaluate(() => {
    const c = document.getElementById("view");
    const { data } = c.getContext("2d").getImageData(0, 0, c.width, c.height);
    const lum = (i) => 0.2126 * data[i] + 0.7152 * data[i + 1] + 0.0722 * data[i + 2];
    let sum = 0;
    for (let y = 0; y < c.height; y++) {
      for (let x = 1; x < c.width; x++) {
        const i = 4 * (y * c.width + x);
        sum += Math.abs(lum(i) - lum(i - 4));
      }
    }
    const d = document.body.dataset;
    return { rough: sum / (c.height * (c.width - 1)), spp: Number(d.frameSpp), denoised: d.frameDenoised === "true" };
  });
}

describe("denoising in the browser", { timeout: 180000 }, () => {
  let server;
  let browser;
  let page;
  let errors;

  before(async () => {
    ({ server, browser, page, errors } = await openPage());
  });

  after(async () => {
    await browser?.close();
    await server?.stop();
  });

  it("the toggle denoises the image, the HUD says so, and V shows the raw one", { timeout: 120000 }, async (t) => {
    const devices = (await api(server.base, "GET", "/devices")).body;
    if (!devices.denoiser || !devices.denoiser.available) {
      const why = devices.denoiser ? devices.denoiser.reason : "no denoiser field";
      if (UNDER_CI) assert.fail(`CI is set but the server cannot denoise: ${why}`);
      t.skip(`no denoiser: ${why}`);
      return;
    }
    await page.goto(`${server.base}/?scene=cornell&width=128&height=96`);
    const id = await waitFor("a session", () => page.evaluate(() => window.pathstream.sessionId));
    // PNG pinned: on a loaded machine auto may switch to a lossy format
    // between the frames compared, and lossy coding changes roughness.
    await pinFormat(page, "png");
    assert.equal(await page.inputValue("#q-denoise"), "off");
    assert.ok(await page.isHidden("#hud-denoise-row"), "no image row while the session does not denoise");

    // Denoise the final frame too, and halt early: the last frame stays.
    await page.selectOption("#q-denoise", "final");
    await waitFor("denoise final on the server", async () => (await session(server.base, id)).quality.denoise === "final");
    await page.fill("#q-spp", "4");
    await page.press("#q-spp", "Tab");
    await waitFor("the HUD to say halted", async () => (await page.textContent("#hud-state")) === "halted");
    await waitFor("the HUD to say denoised", async () => (await page.getAttribute("#hud-denoise", "data-value")) === "denoised");
    const frame = (denoised) => async () => {
      const r = await roughness(page);
      return r.spp === 4 && r.denoised === denoised ? r : null;
    };
    const clean = await waitFor("the halted frame, denoised, on the canvas", frame(true));

    // Keys drive the view once no field has the focus.
    await page.evaluate(() => document.activeElement && document.activeElement.blur());
    await page.keyboard.press("v");
    await waitFor("the HUD to say raw", async () => (await page.getAttribute("#hud-denoise", "data-value")) === "raw");
    const raw = await waitFor("the same frame, raw, on the canvas", frame(false));
    t.diagnostic(`pixel-to-pixel differences at 4 spp: raw ${raw.rough.toFixed(2)}, denoised ${clean.rough.toFixed(2)} (0..255)`);
    // On failure, the server's log too: it warns of a denoised image whose
    // mean moved far from its input's (a flat frame was seen once, 2026-12-07).
    const log = () => `; the server's log: ${server.log().slice(-3000) || "(empty)"}`;
    assert.ok(raw.rough > 2 * clean.rough, `raw ${raw.rough.toFixed(2)} is not twice as rough as denoised ${clean.rough.toFixed(2)}${log()}`);

    await page.keyboard.press("v");
    await waitFor("the HUD to say denoised again", async () => (await page.getAttribute("#hud-denoise", "data-value")) === "denoised");
    const again = await waitFor("the denoised frame again on the canvas", frame(true));
    assert.ok(Math.abs(again.rough - clean.rough) < 0.05 * clean.rough + 0.01, `denoised again: ${again.rough} vs ${clean.rough}${log()}`);

    await page.selectOption("#q-denoise", "off");
    await waitFor("denoise off on the server", async () => (await session(server.base, id)).quality.denoise === "off");
    await waitFor("the image row hidden", () => page.isHidden("#hud-denoise-row"));
    assert.deepEqual(errors, []);
  });
});
