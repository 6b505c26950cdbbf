// Light bases of photomat representations: the function from a light direction to the k
// coefficients c(l) of the shading rule out_c = gain_c * sum_j c_j(l) B_j,c. A line-by-line port
// of represent/light_basis.cc and represent/light_interpolation.cc (LightInterpolator::Weights),
// in double precision like the C++, from the description relight/viewer_export.cc writes into
// viewer.json. Every export carries check lights with the C++ coefficients; checkBasis() compares.
// No DOM here: Node runs the same module in viewer/test.

const DEGREE = Math.PI / 180;

// photomat's light frame: x right, y up, z toward the camera; slant from +z, tilt from +x to +y.
export function lightFromSlantTilt(slantDeg, tiltDeg) {
  const s = slantDeg * DEGREE;
  const t = tiltDeg * DEGREE;
  return [Math.cos(t) * Math.sin(s), Math.sin(t) * Math.sin(s), Math.cos(s)];
}

export function normalise(v) {
  const norm = Math.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  if (!(norm >= 1e-6) || !Number.isFinite(norm)) throw new Error(`not a light direction: ${v}`);
  return [v[0] / norm, v[1] / norm, v[2] / norm];
}

// In [0, 180] (LightDirection::SlantDegrees).
export function slantDegrees(l) {
  return Math.atan2(Math.hypot(l[0], l[1]), l[2]) / DEGREE;
}

// In [0, 360); 0 on the camera axis (LightDirection::TiltDegrees).
export function tiltDegrees(l) {
  if (Math.hypot(l[0], l[1]) < 1e-12) return 0;
  let tilt = Math.atan2(l[1], l[0]) / DEGREE;
  if (tilt < 0) tilt += 360;
  return tilt >= 360 ? 0 : tilt;
}

// LightInterpolator::AddRingWeights.
function addRingWeights(ring, tilt, scale, poleSlant, weights) {
  const nodes = ring.by_tilt;
  if (ring.slant < poleSlant) {
    for (const [, node] of nodes) weights.push([node, scale / nodes.length]);
    return;
  }
  // std::upper_bound on (tilt, INT_MAX): the first node whose tilt is greater.
  let after = nodes.findIndex(([nodeTilt]) => nodeTilt > tilt);
  if (after < 0) after = nodes.length;
  const upper = after === nodes.length ? 0 : after;
  const lower = after === 0 ? nodes.length - 1 : after - 1;
  let lowTilt = nodes[lower][0];
  let highTilt = nodes[upper][0];
  if (lowTilt > tilt) lowTilt -= 360;
  if (highTilt <= tilt) highTilt += 360;
  const f = (tilt - lowTilt) / (highTilt - lowTilt);
  weights.push([nodes[lower][1], scale * (1 - f)]);
  weights.push([nodes[upper][1], scale * f]);
}

// LightInterpolator::RingWeights.
function ringWeights(json, light) {
  const rings = json.rings;
  const slant = slantDegrees(light);
  const tilt = tiltDegrees(light);
  const pole = json.pole_slant_deg;
  let weights = [];
  if (slant <= rings[0].slant) {
    addRingWeights(rings[0], tilt, 1, pole, weights);
  } else if (slant >= rings[rings.length - 1].slant) {
    addRingWeights(rings[rings.length - 1], tilt, 1, pole, weights);
  } else {
    let upper = 1;
    while (rings[upper].slant < slant) ++upper;
    const below = rings[upper - 1];
    const above = rings[upper];
    const t = (slant - below.slant) / (above.slant - below.slant);
    addRingWeights(below, tilt, 1 - t, pole, weights);
    addRingWeights(above, tilt, t, pole, weights);
  }
  weights = weights.filter(([, w]) => !(w <= 1e-12));
  let total = 0;
  for (const [, w] of weights) total += w;
  return weights.map(([node, w]) => [node, w / total]);
}

