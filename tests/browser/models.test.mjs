// Model files in the browser: an OBJ dropped on the page is uploaded, the
// session switches to it and frames it, and the frame shows it at the
// radiance a closed form gives; a broken file picked with the button is
// refused with the server's message and leaves the session as it was.
//
//   node --test tests/browser/models.test.mjs

import assert from "node:assert/strict";
import fs from "node:fs";
import path from "node:path";
import { after, before, describe, it } from "node:test";
import { REPO, canvasStats, openPage, session, waitFor, waitFrame } from "./harness.mjs";

const T = { timeout: 90000 };

/** A closed cube of side 2 about the origin, 12 outward-facing triangles. */
function cubeObj() {
  const v = [];
  for (let i = 0; i < 8; i++) v.push(`v ${i & 1 ? 1 : -1} ${i & 2 ? 1 : -1} ${i & 4 ? 1 : -1}`);
  // Faces as corner quads (1-based), counter-clockwise seen from outside.
  const quads = [[1, 3, 4, 2], [5, 6, 8, 7], [1, 2, 6, 5], [3, 7, 8, 4], [1, 5, 7, 3], [2, 4, 8, 6]];
  const f = quads.flatMap(([a, b, c, d]) => [`f ${a} ${b} ${c}`, `f ${a} ${c} ${d}`]);
  return [...v, ...f].join("\n") + "\n";
}

/** sRGB of linear radiance, as the server's PNG encodes it. */
const srgb = (v) => 255 * (v <= 0.0031308 ? 12.92 * v : 1.055 * v ** (1 / 2.4) - 0.055);

