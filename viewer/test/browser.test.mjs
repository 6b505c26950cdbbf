// The web viewer and the evaluation report in Debian's Chromium (headless, software WebGL):
//  - for every exported method and test light, the viewer's canvas pixels equal photomat's own CPU
//    relighting (`photomat relight`) within a mean absolute difference of 2/255;
//  - the viewer's controls move the light, switch methods and views, zoom;
//  - the report loads with no console error and shows one chart per method;
//  - the deep-zoom viewer fetches only the tiles in view and relights them as photomat does;
//  - screenshots of both land in the screenshot folder for a person to look at.
import { after, before, describe, test } from 'node:test';
import assert from 'node:assert/strict';
import { readFileSync } from 'node:fs';
import path from 'node:path';
import { PNG } from 'pngjs';
import { launchBrowser, loadFixtures, openPage, readPng, screenshotFolder, serve } from './support.mjs';

const fixtures = loadFixtures();
const screenshots = screenshotFolder(fixtures);
const MAX_MEAN_DIFFERENCE = 2 / 255;

let server;
let browser;
before(async () => {
  server = await serve(fixtures.out);
  browser = await launchBrowser();
});
after(async () => {
  await browser?.close();
  await server?.close();
});

// Mean and largest absolute difference over the RGB channels, in units of full scale.
function compare(canvas, reference) {
  assert.equal(canvas.width, reference.width);
  assert.equal(canvas.height, reference.height);
  let sum = 0;
  let largest = 0;
  for (let p = 0; p < canvas.width * canvas.height; ++p) {
    for (let c = 0; c < 3; ++c) {
      const d = Math.abs(canvas.rgba[4 * p + c] - reference.data[4 * p + c]);
      sum += d;
      largest = Math.max(largest, d);
    }
  }
  return { mean: sum / (canvas.width * canvas.height * 3) / 255, largest: largest / 255 };
}

// A neural decoder costs thousands of operations per fragment, and SwiftShader shades on the CPU:
// its viewers open in a smaller page, so that the fitted views stay cheap to draw.
const NEURAL_VIEWPORT = { width: 520, height: 400 };
const viewportFor = (methods) => (methods.includes('neural') ? NEURAL_VIEWPORT : undefined);

async function openViewer(viewer) {
  const opened = await openPage(browser, server.url + viewer.url, viewportFor(viewer.methods));
  await opened.page.evaluate(() => window.photomatViewer.ready);
  return opened;
}