// LightInterpolator::TriangulationWeights, in the azimuthal-equidistant projection.
function triangulationWeights(json, light) {
  const slant = (slantDegrees(light) * Math.PI) / 180;
  const tilt = (tiltDegrees(light) * Math.PI) / 180;
  const scale = json.projection_scale;
  const q = [slant * Math.cos(tilt) * scale, slant * Math.sin(tilt) * scale];
  const p = json.projected;
  for (const tri of json.triangles) {
    const a = p[tri[0]];
    const b = p[tri[1]];
    const c = p[tri[2]];
    const det = (b[1] - c[1]) * (a[0] - c[0]) + (c[0] - b[0]) * (a[1] - c[1]);
    const wa = ((b[1] - c[1]) * (q[0] - c[0]) + (c[0] - b[0]) * (q[1] - c[1])) / det;
    const wb = ((c[1] - a[1]) * (q[0] - c[0]) + (a[0] - c[0]) * (q[1] - c[1])) / det;
    const wc = 1 - wa - wb;
    const inside = -1e-9;
    if (wa >= inside && wb >= inside && wc >= inside) {
      const total = Math.max(wa, 0) + Math.max(wb, 0) + Math.max(wc, 0);
      const weights = [];
      for (const [node, w] of [[tri[0], wa], [tri[1], wb], [tri[2], wc]]) {
        if (w > 0) weights.push([node, w / total]);
      }
      return weights;
    }
  }
  // Outside the triangulated area: the nearest point of its boundary.
  let bestDistance = Infinity;
  let best = [];
  for (const [u, v] of json.boundary) {
    const a = p[u];
    const b = p[v];
    const dx = b[0] - a[0];
    const dy = b[1] - a[1];
    const t = Math.min(Math.max(((q[0] - a[0]) * dx + (q[1] - a[1]) * dy) / (dx * dx + dy * dy), 0), 1);
    const distance = Math.hypot(a[0] + t * dx - q[0], a[1] + t * dy - q[1]);
    if (distance < bestDistance) {
      bestDistance = distance;
      best = [];
      if (t < 1) best.push([u, 1 - t]);
      if (t > 0) best.push([v, t]);
    }
  }
  return best;
}

function interpolatedBasis(json) {
  const values = json.values;
  const size = values[0].length;
  const weightsOf =
    json.scheme === 'slant-rings'
      ? (l) => ringWeights(json, l)
      : json.scheme === 'triangulation'
        ? (l) => triangulationWeights(json, l)
        : null;
  if (!weightsOf) throw new Error(`unknown interpolation scheme "${json.scheme}"`);
  return {
    size,
    coefficients(light) {
      const c = new Float64Array(size);
      for (const [node, w] of weightsOf(light)) {
        for (let j = 0; j < size; ++j) c[j] += w * values[node][j];
      }
      return c;
    },
  };
}

// Hemispherical harmonics (Gautron et al. 2004) in RTIViewer's term order and signs, as HSH .rti
// files and photomat's HshLightBasis define them: theta the slant, phi the tilt, over the upper
// hemisphere through c = cos(theta) (a light below the horizon is taken at the horizon).
function hshBasis(json) {
  const terms = json.terms;
  if (![4, 9, 16].includes(terms)) throw new Error(`HSH has 4, 9 or 16 terms, not ${terms}`);
  const pi = Math.PI;
  return {
    size: terms,
    coefficients(l) {
      const c = Math.min(Math.max(l[2], 0), 1);
      const phi = Math.atan2(l[1], l[0]);
      const s = Math.sqrt(Math.max(0, c - c * c));
      const c2 = c * c;
      const h = new Float64Array(terms);
      h[0] = 1 / Math.sqrt(2 * pi);
      h[1] = Math.sqrt(6 / pi) * s * Math.cos(phi);
      h[2] = Math.sqrt(3 / (2 * pi)) * (2 * c - 1);
      h[3] = Math.sqrt(6 / pi) * s * Math.sin(phi);
      if (terms === 4) return h;
      h[4] = Math.sqrt(30 / pi) * (c2 - c) * Math.cos(2 * phi);
      h[5] = Math.sqrt(30 / pi) * (2 * c - 1) * s * Math.cos(phi);
      h[6] = Math.sqrt(5 / (2 * pi)) * (6 * c2 - 6 * c + 1);
      h[7] = Math.sqrt(30 / pi) * (2 * c - 1) * s * Math.sin(phi);
      h[8] = Math.sqrt(30 / pi) * (c2 - c) * Math.sin(2 * phi);
      if (terms === 9) return h;
      const s3 = s * s * s;
      h[9] = 2 * Math.sqrt(35 / pi) * s3 * Math.cos(3 * phi);
      h[10] = Math.sqrt(210 / pi) * (2 * c - 1) * (c2 - c) * Math.cos(2 * phi);
      h[11] = 2 * Math.sqrt(21 / pi) * s * (5 * c2 - 5 * c + 1) * Math.cos(phi);
      h[12] = Math.sqrt(7 / (2 * pi)) * (20 * c2 * c - 30 * c2 + 12 * c - 1);
      h[13] = 2 * Math.sqrt(21 / pi) * s * (5 * c2 - 5 * c + 1) * Math.sin(phi);
      h[14] = Math.sqrt(210 / pi) * (2 * c - 1) * (c2 - c) * Math.sin(2 * phi);
      h[15] = 2 * Math.sqrt(35 / pi) * s3 * Math.sin(3 * phi);
      return h;
    },
  };
}

