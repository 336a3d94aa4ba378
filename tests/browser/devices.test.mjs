// A session on every device (`pathstream serve --backend all`: PoCL and
// rayon here) in the browser: the HUD lists each device with its rate,
// the long device names in its tooltip, and fits on the line.
//
//   node --test tests/browser/devices.test.mjs

import assert from "node:assert/strict";
import { after, before, describe, it } from "node:test";
import { UNDER_CI, openPage, session, waitFor, waitFrame } from "./harness.mjs";

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
    const s = await session(server.base, id);
    assert.equal(s.backend, "all");
    const n = s.devices.length;
    t.diagnostic(`devices: ${s.devices.map((d) => `${d.backend} ${d.samples_per_sec.toFixed(0)}/s`).join(", ")}`);
    if (UNDER_CI) assert.equal(n, 2, "PoCL and rayon");
    const text = await waitFor("every device in the HUD", async () => {
      const v = await page.textContent("#hud-device");
      return v.split(" · ").length === n && /^all: cpu /.test(v) ? v : null;
    });
    for (const part of text.slice("all: ".length).split(" · ")) {
      assert.match(part, /^(cpu|opencl) [0-9.]+ ?[kMG]?$/, text);
    }
    const title = await page.getAttribute("#hud-device", "title");
    assert.match(title, /cpu: rayon/, title);
    // The line fits its box: nothing cut off with an ellipsis.
    const fits = await page.$eval("#hud-device", (e) => e.scrollWidth <= e.clientWidth);
    assert.ok(fits, `the device line overflows: ${text}`);
    assert.deepEqual(errors, []);
  });
});
