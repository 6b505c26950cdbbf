// Builds the fixtures of the browser test with photomat itself (node make-fixtures.mjs OUT):
//  grid/       a synthetic capture on the thesis grid (Eigen-k: slant rings), every method fitted,
//              exported to a viewer, evaluated into a report
//  irregular/  a capture under irregular lights (Eigen-k: Delaunay triangulation)
//  table/      the grid's PTM and Gradient with their coefficients from the (slant, tilt) table
//  files/      a .ptm and an HSH .rti exported from the grid's fits (values are display codes)
//  deepzoom/   a viewer written as deep-zoom tiles (--viewer-tiles always)
//  neural/     a tiny trained neural basis (the decoder as a fragment shader), whole and tiled
// and, for each viewer, method and test light, photomat's CPU relighting
// (`photomat relight STACK --light S,T --out X.png`), which the viewer's canvas must reproduce.
// Writes OUT/fixtures.json describing it all.
import { execFileSync } from 'node:child_process';
import { existsSync, mkdirSync, readFileSync, rmSync, writeFileSync } from 'node:fs';
import path from 'node:path';

const out = path.resolve(process.argv[2] ?? 'viewer-test');
const build = path.resolve(process.env.PHOTOMAT_BUILD ?? 'build');
const photomat = path.join(build, 'bin', 'photomat');
const exportTool = path.join(build, 'tests', 'viewer_export_tool');
for (const tool of [photomat, exportTool]) {
  if (!existsSync(tool)) throw new Error(`${tool} not found: build photomat first (scripts/build)`);
}

function run(command, args) {
  try {
    return execFileSync(command, args, { encoding: 'utf8', stdio: ['ignore', 'pipe', 'pipe'] });
  } catch (error) {
    throw new Error(`${path.basename(command)} ${args.join(' ')} failed:\n${error.stderr}${error.stdout}`);
  }
}

// Lights a viewer must reproduce: on a fitted light, between rings and tilts, inside the innermost
// ring, past the outermost, grazing, and overhead.
const TEST_LIGHTS = [[30, 0], [52.5, 77], [12, 200], [75, 315], [88, 140], [0, 0]];

// 40 irregular lights (slant 8 to 70, any tilt) from a fixed linear congruential sequence.
function irregularLp() {
  let state = 12345;
  const next = () => {
    state = (state * 1103515245 + 12345) % 2147483648;
    return state / 2147483648;
  };
  const lines = [];
  for (let i = 0; i < 40; ++i) {
    const slant = ((8 + 62 * next()) * Math.PI) / 180;
    const tilt = 2 * Math.PI * next();
    const v = [Math.cos(tilt) * Math.sin(slant), Math.sin(tilt) * Math.sin(slant), Math.cos(slant)];
    lines.push(`img_${String(i).padStart(3, '0')}.png ${v.map((x) => x.toFixed(9)).join(' ')}`);
  }
  return `${lines.join('\n')}\n`;
}

rmSync(out, { recursive: true, force: true });
mkdirSync(out, { recursive: true });
const fixtures = { out, viewers: [], reports: [] };

// Exports `stacks` (a fit folder or a .ptm/.rti file) with `photomat export --viewer` (or, with
// `table`, with the test tool that forces the coefficient table) and relights every method.
function addViewer(name, stacks, { table = null } = {}) {
  const viewer = path.join(out, name, 'viewer');
  if (table) {
    run(exportTool, [stacks, viewer, '--title', `browser test: ${name}`, '--table', table.join(',')]);
  } else {
    run(photomat, ['export', stacks, '--viewer', viewer]);
  }
  const exported = JSON.parse(readFileSync(path.join(viewer, 'viewer.json'), 'utf8')).methods.map((m) => m.name);
  const methods = table ?? exported;
  const comparisons = [];
  for (const method of methods) {
    for (const [slant, tilt] of TEST_LIGHTS) {
      const reference = path.join(out, name, 'reference', `${method}_${slant}_${tilt}.png`);
      mkdirSync(path.dirname(reference), { recursive: true });
      run(photomat, ['relight', stacks, '--method', method, '--light', `${slant},${tilt}`, '--out', reference]);
      comparisons.push({ method, slant, tilt, reference });
    }
  }
  fixtures.viewers.push({ name, url: `${name}/viewer/index.html`, folder: viewer, methods: exported, compared: methods, comparisons });
}

