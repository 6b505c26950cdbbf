// The web viewer and the evaluation report in Debian's Chromium (headless, software WebGL):
//  - for every exported method and test light, the viewer's canvas pixels equal photomat's own CPU
//    relighting (`photomat relight`) within a mean absolute difference of 2/255;
//  - the viewer's controls move the light, switch methods and views, zoom;
//  - the report loads with no console error and shows one chart per method;
//  - screenshots of both land in the screenshot folder for a person to look at.
import { after, before, describe, test } from 'node:test';
import assert from 'node:assert/strict';
import path from 'node:path';
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

async function openViewer(viewer) {
  const opened = await openPage(browser, server.url + viewer.url);
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

after(() => console.log(`screenshots: ${screenshots}`));