describe("model files in the browser", { timeout: 300000 }, () => {
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

  const id = () => page.evaluate(() => window.pathstream.sessionId);

  it("an OBJ dropped on the page renders, framed, at the closed-form radiance", T, async () => {
    await page.goto(`${server.base}/?scene=cornell&width=64&height=48`);
    const first = await waitFrame(page, { spp: 2 });
    const before = await id();
    await page.evaluate((text) => {
      const dt = new DataTransfer();
      dt.items.add(new File([text], "cube.obj", { type: "model/obj" }));
      const target = document.getElementById("view");
      for (const type of ["dragenter", "dragover", "drop"]) {
        target.dispatchEvent(new DragEvent(type, { dataTransfer: dt, bubbles: true, cancelable: true }));
      }
    }, cubeObj());
    await waitFor("the upload to finish", async () => (await page.evaluate(() => document.body.dataset.upload)) === "done");
    assert.equal(await id(), before, "the same session switched scene");
    const s = await session(server.base, before);
    assert.equal(s.scene, "custom");
    assert.ok(s.warnings.some((w) => /environment/.test(w)), JSON.stringify(s.warnings));
    assert.ok(s.warnings.some((w) => /framed/.test(w)), JSON.stringify(s.warnings));
    assert.equal(await page.$eval("#scene", (e) => e.selectedOptions[0].textContent), "cube.obj");
    assert.match(await page.textContent("#message-text"), /cube\.obj: 12 triangles/);
    const assets = await (await fetch(`${server.base}/api/assets`)).json();
    assert.equal(assets.assets.length, 1);
    assert.equal(assets.assets[0].name, "cube.obj");

    // A convex diffuse object under a uniform sky of radiance 1 sees only
    // sky: its radiance is its albedo (0.8, the default material), the
    // sky's 1. The frame's centre shows the cube, its corner the sky.
    await waitFrame(page, { spp: 16, after: first.generation });
    const img = await canvasStats(page, 8);
    const bw = img.width / 8;
    const centre = (img.blocks[2 * bw + 3] + img.blocks[2 * bw + 4] + img.blocks[3 * bw + 3] + img.blocks[3 * bw + 4]) / 4;
    const corner = img.blocks[0];
    assert.ok(Math.abs(centre - srgb(0.8)) < 4, `centre ${centre.toFixed(1)}, expected ${srgb(0.8).toFixed(1)} (albedo 0.8)`);
    assert.ok(corner > 254, `corner ${corner.toFixed(1)}, expected the sky (255)`);
    assert.deepEqual(errors, []);
  });

  it("a broken file picked with the button is refused by name; the session keeps its scene", T, async () => {
    const gen = Number(await page.evaluate(() => document.body.dataset.generation));
    await page.setInputFiles("#model-file", {
      name: "broken.ply",
      mimeType: "application/octet-stream",
      buffer: Buffer.from("ply\nformat ascii 1.0\nelement vertex 1\nend_header\n"),
    });
    await waitFor("the refusal", async () => (await page.evaluate(() => document.body.dataset.upload)) === "failed");
    assert.match(await page.textContent("#message-text"), /broken\.ply/);
    assert.equal(await page.isVisible("#message"), true);
    const s = await session(server.base, await id());
    assert.equal(s.scene, "custom");
    assert.equal(s.generation, gen, "nothing changed");
    // The console shows the refused request (400); nothing else.
    const unexpected = errors.filter((e) => !/status of 400/.test(e));
    assert.deepEqual(unexpected, []);
  });

  it("back to a built-in scene and to the model again from the scene picker", T, async () => {
    const before = await id();
    await page.selectOption("#scene", "cornell");
    await waitFor("cornell", async () => (await session(server.base, before)).scene === "cornell");
    await page.selectOption("#scene", "custom");
    await waitFor("the model again", async () => (await session(server.base, before)).scene === "custom");
    assert.equal(await page.$eval("#scene", (e) => e.selectedOptions[0].textContent), "cube.obj");
  });

  it("an .hdr dropped on the page lights the scene; the environment panel picks built-in maps, intensity, rotation, visibility", T, async () => {
    const sid = await id();
    const hdr = fs.readFileSync(path.join(REPO, "server/tests/data/sunset-64.hdr"));
    await page.evaluate((bytes) => {
      const dt = new DataTransfer();
      dt.items.add(new File([new Uint8Array(bytes)], "sunset-64.hdr"));
      const target = document.getElementById("view");
      for (const type of ["dragenter", "dragover", "drop"]) {
        target.dispatchEvent(new DragEvent(type, { dataTransfer: dt, bubbles: true, cancelable: true }));
      }
    }, [...hdr]);
    await waitFor("the map's upload", async () => (await session(server.base, sid)).environment_name === "sunset-64.hdr");
    const uploaded = (await session(server.base, sid)).environment.map;
    assert.match(uploaded, /^[0-9a-f]{64}$/);
    // The HUD follows the session's next state message, not the upload's reply.
    await waitFor("the HUD names the map", async () => (await page.textContent("#hud-env")) === "sunset-64.hdr");
    assert.equal((await session(server.base, sid)).scene, "custom", "the model stays");

    // A built-in map from the menu.
    const builtin = await (await fetch(`${server.base}/api/environments`)).json();
    const studio = builtin.maps.find((m) => m.name === "studio");
    assert.ok(studio, JSON.stringify(builtin));
    await page.focus("#e-map");
    await waitFor("the menu's built-in maps", async () => (await page.$$eval("#e-map option", (o) => o.map((x) => x.value))).includes(studio.id));
    await page.selectOption("#e-map", studio.id);
    await waitFor("the studio map", async () => (await session(server.base, sid)).environment.map === studio.id);
    assert.equal((await session(server.base, sid)).environment_name, "studio");

    await page.fill("#e-intensity", "2");
    await page.press("#e-intensity", "Tab");
    await waitFor("intensity 2", async () => (await session(server.base, sid)).environment.intensity === 2);
    await page.fill("#e-rotation", "90");
    await page.press("#e-rotation", "Tab");
    await waitFor("rotation 90", async () => (await session(server.base, sid)).environment.rotation_deg === 90);
    const shown = Number(await page.evaluate(() => document.body.dataset.generation));
    await page.uncheck("#e-visible");
    await waitFor("a hidden map", async () => (await session(server.base, sid)).environment.visible === false);
    // Hidden: the corner (sky) shows black; the cube, lit by the map, does not.
    const hidden = (await session(server.base, sid)).generation;
    assert.ok(hidden > shown);
    await waitFrame(page, { spp: 4, after: hidden - 1 });
    const img = await canvasStats(page, 8);
    assert.ok(img.blocks[0] < 1, `corner ${img.blocks[0]}: the hidden map shows black`);
    const bw = img.width / 8;
    assert.ok(img.blocks[3 * bw + 3] > 10, "the cube is lit by the map");

    await page.fill("#e-intensity", "-1");
    await page.press("#e-intensity", "Tab");
    await page.waitForSelector("#message:not([hidden])");
    assert.match(await page.textContent("#message-text"), /environment\.intensity/);
    assert.equal((await session(server.base, sid)).environment.intensity, 2, "a refused value changes nothing");

    await page.selectOption("#e-map", "");
    await waitFor("a uniform colour again", async () => Array.isArray((await session(server.base, sid)).environment));
    assert.deepEqual((await session(server.base, sid)).environment, [1, 1, 1]);
    // The page learns of the change from the status stream, a moment after the server.
    await waitFor("the HUD's map row hidden", async () => page.isHidden("#hud-env-row"));
  });

  it("sun & sky from the environment menu; the sun's elevation and azimuth move it", T, async () => {
    const sid = await id();
    await page.selectOption("#e-map", "sun & sky");
    await waitFor("a sky", async () => (await session(server.base, sid)).environment?.sky != null);
    assert.equal((await session(server.base, sid)).environment_name, "sky");
    await waitFor("the HUD names it", async () => (await page.textContent("#hud-env")) === "sky");
    await waitFor("the sun's inputs enabled", async () => !(await page.isDisabled("#e-sun-elevation")));
    await page.fill("#e-sun-elevation", "10");
    await page.press("#e-sun-elevation", "Tab");
    await waitFor("the sun at 10 degrees", async () => (await session(server.base, sid)).environment.sky.sun_elevation_deg === 10);
    await page.fill("#e-sun-azimuth", "270");
    await page.press("#e-sun-azimuth", "Tab");
    await waitFor("the sun in the west", async () => (await session(server.base, sid)).environment.sky.sun_azimuth_deg === 270);
    assert.equal((await session(server.base, sid)).environment.sky.sun_elevation_deg, 10, "the elevation stays");
    await page.fill("#e-sun-elevation", "120");
    await page.press("#e-sun-elevation", "Tab");
    await waitFor("the refusal", async () => /environment\.sky\.sun_elevation_deg/.test(await page.textContent("#message-text")));
    assert.equal((await session(server.base, sid)).environment.sky.sun_elevation_deg, 10, "a refused value changes nothing");
    await page.selectOption("#e-map", "");
    await waitFor("a uniform colour again", async () => Array.isArray((await session(server.base, sid)).environment));
    // The page learns it from the status that follows, a moment later.
    await waitFor("the sun's inputs disabled", () => page.isDisabled("#e-sun-elevation"));
  });
});