for (const viewer of fixtures.viewers) {
  describe(`viewer "${viewer.name}"`, () => {
    let page;
    let problems;
    before(async () => {
      ({ page, problems } = await openViewer(viewer));
    });
    after(() => page.close());

    test('loads with WebGL2 and its light bases match photomat on every check light', async () => {
      assert.deepEqual(await page.evaluate(() => window.photomatViewer.methods()), viewer.methods);
      const checks = await page.evaluate(() => window.photomatViewer.checks());
      for (const check of checks) {
        assert.ok(check.ok, `${check.method}: basis differs from photomat by ${check.maxError} (tolerance ${check.tolerance})`);
        assert.ok(check.lights >= 65, `${check.method}: only ${check.lights} check lights`);
      }
      console.log(`  ${viewer.name}: ${checks.map((c) => `${c.method} ${c.maxError.toExponential(1)}`).join(', ')}`);
      assert.deepEqual(problems, []);
    });

    for (const method of viewer.compared) {
      test(`${method}: canvas pixels match photomat relight within 2/255`, async () => {
        await page.evaluate((m) => window.photomatViewer.setMethod(m), method);
        await page.evaluate(() => window.photomatViewer.setView('relit'));
        const results = [];
        for (const comparison of viewer.comparisons.filter((c) => c.method === method)) {
          const canvas = await page.evaluate(({ slant, tilt }) => {
            const v = window.photomatViewer;
            v.setLight(slant, tilt);
            v.actualPixels();
            return v.readImagePixels();
          }, comparison);
          const difference = compare(canvas, readPng(comparison.reference));
          results.push({ light: `${comparison.slant},${comparison.tilt}`, ...difference });
        }
        console.log(`  ${viewer.name} ${method}: ${results.map((r) => `(${r.light}) mean ${(r.mean * 255).toFixed(3)}/255 max ${(r.largest * 255).toFixed(0)}/255`).join('; ')}`);
        for (const r of results) {
          assert.ok(r.mean < MAX_MEAN_DIFFERENCE, `${method} at ${r.light}: mean difference ${(r.mean * 255).toFixed(3)}/255`);
        }
        assert.deepEqual(problems, []);
      });
    }

    test('screenshots', async () => {
      for (const method of viewer.methods.filter((m) => ['ptm', 'eigen6', 'gradient'].includes(m)).slice(0, 2)) {
        await page.evaluate((m) => window.photomatViewer.setMethod(m), method);
        await page.evaluate(() => {
          window.photomatViewer.setLight(55, 135);
          window.photomatViewer.fit();
        });
        await page.evaluate(() => new Promise((r) => requestAnimationFrame(() => r())));
        await page.screenshot({ path: path.join(screenshots, `viewer-${viewer.name}-${method}.png`) });
      }
      for (const view of (await page.evaluate(() => window.photomatViewer.views())).filter((v) => v !== 'relit')) {
        await page.evaluate((v) => window.photomatViewer.setView(v), view);
        await page.evaluate(() => new Promise((r) => requestAnimationFrame(() => r())));
        await page.screenshot({ path: path.join(screenshots, `viewer-${viewer.name}-${view}.png`) });
      }
      await page.evaluate(() => window.photomatViewer.setView('relit'));
      assert.deepEqual(problems, []);
    });
  });
}

describe('viewer controls', () => {
  const viewer = fixtures.viewers.find((v) => v.name === 'grid');
  let page;
  let problems;
  before(async () => {
    ({ page, problems } = await openViewer(viewer));
  });
  after(() => page.close());

  test('dragging on the light disc sets slant and tilt', async () => {
    const disc = await page.evaluate(() => window.photomatViewer.lightDisc());
    const centre = [disc.x, disc.y];
    const radius = disc.radius; // the rim: slant 90
    // Half way to the rim, straight up: slant 45, tilt 90.
    await page.mouse.move(centre[0], centre[1]);
    await page.mouse.down();
    await page.mouse.move(centre[0], centre[1] - radius / 2, { steps: 4 });
    await page.mouse.up();
    const state = await page.evaluate(() => window.photomatViewer.state());
    assert.ok(Math.abs(state.slant - 45) < 1.5, `slant ${state.slant}`);
    assert.ok(Math.abs(state.tilt - 90) < 1.5, `tilt ${state.tilt}`);
    const readout = await page.locator('#light-readout').textContent();
    assert.match(readout, /slant 4[4-6]\.\d°, tilt (8[9]|9[01])\.\d°/);
  });

  test('dragging on the image moves the light toward the cursor', async () => {
    const box = await page.locator('#view').boundingBox();
    const centre = [box.x + box.width / 2, box.y + box.height / 2];
    await page.mouse.move(centre[0] - 100, centre[1]);
    await page.mouse.down();
    await page.mouse.move(centre[0] - 200, centre[1] + 1, { steps: 3 });
    await page.mouse.up();
    const state = await page.evaluate(() => window.photomatViewer.state());
    assert.ok(Math.abs(state.tilt - 180) < 2, `tilt ${state.tilt}`); // to the left
    assert.ok(state.slant > 30 && state.slant < 90, `slant ${state.slant}`);
  });

  test('typed slant and tilt, the method menu, the view buttons and the wheel', async () => {
    await page.fill('#slant-input', '60');
    await page.fill('#tilt-input', '300');
    let state = await page.evaluate(() => window.photomatViewer.state());
    assert.ok(Math.abs(state.slant - 60) < 1e-9 && Math.abs(state.tilt - 300) < 1e-9);
    await page.selectOption('#method', 'eigen6');
    await page.waitForFunction(() => window.photomatViewer.state().method === 'eigen6');
    await page.check('#views input[value="normal"]');
    state = await page.evaluate(() => window.photomatViewer.state());
    assert.equal(state.view, 'normal');
    await page.check('#views input[value="relit"]');
    const before = state.zoom;
    const box = await page.locator('#view').boundingBox();
    await page.mouse.move(box.x + box.width / 2, box.y + box.height / 2);
    await page.mouse.wheel(0, -400);
    await page.waitForFunction((z) => window.photomatViewer.state().zoom > z * 1.5, before);
    await page.click('#zoom-1');
    assert.equal((await page.evaluate(() => window.photomatViewer.state())).zoom, 1);
    await page.screenshot({ path: path.join(screenshots, 'viewer-grid-controls.png') });
    assert.deepEqual(problems, []);
  });
});