// CoefficientTable::Coefficients (relight/viewer_export.h): bilinear in (slant, tilt) over float32
// values, term-fastest, then tilt, then slant.
function tableBasis(json, table) {
  const terms = json.terms;
  const slantSteps = json.slant_steps;
  const tiltSteps = json.tilt_steps;
  const step = json.step_deg;
  if (!table || table.length !== slantSteps * tiltSteps * terms) {
    throw new Error(`coefficient table ${json.file}: expected ${slantSteps * tiltSteps * terms} values`);
  }
  const at = (s, t, j) => table[(s * tiltSteps + t) * terms + j];
  return {
    size: terms,
    coefficients(light) {
      const s = Math.min(Math.max(slantDegrees(light) / step, 0), slantSteps - 1);
      const t = Math.min(Math.max(tiltDegrees(light) / step, 0), tiltSteps - 1);
      const s0 = Math.min(Math.trunc(s), slantSteps - 2);
      const t0 = Math.min(Math.trunc(t), tiltSteps - 2);
      const fs = s - s0;
      const ft = t - t0;
      const c = new Float64Array(terms);
      for (let j = 0; j < terms; ++j) {
        c[j] =
          (1 - fs) * ((1 - ft) * at(s0, t0, j) + ft * at(s0, t0 + 1, j)) +
          fs * ((1 - ft) * at(s0 + 1, t0, j) + ft * at(s0 + 1, t0 + 1, j));
      }
      return c;
    },
  };
}

// A basis from its viewer.json description; `table` is the Float32Array of a "table" basis.
// coefficients(light) takes any non-zero [x, y, z] and returns a Float64Array of `size` values.
export function makeBasis(json, table = null) {
  let basis;
  switch (json.kind) {
    case 'linear': {
      const matrix = json.matrix;
      basis = {
        size: matrix.length,
        coefficients(l) {
          return Float64Array.from(matrix, (row) => row[0] * l[0] + row[1] * l[1] + row[2] * l[2]);
        },
      };
      break;
    }
    case 'ptm':
      basis = {
        size: 6,
        coefficients(l) {
          const u = l[0];
          const v = l[1];
          return Float64Array.of(u * u, v * v, u * v, u, v, 1);
        },
      };
      break;
    case 'direction':
      // c = l: the light input of a shading (the neural decoder reads lx, ly).
      basis = { size: 3, coefficients: (l) => Float64Array.of(l[0], l[1], l[2]) };
      break;
    case 'interpolated':
      basis = interpolatedBasis(json);
      break;
    case 'hsh':
      basis = hshBasis(json);
      break;
    case 'table':
      basis = tableBasis(json, table);
      break;
    default:
      throw new Error(`unknown light basis "${json.kind}"`);
  }
  const evaluate = basis.coefficients;
  return { kind: json.kind, size: basis.size, coefficients: (light) => evaluate(normalise(light)) };
}

// Compares the basis with the C++ coefficients of the export's check lights.
export function checkBasis(basis, check) {
  let maxError = 0;
  for (let i = 0; i < check.lights.length; ++i) {
    const c = basis.coefficients(check.lights[i]);
    const expected = check.coefficients[i];
    if (c.length !== expected.length) return { ok: false, maxError: Infinity, lights: i + 1 };
    for (let j = 0; j < c.length; ++j) {
      maxError = Math.max(maxError, Math.abs(c[j] - expected[j]) / Math.max(1, Math.abs(expected[j])));
    }
  }
  return { ok: maxError <= check.tolerance, maxError, lights: check.lights.length, tolerance: check.tolerance };
}