// Fits `methods` and, where this photomat has hemispherical harmonics, the `hsh` ones too (16
// terms need lights at 4 or more slants); returns what it fitted.
function fit(capture, stacks, methods, hsh) {
  const withHsh = [...methods, ...hsh];
  try {
    run(photomat, ['fit', capture, '--method', withHsh.join(','), '--out', stacks]);
    return withHsh;
  } catch (error) {
    if (!/unknown method "hsh/.test(error.message)) throw error;
    console.log('make-fixtures: this photomat has no HSH methods; testing the others');
    run(photomat, ['fit', capture, '--method', methods.join(','), '--out', stacks]);
    return methods;
  }
}

// grid: the thesis's 36 lights over a bricks sample with shadows, highlights and noise.
const grid = path.join(out, 'grid');
run(photomat, ['generate', '--out', path.join(grid, 'capture'), '--size', '96x72', '--pattern', 'bricks',
  '--relief', '45', '--shadows', '--specular', '0.3', '--noise', '0.002', '--seed', '3']);
const all = fit(path.join(grid, 'capture'), path.join(grid, 'stacks'),
  ['3i', 'gradient', 'ptm', 'ptm-lrgb', 'eigen3', 'eigen6'], ['hsh4', 'hsh9']);
addViewer('grid', path.join(grid, 'stacks'));
run(photomat, ['evaluate', path.join(grid, 'capture'), '--methods', all.join(','), '--report',
  path.join(grid, 'report'), '--report-images', '0,17,30']);
fixtures.reports.push({ name: 'grid', url: 'grid/report/index.html', methods: all });

// irregular: Eigen-k interpolates in a Delaunay triangulation.
const irregular = path.join(out, 'irregular');
mkdirSync(irregular, { recursive: true });
writeFileSync(path.join(irregular, 'lights.lp'), irregularLp());
run(photomat, ['generate', '--out', path.join(irregular, 'capture'), '--size', '64x64', '--pattern', 'bumps',
  '--lights', path.join(irregular, 'lights.lp'), '--seed', '5']);
fit(path.join(irregular, 'capture'), path.join(irregular, 'stacks'),
  ['gradient', 'ptm', 'eigen3', 'eigen6'], ['hsh16']);
addViewer('irregular', path.join(irregular, 'stacks'));

// table: the grid's stacks again, PTM and Gradient evaluated from the coefficient table.
addViewer('table', path.join(grid, 'stacks'), { table: ['ptm', 'gradient'] });

// files: interchange files hold display codes, which the viewer decodes as `photomat relight` does.
const files = path.join(out, 'files');
mkdirSync(files, { recursive: true });
run(photomat, ['export', path.join(grid, 'stacks'), '--method', 'ptm', '--ptm', path.join(files, 'grid.ptm')]);
addViewer('ptm-file', path.join(files, 'grid.ptm'));
if (all.includes('hsh9')) {
  run(photomat, ['export', path.join(grid, 'stacks'), '--method', 'hsh9', '--rti', path.join(files, 'grid.rti')]);
  addViewer('rti-file', path.join(files, 'grid.rti'));
}

// Exports `stacks` (a fit folder or one .exr) with `photomat export --viewer ... exportArgs` and
// relights each method under two lights as 8-bit sRGB (the level-0 comparison) and 16-bit linear
// PNG (box-averaged for level 1). When the viewer has normal/albedo/height views (from the stack
// `viewsFrom` names: null for none, undefined to take what the export wrote), the same maps
// exported by `photomat export --stream` are their references.
function addDeepZoom(name, stacks, methods, exportArgs, viewsFrom = undefined) {
  const folder = path.join(out, name);
  run(photomat, ['export', stacks, '--viewer', path.join(folder, 'viewer'), ...exportArgs]);
  const manifest = JSON.parse(readFileSync(path.join(folder, 'viewer', 'viewer.json'), 'utf8'));
  const views = manifest.views.map((v) => v.name);
  let viewReferences = null;
  if (views.length) {
    const maps = path.join(folder, 'export');
    const source = manifest.views[0].source;
    run(photomat, ['export', stacks, ...(stacks.endsWith('.exr') ? [] : ['--method', source]), '--out', maps,
      '--stream', '--no-gltf']);
    viewReferences = { normal: path.join(maps, 'normal.png'), albedo: path.join(maps, 'albedo.png'),
      height: path.join(maps, 'height.png') };
  }
  if (viewsFrom !== undefined && (viewsFrom !== null) !== (views.length > 0)) {
    throw new Error(`${name}: expected ${viewsFrom ? `views from ${viewsFrom}` : 'no views'}, the export wrote [${views}]`);
  }
  const references = [];
  for (const method of methods) {
    for (const [slant, tilt] of [[30, 0], [52.5, 77]]) {
      const reference = path.join(folder, 'reference', `${method}_${slant}_${tilt}`);
      mkdirSync(path.dirname(reference), { recursive: true });
      for (const format of ['png8', 'png16']) {
        run(photomat, ['relight', stacks, ...(stacks.endsWith('.exr') ? [] : ['--method', method]),
          '--light', `${slant},${tilt}`, '--format', format, '--out', `${reference}.${format}.png`]);
      }
      references.push({ method, slant, tilt, png8: `${reference}.png8.png`, png16: `${reference}.png16.png` });
    }
  }
  fixtures.deepzoom.push({ name, url: `${name}/viewer/index.html`, folder: path.join(folder, 'viewer'), methods, references,
    views, viewReferences });
}

// deepzoom: a 256 x 192 capture whose viewer is forced into deep-zoom tiles of 32 px (4 levels;
// a stack small enough for a fast test).
fixtures.deepzoom = [];
const deep = path.join(out, 'deepzoom');
run(photomat, ['generate', '--out', path.join(deep, 'capture'), '--size', '256x192', '--pattern', 'bricks',
  '--relief', '45', '--seed', '7']);
run(photomat, ['fit', path.join(deep, 'capture'), '--method', 'gradient,ptm', '--out', path.join(deep, 'stacks')]);
addDeepZoom('deepzoom', path.join(deep, 'stacks'), ['gradient', 'ptm'], ['--viewer-tiles', 'always', '--viewer-tile-size', '32'],
  'gradient');
// neural: a tiny neural basis (NeuralRTI's decoder, k = 9, 8 seeded epochs on 1,920 of 12,288 pixels:
// a few seconds) trained on a small specular capture, shown whole and as deep-zoom tiles; the
// viewer's decoder shader must reproduce `photomat relight`'s Eigen decoder. Skipped, with the
// reason, where photomat was built without libtorch.
fixtures.skipped = [];
const neural = path.join(out, 'neural');
run(photomat, ['generate', '--out', path.join(neural, 'capture'), '--size', '128x96', '--pattern', 'bricks',
  '--relief', '45', '--specular', '0.3', '--seed', '9']);
try {
  run(photomat, ['fit', path.join(neural, 'capture'), '--method', 'neural', '--out', path.join(neural, 'stacks'),
    '--neural-epochs', '8', '--neural-sample-pixels', '1920', '--neural-threads', '2', '--seed', '1']);
} catch (error) {
  if (!/built without/.test(error.message)) throw error;
  const reason = error.message.split('\n').find((line) => /built without/.test(line)).trim();
  console.log(`make-fixtures: SKIPPED the neural viewer: ${reason}`);
  fixtures.skipped.push({ name: 'neural', reason });
}
if (existsSync(path.join(neural, 'stacks', 'neural.exr'))) {
  addViewer('neural', path.join(neural, 'stacks'));
  addDeepZoom('deepzoom-neural', path.join(neural, 'stacks', 'neural.exr'), ['neural'],
    ['--viewer-tiles', 'always', '--viewer-tile-size', '32'], null);
}

// PHOTOMAT_DEEPZOOM_STACK=STACK.exr METHOD: a large stack (bench/deepzoom_48mp's), exported as
// tiles (what `photomat export --viewer` does by default above 4096 x 4096 pixels; `always`, so
// that a smaller stack can check the benchmark script too).
if (process.env.PHOTOMAT_DEEPZOOM_STACK) {
  const [stack, method] = process.env.PHOTOMAT_DEEPZOOM_STACK.split(' ');
  addDeepZoom('deepzoom-large', path.resolve(stack), [method], ['--viewer-tiles', 'always']);
}

writeFileSync(path.join(out, 'fixtures.json'), `${JSON.stringify(fixtures, null, 2)}\n`);
console.log(`fixtures in ${out}: ${fixtures.viewers.map((v) => `${v.name} (${v.comparisons.length} references)`).join(', ')}`);