// The deep-zoom viewer (README "Web viewer and evaluation report"): the tiles each view needs are
// fetched and no others, and the relit tiles reproduce photomat's relighting at level 0 and its
// box average at level 1.
for (const deep of fixtures.deepzoom) describe(`deep-zoom viewer "${deep.name}"`, () => {
  const manifest = JSON.parse(readFileSync(path.join(deep.folder, 'viewer.json'), 'utf8'));
  // A method's pyramid, or a view's (normal, albedo, height).
  const pyramid = (name) => [...manifest.methods, ...manifest.views].find((m) => m.name === name).data.pyramid;
  let page;
  let problems;
  const requests = [];
  before(async () => {
    ({ page, problems } = await openPage(browser, server.url + deep.url, viewportFor(deep.methods)));
    page.on('request', (request) => {
      const match = /\/maps\/(?:views\/)?([^/]+)\/levels\/(\d+)\/(\d+)_(\d+)\.f32$/.exec(request.url());
      if (match) requests.push({ method: match[1], level: +match[2], column: +match[3], row: +match[4] });
    });
    await page.evaluate(() => window.photomatViewer.ready);
    await page.waitForFunction(() => window.photomatViewer.tilesPending() === 0);
  });
  after(() => page.close());

  // Sets the view, then waits until every tile it wants has loaded; the requests it made.
  async function showAt(zoom, origin) {
    const first = requests.length;
    await page.evaluate(({ z, o }) => window.photomatViewer.setZoomOrigin(z, o), { z: zoom, o: origin });
    await page.waitForFunction(() => window.photomatViewer.tilesPending() === 0);
    return requests.slice(first);
  }

  async function selectMethod(method) {
    const first = requests.length;
    await page.evaluate((m) => window.photomatViewer.setMethod(m), method);
    await page.waitForFunction(() => window.photomatViewer.tilesPending() === 0);
    return requests.slice(first);
  }

  // The tiles of `level` a canvas shows (computed here from the pyramid's geometry), widened by
  // `margin` tiles: as "column_row" strings.
  function tilesShown(p, level, { zoom, origin, canvas }, margin) {
    const [width, height] = p.level_sizes[level];
    const scale = zoom * 2 ** level;
    const x0 = Math.max(Math.floor(-origin[0] / scale), 0);
    const y0 = Math.max(Math.floor(-origin[1] / scale), 0);
    const x1 = Math.min(Math.ceil((canvas[0] - origin[0]) / scale), width);
    const y1 = Math.min(Math.ceil((canvas[1] - origin[1]) / scale), height);
    const t = p.tile_size;
    const shown = new Set();
    for (let r = Math.max(Math.floor(y0 / t) - margin, 0); r <= Math.min(Math.floor((y1 - 1) / t) + margin, Math.ceil(height / t) - 1); ++r) {
      for (let c = Math.max(Math.floor(x0 / t) - margin, 0); c <= Math.min(Math.floor((x1 - 1) / t) + margin, Math.ceil(width / t) - 1); ++c) {
        shown.add(`${c}_${r}`);
      }
    }
    return shown;
  }

  function checkRequests(made, method, level, state) {
    const p = pyramid(method);
    const allowed = tilesShown(p, level, state, 1);
    const needed = tilesShown(p, level, state, 0);
    const got = new Set();
    for (const r of made) {
      assert.equal(r.method, method);
      // The coarsest level's single tile is the backdrop every method loads first.
      if (r.level === p.levels - 1) continue;
      assert.equal(r.level, level, `a tile of level ${r.level} requested at level ${level}`);
      assert.ok(allowed.has(`${r.column}_${r.row}`), `tile ${r.column}_${r.row} is not in view`);
      got.add(`${r.column}_${r.row}`);
    }
    for (const t of needed) assert.ok(got.has(t), `tile ${t} in view was not requested`);
    const total = Math.ceil(p.level_sizes[level][0] / p.tile_size) * Math.ceil(p.level_sizes[level][1] / p.tile_size);
    return { requested: got.size, inView: needed.size, total };
  }

  // Mean absolute difference over RGB of a canvas crop and `expected(x, y, c)` (0-255 codes).
  function meanDifference(canvas, expected) {
    let sum = 0;
    for (let y = 0; y < canvas.height; ++y) {
      for (let x = 0; x < canvas.width; ++x) {
        for (let c = 0; c < 3; ++c) sum += Math.abs(canvas.rgba[4 * (y * canvas.width + x) + c] - expected(x, y, c));
      }
    }
    return sum / (canvas.width * canvas.height * 3) / 255;
  }

  const srgbCode = (v) => {
    const x = Math.min(Math.max(v, 0), 1);
    return Math.round(255 * (x <= 0.0031308 ? 12.92 * x : 1.055 * x ** (1 / 2.4) - 0.055));
  };

  async function readCrop(light, width, height) {
    return page.evaluate(({ slant, tilt, w, h }) => {
      window.photomatViewer.setLight(slant, tilt);
      return window.photomatViewer.readCanvas(0, 0, w, h);
    }, { slant: light.slant, tilt: light.tilt, w: width, h: height });
  }

  test('requests only the tiles in view; level 0 matches photomat relight on a crop, level 1 its box average', async () => {
    const { canvas } = await page.evaluate(() => window.photomatViewer.state());
    // Level 0 at 1:1, the image's top-left part off the canvas.
    const [w, h] = pyramid(deep.methods[0]).level_sizes[0];
    const origin0 = [-Math.floor(0.6 * w), -Math.floor(0.5 * h)];
    const crop0 = [Math.min(w + origin0[0], canvas[0]), Math.min(h + origin0[1], canvas[1])];
    let made0;
    let first = deep.methods[0];
    // A small stack's fitted view may be level 0 already (the neural fixture, drawn in a small
    // page): its tiles are then cached and a single method requests nothing new.
    const fittedAtLevel0 = (await page.evaluate(() => window.photomatViewer.level())) === 0;
    if (deep.methods.length > 1) {
      // The first method has loaded level 0 for the fitted view: the second has loaded nothing
      // yet, so what it requests now is the backdrop and this view's tiles.
      await showAt(1, origin0);
      first = deep.methods[1];
      made0 = await selectMethod(first);
    } else {
      made0 = await showAt(1, origin0); // from the fitted view's coarser level
    }
    const state0 = await page.evaluate(() => window.photomatViewer.state());
    assert.equal(await page.evaluate(() => window.photomatViewer.level()), 0);
    const checkLevel0 = deep.methods.length > 1 || !fittedAtLevel0;
    const counts0 = checkLevel0 ? checkRequests(made0, first, 0, state0) : null;
    if (counts0) assert.ok(counts0.requested < counts0.total, `${counts0.requested} of ${counts0.total} tiles requested`);

    const order0 = [first, ...deep.methods.filter((m) => m !== first)];
    const results = [];
    for (const method of order0) {
      await selectMethod(method);
      for (const reference of deep.references.filter((r) => r.method === method)) {
        const crop = await readCrop(reference, crop0[0], crop0[1]);
        const png = readPng(reference.png8);
        const mean = meanDifference(crop, (x, y, c) => png.data[4 * ((y - origin0[1]) * png.width + x - origin0[0]) + c]);
        results.push({ level: 0, method, light: `${reference.slant},${reference.tilt}`, mean });
      }
    }

    // Level 1 at zoom 1/2: each canvas pixel is a level-1 pixel, the average of 2 x 2 image pixels.
    const current = order0[order0.length - 1];
    const [w1, h1] = pyramid(current).level_sizes[1];
    const origin1 = [-Math.floor(0.3 * w1), -Math.floor(0.3 * h1)];
    const crop1 = [Math.min(w1 + origin1[0], canvas[0]), Math.min(h1 + origin1[1], canvas[1])];
    const made1 = await showAt(0.5, origin1);
    const state1 = await page.evaluate(() => window.photomatViewer.state());
    assert.equal(await page.evaluate(() => window.photomatViewer.level()), 1);
    const counts1 = checkRequests(made1, current, 1, state1);
    for (const method of [current, ...deep.methods.filter((m) => m !== current)]) {
      const made = await selectMethod(method);
      if (method !== current) checkRequests(made, method, 1, state1);
      for (const reference of deep.references.filter((r) => r.method === method)) {
        const crop = await readCrop(reference, crop1[0], crop1[1]);
        const png = PNG.sync.read(readFileSync(reference.png16), { skipRescale: true });
        const boxAverage = (x, y, c) => {
          let sum = 0;
          for (const [dx, dy] of [[0, 0], [1, 0], [0, 1], [1, 1]]) {
            sum += png.data[4 * ((2 * (y - origin1[1]) + dy) * png.width + 2 * (x - origin1[0]) + dx) + c] / 65535;
          }
          return srgbCode(sum / 4);
        };
        results.push({ level: 1, method, light: `${reference.slant},${reference.tilt}`, mean: meanDifference(crop, boxAverage) });
      }
    }
    const requested0 = counts0 ? `requested ${counts0.requested} of ${counts0.total} tiles (${counts0.inView} in view)`
      : 'tiles loaded by the fitted view (requests checked at level 1)';
    console.log(`  ${deep.name}: ${w}x${h}, level 0 view ${crop0[0]}x${crop0[1]} ${requested0}, ` +
      `level 1 ${counts1.requested} of ${counts1.total} (${counts1.inView} in view); ` +
      results.map((r) => `L${r.level} ${r.method} (${r.light}) mean ${(r.mean * 255).toFixed(3)}/255`).join('; '));
    // A neural decoder is not linear in its coefficients: a coarser level, which averages
    // coefficients, relights to the decoding of the average, not to the average of the relit
    // pixels (README "Web viewer and evaluation report").
    const nonlinear = (m) => Boolean(manifest.methods.find((x) => x.name === m)?.shading);
    for (const r of results) {
      if (r.level > 0 && nonlinear(r.method) && r.mean >= MAX_MEAN_DIFFERENCE) {
        console.log(`EXPECTED FAILURE: target ${MAX_MEAN_DIFFERENCE * 255}/255 at level ${r.level} not met for ${r.method} at ${r.light} ` +
          `(measured ${(r.mean * 255).toFixed(3)}/255) because coarser levels average the coefficients of a nonlinear decoder`);
        continue;
      }
      assert.ok(r.mean < MAX_MEAN_DIFFERENCE, `level ${r.level} ${r.method} at ${r.light}: mean difference ${(r.mean * 255).toFixed(3)}/255`);
    }
    await page.evaluate(() => window.photomatViewer.fit());
    await page.waitForFunction(() => window.photomatViewer.tilesPending() === 0);
    await page.screenshot({ path: path.join(screenshots, `viewer-${deep.name}.png`) });
    assert.deepEqual(problems, []);
  });

  // The normal, albedo and height views of a deep-zoom viewer (relight/web/viewer_display_pyramids.h)
  // are the maps `photomat export --stream` writes: their level-0 tiles in view show the exported
  // PNGs' codes (16-bit normal and height, 8-bit sRGB albedo) as 8-bit canvas pixels.
  if (deep.views?.length) {
    test('normal, albedo and height views: only the tiles in view, equal to the exported maps on a crop', async () => {
      const { canvas } = await page.evaluate(() => window.photomatViewer.state());
      const [w, h] = pyramid(deep.views[0]).level_sizes[0];
      const origin = [-Math.floor(0.4 * w), -Math.floor(0.3 * h)];
      const crop = [Math.min(w + origin[0], canvas[0]), Math.min(h + origin[1], canvas[1])];
      await showAt(1 / 8, [0, 0]); // first the coarse levels, so that level 0 is fetched afresh
      const results = [];
      for (const view of deep.views) {
        const first = requests.length;
        await page.evaluate((v) => window.photomatViewer.setView(v), view);
        await page.evaluate(({ z, o }) => window.photomatViewer.setZoomOrigin(z, o), { z: 1, o: origin });
        await page.waitForFunction(() => window.photomatViewer.tilesPending() === 0);
        const state = await page.evaluate(() => window.photomatViewer.state());
        assert.equal(state.view, view);
        assert.equal(await page.evaluate(() => window.photomatViewer.level()), 0);
        const counts = checkRequests(requests.slice(first), view, 0, state);
        const shown = await page.evaluate(({ cw, ch }) => window.photomatViewer.readCanvas(0, 0, cw, ch), { cw: crop[0], ch: crop[1] });
        const bits16 = view !== 'albedo';
        const png = PNG.sync.read(readFileSync(deep.viewReferences[view]), { skipRescale: true });
        const code = (x, y, c) => {
          const v = png.data[4 * ((y - origin[1]) * png.width + x - origin[0]) + c];
          return bits16 ? Math.round((v / 65535) * 255) : v;
        };
        results.push({ view, mean: meanDifference(shown, code), ...counts });
      }
      console.log(`  ${deep.name} views: ${results.map((r) => `${r.view} ${r.requested} of ${r.total} tiles (${r.inView} in view), mean ${(r.mean * 255).toFixed(3)}/255`).join('; ')}`);
      for (const r of results) {
        assert.ok(r.mean < MAX_MEAN_DIFFERENCE, `${r.view}: mean difference ${(r.mean * 255).toFixed(3)}/255`);
      }
      for (const view of deep.views) {
        await page.evaluate((v) => window.photomatViewer.setView(v), view);
        await page.evaluate(() => window.photomatViewer.fit());
        await page.waitForFunction(() => window.photomatViewer.tilesPending() === 0);
        await page.screenshot({ path: path.join(screenshots, `viewer-${deep.name}-${view}.png`) });
      }
      await page.evaluate(() => window.photomatViewer.setView('relit'));
      assert.deepEqual(problems, []);
    });
  }
});

