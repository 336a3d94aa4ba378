// A session on every device (`pathstream serve --backend all`: PoCL and
// rayon here) in the browser: the HUD lists each device with its rate,
// the long device names in its tooltip, and fits on the line.
//
//   node --test tests/browser/devices.test.mjs

import assert from "node:assert/strict";
import { after, before, describe, it } from "node:test";
import { UNDER_CI, haltShown, openPage, showsRate, waitFrame } from "./harness.mjs";

describe("a session on every device in the browser", { timeout: 120000 }, () => {
  let server;
  let browser;
  let page;
  let errors;

  before(async () => {
    ({ server, browser, page, errors } = await openPage({ backend: "all" }));
  });

  after(async () => {
    await browser?.close();
    await server?.stop();
  });

  it("the HUD shows each device's rate", { timeout: 60000 }, async (t) => {
    await page.goto(`${server.base}/?scene=cornell&width=96&height=64`);
    await waitFrame(page, { spp: 4 });
    const id = await page.evaluate(() => window.pathstream.sessionId);
    // Halted, the rates stay put: the HUD must show the status's own.
    const s = await haltShown(page, server.base, id, 16);
    assert.equal(s.backend, "all");
    const n = s.devices.length;
    t.diagnostic(`devices: ${s.devices.map((d) => `${d.backend} ${d.samples_per_sec.toFixed(0)}/s`).join(", ")}`);
    if (UNDER_CI) assert.equal(n, 2, "PoCL and rayon");
    assert.ok(s.samples_per_sec > 0 && s.devices.some((d) => d.samples_per_sec > 0), JSON.stringify(s.devices));
    const text = await page.textContent("#hud-device");
    t.diagnostic(`HUD: ${text}`);
    assert.match(text, /^all: /);
    const parts = text.slice("all: ".length).split(" · ");
    assert.equal(parts.length, n, text);
    parts.forEach((part, i) => {
      const d = s.devices[i];
      const m = /^(cpu|opencl) (.+)$/.exec(part);
      assert.ok(m, `${part} in ${text}`);
      assert.equal(m[1], d.backend, text);
      assert.ok(showsRate(m[2], d.samples_per_sec), `HUD ${part}, status ${d.backend} ${d.samples_per_sec}/s`);
    });
    const sps = await page.textContent("#hud-sps");
    assert.ok(showsRate(sps, s.samples_per_sec), `HUD ${sps} paths/s in all, status ${s.samples_per_sec}`);
    const title = await page.getAttribute("#hud-device", "title");
    assert.match(title, /cpu: rayon/, title);
    // The line fits its box: nothing cut off with an ellipsis.
    const fits = await page.$eval("#hud-device", (e) => e.scrollWidth <= e.clientWidth);
    assert.ok(fits, `the device line overflows: ${text}`);
    assert.deepEqual(errors, []);
  });
});
