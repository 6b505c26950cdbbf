// basis.js in Node, against the exports of make-fixtures.mjs: every method's coefficients equal
// photomat's (the C++ values each export carries for its check lights), and the interpolated bases
// behave as represent/light_interpolation.h promises (exact at the fitted lights, continuous across
// the tilt wrap-around, clamped outside the rings, convex weights).
import { describe, test } from 'node:test';
import assert from 'node:assert/strict';
import { readFileSync } from 'node:fs';
import path from 'node:path';
import { checkBasis, lightFromSlantTilt, makeBasis, slantDegrees, tiltDegrees } from '../src/basis.js';
import { loadFixtures } from './support.mjs';

const fixtures = loadFixtures();

function loadMethods(viewer) {
  const manifest = JSON.parse(readFileSync(path.join(viewer.folder, 'viewer.json'), 'utf8'));
  return manifest.methods.map((m) => {
    let table = null;
    if (m.basis.kind === 'table') {
      const bytes = readFileSync(path.join(viewer.folder, m.basis.file));
      table = new Float32Array(bytes.buffer, bytes.byteOffset, bytes.byteLength / 4);
    }
    return { json: m, basis: makeBasis(m.basis, table) };
  });
}

const maxDifference = (a, b) => Math.max(...Array.from(a, (v, j) => Math.abs(v - b[j])));

test('slant and tilt follow photomat\'s light frame', () => {
  const l = lightFromSlantTilt(30, 90);
  assert.ok(Math.abs(l[0]) < 1e-15 && Math.abs(l[1] - 0.5) < 1e-15 && Math.abs(l[2] - Math.sqrt(3) / 2) < 1e-15);
  assert.ok(Math.abs(slantDegrees(l) - 30) < 1e-12);
  assert.ok(Math.abs(tiltDegrees(l) - 90) < 1e-12);
  assert.equal(tiltDegrees([0, 0, 1]), 0);
  assert.ok(Math.abs(tiltDegrees(lightFromSlantTilt(40, -10)) - 350) < 1e-12);
});

// Gautron's hemispherical harmonics are orthonormal over the upper hemisphere: a check of every
// term's constant, sign convention aside, independent of photomat's C++.
test('HSH terms are orthonormal over the hemisphere', () => {
  const basis = makeBasis({ kind: 'hsh', terms: 16 });
  const n = 240;
  const gram = Array.from({ length: 16 }, () => new Float64Array(16));
  for (let i = 0; i < n; ++i) {
    const theta = ((i + 0.5) / n) * (Math.PI / 2);
    for (let k = 0; k < 2 * n; ++k) {
      const phi = ((k + 0.5) / (2 * n)) * 2 * Math.PI;
      const weight = Math.sin(theta) * (Math.PI / 2 / n) * (Math.PI / n);
      const h = basis.coefficients([Math.sin(theta) * Math.cos(phi), Math.sin(theta) * Math.sin(phi), Math.cos(theta)]);
      for (let a = 0; a < 16; ++a) for (let b = 0; b < 16; ++b) gram[a][b] += weight * h[a] * h[b];
    }
  }
  for (let a = 0; a < 16; ++a) {
    for (let b = 0; b < 16; ++b) assert.ok(Math.abs(gram[a][b] - (a === b ? 1 : 0)) < 2e-3, `<h${a}, h${b}> = ${gram[a][b]}`);
  }
  assert.equal(makeBasis({ kind: 'hsh', terms: 9 }).size, 9);
  assert.throws(() => makeBasis({ kind: 'hsh', terms: 7 }), /4, 9 or 16/);
});

test('unknown basis kinds are refused', () => {
  assert.throws(() => makeBasis({ kind: 'spherical-harmonics' }), /unknown light basis/);
  assert.throws(() => makeBasis({ kind: 'linear', matrix: [[1, 0, 0]] }).coefficients([0, 0, 0]), /not a light/);
});

for (const viewer of fixtures.viewers) {
  describe(`basis.js on the "${viewer.name}" export`, () => {
    const methods = loadMethods(viewer);

    for (const { json, basis } of methods) {
      test(`${json.name} (${json.basis.kind}${json.basis.scheme ? `, ${json.basis.scheme}` : ''}) equals photomat on ${json.check.lights.length} check lights`, () => {
        const result = checkBasis(basis, json.check);
        assert.ok(result.ok, `largest difference ${result.maxError} > ${result.tolerance}`);
        assert.equal(basis.size, json.layout.basis_size);
      });
    }

    for (const { json, basis } of methods.filter((m) => m.json.basis.kind === 'interpolated')) {
      test(`${json.name}: exact at the fitted lights, continuous across tilt 0/360, clamped`, () => {
        const { nodes, values } = json.basis;
        nodes.forEach((node, i) => assert.ok(maxDifference(basis.coefficients(node), values[i]) < 1e-9, `node ${i}`));
        for (const slant of [20, 40, 55, 80]) {
          const below = basis.coefficients(lightFromSlantTilt(slant, 359.999999));
          const above = basis.coefficients(lightFromSlantTilt(slant, 0.000001));
          assert.ok(maxDifference(below, above) < 1e-4, `slant ${slant}`);
        }
        // Beyond the outermost fitted slant nothing new is invented: a convex combination of nodes.
        const outside = basis.coefficients(lightFromSlantTilt(89, 123));
        for (let j = 0; j < basis.size; ++j) {
          const column = values.map((v) => v[j]);
          assert.ok(outside[j] >= Math.min(...column) - 1e-12 && outside[j] <= Math.max(...column) + 1e-12);
        }
      });
    }
  });
}