for (const report of fixtures.reports) {
  describe(`report "${report.name}"`, () => {
    test('loads with no console error and shows one chart per method', async () => {
      const { page, problems } = await openPage(browser, server.url + report.url);
      const charts = await page.locator('svg.method-chart').evaluateAll((svgs) => svgs.map((s) => s.dataset.method));
      assert.deepEqual(charts, report.methods);
      const rows = await page.locator('table.eta tbody tr td:first-child').allTextContents();
      assert.deepEqual(rows, report.methods);
      const broken = await page.locator('img').evaluateAll((images) =>
        images.filter((i) => !i.complete || i.naturalWidth === 0).map((i) => i.getAttribute('src')));
      assert.deepEqual(broken, []);
      assert.ok((await page.locator('img.heat-map').count()) >= 3, 'normal error heat maps');
      await page.screenshot({ path: path.join(screenshots, `report-${report.name}.png`), fullPage: true });
      assert.deepEqual(problems, []);
      await page.close();
    });
  });
}

// Fixtures this photomat cannot make (the neural viewers without libtorch) show as skipped tests,
// with the reason make-fixtures recorded.
for (const skipped of fixtures.skipped ?? []) {
  test(`viewer "${skipped.name}"`, { skip: skipped.reason }, () => {});
}

after(() => console.log(`screenshots: ${screenshots}`));
