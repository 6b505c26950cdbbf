// photomat's web relighting viewer. Reads viewer.json (written by relight/viewer_export.cc) and
// relights each method with one WebGL2 fragment shader: out_c = gain_c * sum_j c_j(l) B_j,c, the
// rule of represent/representation.h, with the maps as float32 texels and c(l) from basis.js; a
// neural method's shader evaluates its decoder instead (weights in a float texture).
// No network access beyond the folder it is served from; no libraries.
// Large stacks come as deep-zoom pyramids (relight/web/viewer_pyramid.h): the tiles in view (and
// a margin of one tile) of the level the zoom asks for are fetched, kept in a bounded LRU cache
// and relit one texture per tile by the same shader, clipped to the tile's pixels.

import { checkBasis, lightFromSlantTilt, makeBasis, slantDegrees, tiltDegrees } from './basis.js';

const $ = (id) => document.getElementById(id);

const VERTEX_SHADER = `#version 300 es
// One triangle covering the viewport; the fragment shader maps canvas pixels to image pixels.
void main() {
  vec2 p = vec2(float((gl_VertexID & 1) << 2) - 1.0, float((gl_VertexID & 2) << 1) - 1.0);
  gl_Position = vec4(p, 0.0, 1.0);
}`;

const COMMON_GLSL = `
precision highp float;
precision highp int;
uniform vec2 u_origin;         // canvas pixel (from the top left) of the image's top-left corner
uniform float u_zoom;          // canvas pixels per image pixel
uniform float u_canvas_height;
uniform ivec2 u_size;          // image width, height
out vec4 o_colour;
const vec4 kBackground = vec4(0.067, 0.071, 0.078, 1.0);

// The image pixel under this fragment (nearest: at zoom 1 each canvas pixel is one image pixel).
ivec2 ImagePixel() {
  vec2 canvas = vec2(gl_FragCoord.x, u_canvas_height - gl_FragCoord.y);
  return ivec2(floor((canvas - u_origin) / u_zoom));
}
bool Outside(ivec2 p) { return any(lessThan(p, ivec2(0))) || any(greaterThanEqual(p, u_size)); }
`;

// The frame every relighting shader shares: the tile clipping, the maps of the pixel (map
// 4 * layer + component of the RGBA32F array texture) and the output transfer. `colourBody` is GLSL
// that sets `vec3 colour` (linear RGB, or grey in all three) from `maps`; `declarations` come before
// main. `srgbValues`: the relit values are display codes (stacks from .ptm/.rti files), decoded to
// linear first as `photomat relight` does.
function relightFrame(layers, srgbValues, declarations, colourBody) {
  return `#version 300 es
#define LAYERS ${layers}
#define VALUES_SRGB ${srgbValues ? 1 : 0}
precision highp sampler2DArray;
${COMMON_GLSL}
uniform sampler2DArray u_maps;     // map 4 * layer + component
uniform float u_exposure;          // linear scale
// The texture is a tile of a pyramid level (the whole image: level 0, one tile of it all).
uniform float u_level_scale;       // image pixels per level pixel, 2^level
uniform ivec2 u_tile_origin;       // the level pixel of texel (0, 0)
uniform ivec2 u_core_min;          // the level pixels this tile draws: [min, max)
uniform ivec2 u_core_max;

// The sRGB transfer function, as photomat writes 8-bit images (core/colour.cc LinearToSrgb).
float Srgb(float v) {
  v = clamp(v, 0.0, 1.0);
  return v <= 0.0031308 ? v * 12.92 : 1.055 * pow(v, 1.0 / 2.4) - 0.055;
}

// Its inverse (core/colour.cc SrgbToLinear), for values that are display codes.
float Linear(float v) {
  v = clamp(v, 0.0, 1.0);
  return v <= 0.04045 ? v / 12.92 : pow((v + 0.055) / 1.055, 2.4);
}
${declarations}
void main() {
  vec2 canvas = vec2(gl_FragCoord.x, u_canvas_height - gl_FragCoord.y);
  ivec2 q = ivec2(floor((canvas - u_origin) / (u_zoom * u_level_scale)));
  // Outside the tile (or the image) the cleared background shows.
  if (any(lessThan(q, u_core_min)) || any(greaterThanEqual(q, u_core_max))) discard;
  ivec2 p = q - u_tile_origin;
  float maps[LAYERS * 4];
  for (int layer = 0; layer < LAYERS; ++layer) {
    vec4 t = texelFetch(u_maps, ivec3(p, layer), 0);
    maps[4 * layer] = t.r;
    maps[4 * layer + 1] = t.g;
    maps[4 * layer + 2] = t.b;
    maps[4 * layer + 3] = t.a;
  }
  vec3 colour = vec3(0.0);
${colourBody}
  if (VALUES_SRGB == 1) colour = vec3(Linear(colour.r), Linear(colour.g), Linear(colour.b));
  colour *= u_exposure;
  o_colour = vec4(Srgb(colour.r), Srgb(colour.g), Srgb(colour.b), 1.0);
}`;
}

// The relighting shader of one linear method layout (MapLayout in represent/representation.h):
// out_c = gain_c * sum_j c_j(l) B_j,c.
function relightShader(layout, layers, srgbValues) {
  const perTerm = layout.basis_per_channel ? layout.output_channels : 1;
  const gainOffset = layout.basis_size * perTerm;
  return relightFrame(layers, srgbValues, `
#define TERMS ${layout.basis_size}
#define CHANNELS ${layout.output_channels}
#define PER_TERM ${perTerm}
#define PER_CHANNEL ${layout.basis_per_channel ? 1 : 0}
#define HAS_GAIN ${layout.has_gain ? 1 : 0}
#define GAIN_OFFSET ${gainOffset}
uniform float u_coefficients[TERMS];
`, `
  for (int o = 0; o < CHANNELS && o < 3; ++o) {
    float sum = 0.0;
    for (int j = 0; j < TERMS; ++j) {
      sum += u_coefficients[j] * maps[j * PER_TERM + (PER_CHANNEL == 1 ? o : 0)];
    }
    colour[o] = HAS_GAIN == 1 ? sum * maps[GAIN_OFFSET + o] : sum;
  }
  if (CHANNELS == 1) colour = vec3(colour.r);`);
}

// The relighting shader of a `neural` method: NeuralShading's decoder (represent/model/
// neural_decoder.h) per fragment, from the pixel's k coefficient maps and the light's (lx, ly)
// (u_coefficients: the "direction" basis, c = l). The weights are the RGBA32F texture of
// relight/web/viewer_decoder.h: one row per neuron, texel t holding its weights 4t .. 4t + 3 and
// the texel after the last holding its bias; so each neuron is a few vec4 dot products. ELU
// (alpha 1) after every layer but the last, whose outputs are scaled by output_scale.
function neuralShader(shading, layers, srgbValues) {
  const widest = Math.max(shading.coefficients + 2, ...shading.layers.map((l) => l.outputs));
  const chunks = Math.ceil(widest / 4);
  let body = `
  float x[${4 * chunks}];
  for (int i = 0; i < ${4 * chunks}; ++i) x[i] = 0.0;
  for (int j = 0; j < ${shading.coefficients}; ++j) x[j] = maps[j];
  x[${shading.coefficients}] = u_coefficients[0];
  x[${shading.coefficients + 1}] = u_coefficients[1];
  vec4 a[${chunks}];`;
  shading.layers.forEach((layer, l) => {
    const inputs = Math.ceil(layer.inputs / 4);
    const activation = l + 1 < shading.layers.length ? 'Elu(sum)' : 'sum';
    body += `
  // layer ${l}: ${layer.inputs} -> ${layer.outputs}
  for (int t = 0; t < ${inputs}; ++t) a[t] = vec4(x[4 * t], x[4 * t + 1], x[4 * t + 2], x[4 * t + 3]);
  for (int i = 0; i < ${4 * chunks}; ++i) x[i] = 0.0;
  for (int o = 0; o < ${layer.outputs}; ++o) {
    int row = ${layer.first_row} + o;
    float sum = texelFetch(u_decoder, ivec2(${inputs}, row), 0).r;
    for (int t = 0; t < ${inputs}; ++t) sum += dot(texelFetch(u_decoder, ivec2(t, row), 0), a[t]);
    x[o] = ${activation};
  }`;
  });
  body += `
  for (int o = 0; o < ${shading.outputs} && o < 3; ++o) colour[o] = x[o] * ${glslFloat(shading.output_scale)};
  if (${shading.outputs} == 1) colour = vec3(colour.r);`;
  return relightFrame(layers, srgbValues, `
uniform float u_coefficients[3];
uniform highp sampler2D u_decoder;  // the decoder's weights and biases
// ELU with alpha 1 (torch::nn::ELU's default).
float Elu(float v) { return v > 0.0 ? v : exp(v) - 1.0; }
`, body);
}

// A number as a GLSL float literal, to float32 precision (9 significant digits round-trip).
function glslFloat(value) {
  const text = Math.fround(value).toPrecision(9);
  return /[.e]/.test(text) ? text : `${text}.0`;
}

// The shader of a method: its decoder's for a neural method, else the linear rule's.
function methodProgram(method) {
  const { layout, data, shading, values } = method.json;
  if (shading) {
    if (shading.kind !== 'neural' || shading.activation !== 'elu') {
      throw new Error(`${method.json.name}: the viewer has no ${shading.kind} shading`);
    }
    return program(neuralShader(shading, data.layers, values === 'srgb'));
  }
  return program(relightShader(layout, data.layers, values === 'srgb'));
}

// A neural method's decoder texture (relight/web/viewer_decoder.h), and its values for the pixel
// readout.
async function loadDecoder(method) {
  const { shading } = method.json;
  if (!shading || method.decoder) return;
  const { width, height } = shading.texture;
  const values = float32s(await fetchChecked(shading.file, 'buffer'), shading.file);
  if (values.length !== width * height * 4) {
    throw new Error(`${shading.file}: ${values.length} values, expected ${width * height * 4}`);
  }
  const texture = gl.createTexture();
  gl.bindTexture(gl.TEXTURE_2D, texture);
  gl.pixelStorei(gl.UNPACK_ALIGNMENT, 4);
  gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA32F, width, height, 0, gl.RGBA, gl.FLOAT, values);
  gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.NEAREST);
  gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, gl.NEAREST);
  method.decoder = { texture, values };
}

// The decoder on the CPU, for the pixel readout: what neuralShader computes.
function evaluateDecoder(shading, weights, codes, lx, ly) {
  const width = shading.texture.width;
  let x = [...codes, lx, ly];
  shading.layers.forEach((layer, l) => {
    const chunks = Math.ceil(layer.inputs / 4);
    const out = [];
    for (let o = 0; o < layer.outputs; ++o) {
      const row = (layer.first_row + o) * width * 4;
      let sum = weights[row + 4 * chunks];
      for (let i = 0; i < layer.inputs; ++i) sum += weights[row + i] * x[i];
      out.push(l + 1 < shading.layers.length && sum <= 0 ? Math.expm1(sum) : sum);
    }
    x = out;
  });
  return x.map((v) => v * shading.output_scale);
}

// Normal, albedo and height maps: 8-bit PNG codes shown as they are.
const MAP_SHADER = `#version 300 es
${COMMON_GLSL}
uniform sampler2D u_image;
void main() {
  ivec2 p = ImagePixel();
  o_colour = Outside(p) ? kBackground : vec4(texelFetch(u_image, p, 0).rgb, 1.0);
}`;

// A deep-zoom view's tile (relight/web/viewer_display_pyramids.h): display codes in [0, 1] shown as
// they are (one channel: grey), clipped to the tile's pixels like the relit tiles.
const VIEW_TILE_SHADER = `#version 300 es
precision highp sampler2DArray;
${COMMON_GLSL}
uniform sampler2DArray u_maps;
uniform float u_level_scale;
uniform ivec2 u_tile_origin;
uniform ivec2 u_core_min;
uniform ivec2 u_core_max;
uniform int u_grey;
void main() {
  vec2 canvas = vec2(gl_FragCoord.x, u_canvas_height - gl_FragCoord.y);
  ivec2 q = ivec2(floor((canvas - u_origin) / (u_zoom * u_level_scale)));
  if (any(lessThan(q, u_core_min)) || any(greaterThanEqual(q, u_core_max))) discard;
  vec4 t = texelFetch(u_maps, ivec3(q - u_tile_origin, 0), 0);
  o_colour = vec4(u_grey == 1 ? vec3(t.r) : t.rgb, 1.0);
}`;

const state = {
  manifest: null,
  methods: new Map(), // name -> {json, basis, check, texture, program, loading}
  views: new Map(), // name -> {json, texture}
  method: null,
  view: 'relit',
  light: lightFromSlantTilt(45, 0),
  exposure: 0,
  zoom: 1,
  origin: [0, 0],
  dragMode: 'light',
  checks: [],
  drawQueued: false,
};

let gl = null;
let canvas = null;
let mapProgram = null;
let viewTileProgram = null;

// IMPLEMENTER CHOICE: tiles of the level in view and one tile around it are fetched (the margin
// hides the edges while panning), at most 6 at once (a browser's connections per server); the
// cache keeps at most 384 MB of tiles (texture and CPU copy for the pixel readout), least
// recently drawn evicted first, never the coarsest level's (the backdrop while tiles load).
const TILE_MARGIN = 1;
const TILE_FETCHES = 6;
const TILE_CACHE_BYTES = 384 * 2 ** 20;
const tiles = {
  cache: new Map(), // key -> {texture, values, rect, bytes}; Map order: least recently used first
  loading: new Map(), // key -> promise
  wanted: [], // [{method, level, column, row, key}] for the view, in order of need
  bytes: 0,
};

function setStatus(text, kind = '') {
  const status = $('status');
  status.textContent = text;
  status.className = `small ${kind}`;
}

function fail(message) {
  console.error(`photomat viewer: ${message}`);
  setStatus(message, 'bad');
}

async function fetchChecked(url, type) {
  const response = await fetch(url);
  if (!response.ok) throw new Error(`${url}: HTTP ${response.status}`);
  return type === 'json' ? response.json() : response.arrayBuffer();
}

// Float32 little-endian, as viewer_export.cc writes; converted on big-endian hosts.
function float32s(buffer, url) {
  if (buffer.byteLength % 4 !== 0) throw new Error(`${url}: not float32 data`);
  const littleEndian = new Uint8Array(new Uint16Array([1]).buffer)[0] === 1;
  if (littleEndian) return new Float32Array(buffer);
  const view = new DataView(buffer);
  return Float32Array.from({ length: buffer.byteLength / 4 }, (_, i) => view.getFloat32(4 * i, true));
}

function compile(type, source) {
  const shader = gl.createShader(type);
  gl.shaderSource(shader, source);
  gl.compileShader(shader);
  if (!gl.getShaderParameter(shader, gl.COMPILE_STATUS)) {
    throw new Error(`shader: ${gl.getShaderInfoLog(shader)}`);
  }
  return shader;
}

function program(fragmentSource) {
  const p = gl.createProgram();
  gl.attachShader(p, compile(gl.VERTEX_SHADER, VERTEX_SHADER));
  gl.attachShader(p, compile(gl.FRAGMENT_SHADER, fragmentSource));
  gl.linkProgram(p);
  if (!gl.getProgramParameter(p, gl.LINK_STATUS)) throw new Error(`program: ${gl.getProgramInfoLog(p)}`);
  const uniforms = {};
  const count = gl.getProgramParameter(p, gl.ACTIVE_UNIFORMS);
  for (let i = 0; i < count; ++i) {
    const name = gl.getActiveUniform(p, i).name.replace(/\[0\]$/, '');
    uniforms[name] = gl.getUniformLocation(p, name);
  }
  return { program: p, uniforms };
}

async function loadMethodData(method) {
  if (method.json.data.pyramid) return loadPyramid(method);
  if (method.texture) return;
  if (!method.loading) {
    method.loading = (async () => {
      const { width, height } = state.manifest;
      const { file, layers } = method.json.data;
      const data = float32s(await fetchChecked(file, 'buffer'), file);
      if (data.length !== layers * width * height * 4) {
        throw new Error(`${file}: ${data.length} values, expected ${layers * width * height * 4}`);
      }
      if (layers > gl.getParameter(gl.MAX_ARRAY_TEXTURE_LAYERS)) {
        throw new Error(`${method.json.name}: ${layers} texture layers exceed this browser's limit`);
      }
      const texture = gl.createTexture();
      gl.bindTexture(gl.TEXTURE_2D_ARRAY, texture);
      gl.pixelStorei(gl.UNPACK_ALIGNMENT, 4);
      gl.texImage3D(gl.TEXTURE_2D_ARRAY, 0, gl.RGBA32F, width, height, layers, 0, gl.RGBA, gl.FLOAT, data);
      // Float textures are not filterable everywhere; texelFetch reads exact texels anyway.
      gl.texParameteri(gl.TEXTURE_2D_ARRAY, gl.TEXTURE_MIN_FILTER, gl.NEAREST);
      gl.texParameteri(gl.TEXTURE_2D_ARRAY, gl.TEXTURE_MAG_FILTER, gl.NEAREST);
      await loadDecoder(method);
      method.program = methodProgram(method);
      method.values = data; // for the pixel readout
      method.texture = texture;
    })();
  }
  await method.loading;
}

// ---- deep-zoom tiles ----------------------------------------------------------------------

// A tile's pixels in its level, overlap included (PyramidLayout::Tile), and the pixels it draws.
function tileRect(pyramid, level, column, row) {
  const [width, height] = pyramid.level_sizes[level];
  const t = pyramid.tile_size;
  const o = pyramid.overlap;
  const x = Math.max(column * t - o, 0);
  const y = Math.max(row * t - o, 0);
  return {
    x, y, width: Math.min((column + 1) * t + o, width) - x, height: Math.min((row + 1) * t + o, height) - y,
    core: [column * t, row * t, Math.min((column + 1) * t, width), Math.min((row + 1) * t, height)],
  };
}

function tileKey(method, level, column, row) {
  return `${method.json.name}/${level}/${column}_${row}`;
}

// The level whose pixels are at least as fine as the screen's: level L for zooms down to 2^-L.
function levelForZoom(pyramid) {
  const level = Math.floor(Math.log2(1 / state.zoom) + 1e-9);
  return Math.min(Math.max(level, 0), pyramid.levels - 1);
}

// The tiles of `level` that the canvas shows, widened by `margin` tiles on every side.
function tilesInView(pyramid, level, margin) {
  const [width, height] = pyramid.level_sizes[level];
  const scale = state.zoom * 2 ** level;
  const x0 = Math.max(Math.floor(-state.origin[0] / scale), 0);
  const y0 = Math.max(Math.floor(-state.origin[1] / scale), 0);
  const x1 = Math.min(Math.ceil((canvas.width - state.origin[0]) / scale), width);
  const y1 = Math.min(Math.ceil((canvas.height - state.origin[1]) / scale), height);
  if (x1 <= x0 || y1 <= y0) return [];
  const t = pyramid.tile_size;
  const columns = Math.ceil(width / t);
  const rows = Math.ceil(height / t);
  const list = [];
  for (let row = Math.max(Math.floor(y0 / t) - margin, 0); row <= Math.min(Math.floor((y1 - 1) / t) + margin, rows - 1); ++row) {
    for (let column = Math.max(Math.floor(x0 / t) - margin, 0); column <= Math.min(Math.floor((x1 - 1) / t) + margin, columns - 1); ++column) {
      list.push({ level, column, row });
    }
  }
  return list;
}

function loadTile(method, level, column, row) {
  const key = tileKey(method, level, column, row);
  if (tiles.cache.has(key)) return Promise.resolve();
  if (!tiles.loading.has(key)) {
    const pyramid = method.json.data.pyramid;
    const url = `${pyramid.folder}/${level}/${column}_${row}.f32`;
    const promise = (async () => {
      const rect = tileRect(pyramid, level, column, row);
      const { layers } = method.json.data;
      const values = float32s(await fetchChecked(url, 'buffer'), url);
      if (values.length !== layers * rect.width * rect.height * 4) {
        throw new Error(`${url}: ${values.length} values, expected ${layers * rect.width * rect.height * 4}`);
      }
      const texture = gl.createTexture();
      gl.bindTexture(gl.TEXTURE_2D_ARRAY, texture);
      gl.pixelStorei(gl.UNPACK_ALIGNMENT, 4);
      gl.texImage3D(gl.TEXTURE_2D_ARRAY, 0, gl.RGBA32F, rect.width, rect.height, layers, 0, gl.RGBA, gl.FLOAT, values);
      gl.texParameteri(gl.TEXTURE_2D_ARRAY, gl.TEXTURE_MIN_FILTER, gl.NEAREST);
      gl.texParameteri(gl.TEXTURE_2D_ARRAY, gl.TEXTURE_MAG_FILTER, gl.NEAREST);
      const pinned = level === pyramid.levels - 1;
      tiles.cache.set(key, { texture, values, rect, level, pinned, bytes: 2 * values.byteLength });
      tiles.bytes += 2 * values.byteLength;
      evictTiles();
    })().finally(() => {
      tiles.loading.delete(key);
      pumpTiles();
      requestDraw();
    });
    tiles.loading.set(key, promise);
  }
  return tiles.loading.get(key);
}

// Least recently used first, sparing the backdrop and the tiles the view wants.
function evictTiles() {
  if (tiles.bytes <= TILE_CACHE_BYTES) return;
  const wanted = new Set(tiles.wanted.map((w) => w.key));
  for (const [key, tile] of tiles.cache) {
    if (tiles.bytes <= TILE_CACHE_BYTES) break;
    if (tile.pinned || wanted.has(key)) continue;
    gl.deleteTexture(tile.texture);
    tiles.cache.delete(key);
    tiles.bytes -= tile.bytes;
  }
}

// Starts fetching wanted tiles, up to TILE_FETCHES at once.
function pumpTiles() {
  for (const w of tiles.wanted) {
    if (tiles.loading.size >= TILE_FETCHES) break;
    if (!tiles.cache.has(w.key) && !tiles.loading.has(w.key)) {
      loadTile(w.method, w.level, w.column, w.row).catch((e) => fail(e.message));
    }
  }
}

// What is shown: the current method when relit, else the current view.
function shownSource() {
  return state.view === 'relit' ? state.methods.get(state.method) : state.views.get(state.view);
}

// What the view needs of the method or view shown: its level's tiles in view and the margin.
function updateWantedTiles() {
  const method = shownSource();
  if (!method?.json.data?.pyramid || !canvas.width) {
    tiles.wanted = [];
    return;
  }
  const pyramid = method.json.data.pyramid;
  const level = levelForZoom(pyramid);
  // The tiles in view first, then the margin.
  const inView = tilesInView(pyramid, level, 0);
  const seen = new Set();
  tiles.wanted = [];
  for (const t of [...inView, ...tilesInView(pyramid, level, TILE_MARGIN)]) {
    const key = tileKey(method, t.level, t.column, t.row);
    if (!seen.has(key)) {
      seen.add(key);
      tiles.wanted.push({ method, key, ...t });
    }
  }
  pumpTiles();
}

// The pyramid's coarsest level (one tile): the backdrop every view starts from.
async function loadPyramid(method) {
  const { pyramid, layers } = method.json.data;
  if (layers > gl.getParameter(gl.MAX_ARRAY_TEXTURE_LAYERS)) {
    throw new Error(`${method.json.name}: ${layers} texture layers exceed this browser's limit`);
  }
  await loadDecoder(method);
  if (!method.program) method.program = methodProgram(method);
  await loadTile(method, pyramid.levels - 1, 0, 0);
  method.ready = true;
}

function drawTile(p, tile, scale) {
  const [cx0, cy0, cx1, cy1] = tile.rect.core;
  // The canvas pixels of the tile's core, widened to whole pixels (the shader clips exactly).
  const left = Math.max(Math.floor(state.origin[0] + cx0 * scale), 0);
  const top = Math.max(Math.floor(state.origin[1] + cy0 * scale), 0);
  const right = Math.min(Math.ceil(state.origin[0] + cx1 * scale), canvas.width);
  const bottom = Math.min(Math.ceil(state.origin[1] + cy1 * scale), canvas.height);
  if (right <= left || bottom <= top) return;
  gl.scissor(left, canvas.height - bottom, right - left, bottom - top);
  gl.bindTexture(gl.TEXTURE_2D_ARRAY, tile.texture);
  gl.uniform1f(p.uniforms.u_level_scale, 2 ** tile.level);
  gl.uniform2i(p.uniforms.u_tile_origin, tile.rect.x, tile.rect.y);
  gl.uniform2i(p.uniforms.u_core_min, cx0, cy0);
  gl.uniform2i(p.uniforms.u_core_max, cx1, cy1);
  gl.drawArrays(gl.TRIANGLES, 0, 3);
}

// The backdrop (coarsest level), then the loaded tiles of the level in view over it.
function drawPyramid(method, p) {
  const pyramid = method.json.data.pyramid;
  updateWantedTiles();
  gl.enable(gl.SCISSOR_TEST);
  const top = tiles.cache.get(tileKey(method, pyramid.levels - 1, 0, 0));
  if (top) drawTile(p, top, state.zoom * 2 ** top.level);
  for (const w of tiles.wanted) {
    const tile = tiles.cache.get(w.key);
    if (!tile || tile === top) continue;
    tiles.cache.delete(w.key); // most recently used: to the end of the Map's order
    tiles.cache.set(w.key, tile);
    drawTile(p, tile, state.zoom * 2 ** tile.level);
  }
  gl.disable(gl.SCISSOR_TEST);
}

// Wanted tiles not yet in the cache (and fetches under way).
function tilesPending() {
  updateWantedTiles();
  return tiles.wanted.filter((w) => !tiles.cache.has(w.key)).length + tiles.loading.size;
}

async function loadView(view) {
  if (view.json.data?.pyramid) {
    await loadTile(view, view.json.data.pyramid.levels - 1, 0, 0);
    view.ready = true;
    return;
  }
  if (view.texture) return;
  if (!view.loading) {
    view.loading = (async () => {
      const image = new Image();
      image.src = view.json.file;
      await image.decode();
      const texture = gl.createTexture();
      gl.bindTexture(gl.TEXTURE_2D, texture);
      gl.pixelStorei(gl.UNPACK_FLIP_Y_WEBGL, false);
      gl.pixelStorei(gl.UNPACK_PREMULTIPLY_ALPHA_WEBGL, false);
      gl.pixelStorei(gl.UNPACK_COLORSPACE_CONVERSION_WEBGL, gl.NONE);
      gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA8, gl.RGBA, gl.UNSIGNED_BYTE, image);
      gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.NEAREST);
      gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, gl.NEAREST);
      view.texture = texture;
    })();
  }
  await view.loading;
}

// ---- drawing -------------------------------------------------------------------------------

function resizeCanvas() {
  const ratio = window.devicePixelRatio || 1;
  const width = Math.max(1, Math.round(canvas.clientWidth * ratio));
  const height = Math.max(1, Math.round(canvas.clientHeight * ratio));
  if (canvas.width !== width || canvas.height !== height) {
    const centre = imageCentreOnCanvas();
    canvas.width = width;
    canvas.height = height;
    if (centre) {
      // Keep the image point at the centre in the centre.
      state.origin = [width / 2 - centre[0] * state.zoom, height / 2 - centre[1] * state.zoom];
    }
  }
}

function imageCentreOnCanvas() {
  if (!canvas.width || !state.manifest) return null;
  return [(canvas.width / 2 - state.origin[0]) / state.zoom, (canvas.height / 2 - state.origin[1]) / state.zoom];
}

function draw() {
  state.drawQueued = false;
  if (!gl || !state.manifest) return;
  resizeCanvas();
  gl.viewport(0, 0, canvas.width, canvas.height);
  gl.clearColor(0.067, 0.071, 0.078, 1);
  gl.clear(gl.COLOR_BUFFER_BIT);
  let p = null;
  if (state.view === 'relit') {
    const method = state.methods.get(state.method);
    if (!method || !(method.texture || method.ready)) return;
    p = method.program;
    gl.useProgram(p.program);
    if (method.decoder) {
      gl.activeTexture(gl.TEXTURE1);
      gl.bindTexture(gl.TEXTURE_2D, method.decoder.texture);
      gl.uniform1i(p.uniforms.u_decoder, 1);
    }
    gl.activeTexture(gl.TEXTURE0);
    gl.uniform1i(p.uniforms.u_maps, 0);
    gl.uniform1fv(p.uniforms.u_coefficients, Float32Array.from(method.basis.coefficients(state.light)));
    gl.uniform1f(p.uniforms.u_exposure, 2 ** state.exposure);
    if (method.json.data.pyramid) {
      setViewUniforms(p);
      drawPyramid(method, p);
      return;
    }
    // The whole image: one tile of level 0, scissored to the image's pixels on the canvas (a
    // neural decoder costs thousands of operations per fragment: none is spent off the image).
    setViewUniforms(p);
    const { width, height } = state.manifest;
    gl.enable(gl.SCISSOR_TEST);
    drawTile(p, { texture: method.texture, level: 0, rect: { x: 0, y: 0, core: [0, 0, width, height] } }, state.zoom);
    gl.disable(gl.SCISSOR_TEST);
    return;
  } else {
    const view = state.views.get(state.view);
    if (view?.ready) {
      p = viewTileProgram;
      gl.useProgram(p.program);
      gl.activeTexture(gl.TEXTURE0);
      gl.uniform1i(p.uniforms.u_maps, 0);
      gl.uniform1i(p.uniforms.u_grey, view.json.data.maps === 1 ? 1 : 0);
      setViewUniforms(p);
      drawPyramid(view, p);
      return;
    }
    if (!view || !view.texture) return;
    p = mapProgram;
    gl.useProgram(p.program);
    gl.activeTexture(gl.TEXTURE0);
    gl.bindTexture(gl.TEXTURE_2D, view.texture);
    gl.uniform1i(p.uniforms.u_image, 0);
  }
  setViewUniforms(p);
  gl.drawArrays(gl.TRIANGLES, 0, 3);
}

// Where the image is on the canvas.
function setViewUniforms(p) {
  gl.uniform2f(p.uniforms.u_origin, state.origin[0], state.origin[1]);
  gl.uniform1f(p.uniforms.u_zoom, state.zoom);
  gl.uniform1f(p.uniforms.u_canvas_height, canvas.height);
  gl.uniform2i(p.uniforms.u_size, state.manifest.width, state.manifest.height);
}

function requestDraw() {
  if (!state.drawQueued) {
    state.drawQueued = true;
    requestAnimationFrame(draw);
  }
}

// ---- light ---------------------------------------------------------------------------------

function setLightVector(light) {
  state.light = light;
  const slant = slantDegrees(light);
  const tilt = tiltDegrees(light);
  $('light-readout').textContent = `slant ${slant.toFixed(1)}°, tilt ${tilt.toFixed(1)}°`;
  if (document.activeElement !== $('slant-input')) $('slant-input').value = slant.toFixed(1);
  if (document.activeElement !== $('tilt-input')) $('tilt-input').value = tilt.toFixed(1);
  drawHemisphere();
  requestDraw();
}

function setLight(slant, tilt) {
  if (!Number.isFinite(slant) || !Number.isFinite(tilt)) return;
  setLightVector(lightFromSlantTilt(Math.min(Math.max(slant, 0), 90), ((tilt % 360) + 360) % 360));
}

// The light widget: slant * (cos tilt, sin tilt) on a disc (azimuthal equidistant, as photomat's
// light interpolation projects), rim at slant 90, tilt 0 to the right, 90 up.
function hemisphereGeometry() {
  const widget = $('hemisphere');
  const size = widget.width;
  return { widget, centre: size / 2, radius: size / 2 - 26 * (window.devicePixelRatio || 1) };
}

function drawHemisphere() {
  const { widget, centre, radius } = hemisphereGeometry();
  const ctx = widget.getContext('2d');
  const ratio = window.devicePixelRatio || 1;
  ctx.clearRect(0, 0, widget.width, widget.height);
  ctx.fillStyle = '#15171a';
  ctx.beginPath();
  ctx.arc(centre, centre, radius, 0, 2 * Math.PI);
  ctx.fill();
  ctx.strokeStyle = '#3a3e46';
  ctx.lineWidth = ratio;
  for (const slant of [30, 60, 90]) {
    ctx.beginPath();
    ctx.arc(centre, centre, (radius * slant) / 90, 0, 2 * Math.PI);
    ctx.stroke();
  }
  for (let tilt = 0; tilt < 360; tilt += 30) {
    const a = (tilt * Math.PI) / 180;
    ctx.beginPath();
    ctx.moveTo(centre, centre);
    ctx.lineTo(centre + radius * Math.cos(a), centre - radius * Math.sin(a));
    ctx.stroke();
  }
  ctx.fillStyle = '#9a9ea6';
  ctx.font = `${10 * ratio}px system-ui, sans-serif`;
  ctx.textAlign = 'center';
  ctx.textBaseline = 'middle';
  const label = radius + 10 * ratio;
  ctx.fillText('90', centre, centre - label);
  ctx.fillText('270', centre, centre + label);
  ctx.textAlign = 'left';
  ctx.fillText('0', centre + radius + 4 * ratio, centre);
  ctx.textAlign = 'right';
  ctx.fillText('180', centre - radius - 4 * ratio, centre);
  const toWidget = (l) => {
    const r = (radius * Math.min(slantDegrees(l), 90)) / 90;
    const t = (tiltDegrees(l) * Math.PI) / 180;
    return [centre + r * Math.cos(t), centre - r * Math.sin(t)];
  };
  ctx.fillStyle = '#6d7380';
  for (const l of state.manifest?.capture_lights ?? []) {
    const [x, y] = toWidget(l);
    ctx.beginPath();
    ctx.arc(x, y, 2 * ratio, 0, 2 * Math.PI);
    ctx.fill();
  }
  const [x, y] = toWidget(state.light);
  ctx.strokeStyle = '#f2c14e';
  ctx.lineWidth = 1.5 * ratio;
  ctx.beginPath();
  ctx.moveTo(centre, centre);
  ctx.lineTo(x, y);
  ctx.stroke();
  ctx.fillStyle = '#f2c14e';
  ctx.beginPath();
  ctx.arc(x, y, 5 * ratio, 0, 2 * Math.PI);
  ctx.fill();
}

function lightFromWidget(event) {
  const { widget, centre, radius } = hemisphereGeometry();
  const box = widget.getBoundingClientRect();
  const x = ((event.clientX - box.left) / box.width) * widget.width - centre;
  const y = centre - ((event.clientY - box.top) / box.height) * widget.height;
  setLight((Math.min(Math.hypot(x, y), radius) / radius) * 90, (Math.atan2(y, x) * 180) / Math.PI);
}

// Dragging on the image: the light points from the image centre toward the cursor, grazing at the
// edge of the smaller canvas side.
function lightFromImageDrag(event) {
  const box = canvas.getBoundingClientRect();
  const x = event.clientX - box.left - box.width / 2;
  const y = box.height / 2 - (event.clientY - box.top);
  const reach = Math.min(box.width, box.height) / 2;
  setLight(Math.min(Math.hypot(x, y) / reach, 1) * 90, (Math.atan2(y, x) * 180) / Math.PI);
}

// Exposure in stops: the linear values are scaled by 2^stops before the sRGB curve.
function setExposure(stops) {
  state.exposure = stops;
  $('exposure').value = stops;
  $('exposure-readout').textContent = `${stops > 0 ? '+' : ''}${stops} EV`;
  requestDraw();
}

// ---- zoom and pan --------------------------------------------------------------------------

function setZoom(zoom, anchor = [canvas.width / 2, canvas.height / 2]) {
  const z = Math.min(Math.max(zoom, 1 / 64), 64);
  state.origin = [anchor[0] - ((anchor[0] - state.origin[0]) * z) / state.zoom,
    anchor[1] - ((anchor[1] - state.origin[1]) * z) / state.zoom];
  state.zoom = z;
  $('zoom-readout').textContent = `${Math.round(z * 100)} %`;
  requestDraw();
}

function fitImage() {
  resizeCanvas();
  const { width, height } = state.manifest;
  // Enlargements by whole factors, so that every image pixel is drawn the same size.
  const fit = Math.min(canvas.width / width, canvas.height / height) * 0.96;
  const z = fit > 1 ? Math.floor(fit) : fit;
  state.zoom = z;
  state.origin = [(canvas.width - width * z) / 2, (canvas.height - height * z) / 2];
  $('zoom-readout').textContent = `${Math.round(z * 100)} %`;
  requestDraw();
}

// Zoom 1 with the image on whole canvas pixels: each canvas pixel is exactly one image pixel.
function actualPixels() {
  resizeCanvas();
  const centre = imageCentreOnCanvas() ?? [state.manifest.width / 2, state.manifest.height / 2];
  state.zoom = 1;
  state.origin = [Math.round(canvas.width / 2 - centre[0]), Math.round(canvas.height / 2 - centre[1])];
  $('zoom-readout').textContent = '100 %';
  requestDraw();
}

function centreImage() {
  resizeCanvas();
  const { width, height } = state.manifest;
  state.origin = [Math.round((canvas.width - width * state.zoom) / 2),
    Math.round((canvas.height - height * state.zoom) / 2)];
  requestDraw();
}

// ---- pixel readout -------------------------------------------------------------------------

// Map i of image pixel (x, y), from the whole maps or a loaded level-0 tile; null when not loaded.
function mapsAt(method, x, y) {
  const pyramid = method.json.data.pyramid;
  if (!pyramid) {
    if (!method.values) return null;
    const { width, height } = state.manifest;
    return (i) => method.values[((Math.floor(i / 4) * height + y) * width + x) * 4 + (i % 4)];
  }
  const t = pyramid.tile_size;
  const tile = tiles.cache.get(tileKey(method, 0, Math.floor(x / t), Math.floor(y / t)));
  if (!tile) return null;
  const { rect, values } = tile;
  return (i) => values[((Math.floor(i / 4) * rect.height + y - rect.y) * rect.width + x - rect.x) * 4 + (i % 4)];
}

// A pixel's relit values (every output channel) from its maps (`maps(i)`) and the light's
// coefficients `c`: what the method's shader computes.
function relitValues(method, maps, c) {
  const { layout, shading } = method.json;
  if (shading) {
    const codes = Array.from({ length: shading.coefficients }, (_, j) => maps(j));
    return evaluateDecoder(shading, method.decoder.values, codes, c[0], c[1]);
  }
  const perTerm = layout.basis_per_channel ? layout.output_channels : 1;
  const out = [];
  for (let o = 0; o < layout.output_channels; ++o) {
    let sum = 0;
    for (let j = 0; j < layout.basis_size; ++j) sum += c[j] * maps(j * perTerm + (layout.basis_per_channel ? o : 0));
    out.push(layout.has_gain ? sum * maps(layout.basis_size * perTerm + o) : sum);
  }
  return out;
}

function showPixel(event) {
  const box = canvas.getBoundingClientRect();
  const ratio = canvas.width / box.width;
  const x = Math.floor(((event.clientX - box.left) * ratio - state.origin[0]) / state.zoom);
  const y = Math.floor(((event.clientY - box.top) * ratio - state.origin[1]) / state.zoom);
  const { width, height } = state.manifest;
  const method = state.methods.get(state.method);
  const maps = x < 0 || y < 0 || x >= width || y >= height || !method ? null : mapsAt(method, x, y);
  if (!maps) {
    $('pixel-readout').textContent = '';
    return;
  }
  const out = relitValues(method, maps, method.basis.coefficients(state.light));
  const encoding = method.json.values === 'srgb' ? 'sRGB codes / 255' : 'linear';
  $('pixel-readout').textContent = `pixel ${x}, ${y}: ${out.map((v) => v.toFixed(4)).join(' ')} (${encoding})`;
}

// ---- user interface ------------------------------------------------------------------------

async function selectMethod(name) {
  const method = state.methods.get(name);
  if (!method) throw new Error(`no method "${name}"`);
  state.method = name;
  $('method').value = name;
  const layout = method.json.layout;
  const pyramid = method.json.data.pyramid;
  const terms = method.json.shading ? `a decoder of ${method.json.shading.layers.length} layers`
    : `${layout.basis_size} light terms`;
  $('method-info').textContent = `${method.json.channels.length} maps, ${terms}` +
    (method.json.basis.kind === 'table' ? ' (coefficients from a slant/tilt table)' : '') +
    (pyramid ? `; deep-zoom tiles of ${pyramid.tile_size} px, ${pyramid.levels} levels` : '');
  setStatus(`loading ${method.json.label}…`);
  await loadMethodData(method);
  if (state.method === name) {
    reportChecks();
    requestDraw();
  }
}

async function selectView(name) {
  if (name !== 'relit' && !state.views.has(name)) throw new Error(`no view "${name}"`);
  state.view = name;
  for (const input of document.querySelectorAll('#views input')) input.checked = input.value === name;
  const source = state.views.get(name)?.json;
  $('view-info').textContent = source
    ? `${source.label} map from the ${state.methods.get(source.source)?.json.label ?? source.source} fit` : '';
  if (name !== 'relit') await loadView(state.views.get(name));
  requestDraw();
}

function reportChecks() {
  const bad = state.checks.filter((c) => !c.ok);
  if (bad.length) {
    fail(`light basis mismatch with photomat: ${bad.map((c) => `${c.method} (${c.maxError.toExponential(1)})`).join(', ')}`);
  } else {
    const worst = Math.max(0, ...state.checks.map((c) => c.maxError));
    setStatus(`Light bases match photomat on ${state.checks.reduce((n, c) => n + c.lights, 0)} check lights ` +
      `(largest difference ${worst.toExponential(1)}).`, 'good');
  }
}

function buildInterface() {
  const manifest = state.manifest;
  document.title = `${manifest.title} · photomat viewer`;
  $('title').textContent = manifest.title;
  const select = $('method');
  for (const m of manifest.methods) {
    const option = document.createElement('option');
    option.value = m.name;
    option.textContent = m.label;
    select.append(option);
  }
  select.addEventListener('change', () => selectMethod(select.value).catch((e) => fail(e.message)));

  const views = $('views');
  const addView = (name, label) => {
    const wrapper = document.createElement('label');
    wrapper.innerHTML = `<input type="radio" name="view" value="${name}"> <span></span>`;
    wrapper.querySelector('span').textContent = label;
    wrapper.querySelector('input').addEventListener('change', () => selectView(name).catch((e) => fail(e.message)));
    views.append(wrapper);
  };
  addView('relit', 'Relit');
  for (const v of manifest.views) addView(v.name, v.label);
  views.querySelector('input').checked = true;

  const widget = $('hemisphere');
  const ratio = window.devicePixelRatio || 1;
  widget.width = widget.height = Math.round(220 * ratio);
  widget.addEventListener('pointerdown', (e) => {
    widget.setPointerCapture(e.pointerId);
    lightFromWidget(e);
  });
  widget.addEventListener('pointermove', (e) => {
    if (widget.hasPointerCapture(e.pointerId)) lightFromWidget(e);
  });

  for (const id of ['slant-input', 'tilt-input']) {
    $(id).addEventListener('input', () => setLight(parseFloat($('slant-input').value), parseFloat($('tilt-input').value)));
  }
  document.addEventListener('keydown', (e) => {
    if (e.target instanceof HTMLInputElement || e.target instanceof HTMLSelectElement) return;
    const slant = slantDegrees(state.light);
    const tilt = tiltDegrees(state.light);
    const moves = { ArrowLeft: [0, 5], ArrowRight: [0, -5], ArrowUp: [-5, 0], ArrowDown: [5, 0] };
    if (moves[e.key]) {
      setLight(slant + moves[e.key][0], tilt + moves[e.key][1]);
      e.preventDefault();
    }
  });

  $('exposure').addEventListener('input', () => setExposure(parseFloat($('exposure').value)));

  $('zoom-fit').addEventListener('click', fitImage);
  $('zoom-1').addEventListener('click', actualPixels);
  $('zoom-in').addEventListener('click', () => setZoom(state.zoom * 2));
  $('zoom-out').addEventListener('click', () => setZoom(state.zoom / 2));
  for (const radio of document.querySelectorAll('input[name="drag"]')) {
    radio.addEventListener('change', () => { state.dragMode = radio.value; });
  }

  let drag = null;
  canvas.addEventListener('contextmenu', (e) => e.preventDefault());
  canvas.addEventListener('pointerdown', (e) => {
    canvas.setPointerCapture(e.pointerId);
    const pan = state.dragMode === 'pan' || e.shiftKey || e.button !== 0;
    drag = { pan, x: e.clientX, y: e.clientY, origin: [...state.origin] };
    canvas.classList.add('dragging');
    if (!pan) lightFromImageDrag(e);
  });
  canvas.addEventListener('pointermove', (e) => {
    showPixel(e);
    if (!drag || !canvas.hasPointerCapture(e.pointerId)) return;
    if (drag.pan) {
      const ratio2 = canvas.width / canvas.getBoundingClientRect().width;
      state.origin = [drag.origin[0] + (e.clientX - drag.x) * ratio2, drag.origin[1] + (e.clientY - drag.y) * ratio2];
      requestDraw();
    } else {
      lightFromImageDrag(e);
    }
  });
  const endDrag = () => {
    drag = null;
    canvas.classList.remove('dragging');
  };
  canvas.addEventListener('pointerup', endDrag);
  canvas.addEventListener('pointercancel', endDrag);
  canvas.addEventListener('wheel', (e) => {
    e.preventDefault();
    const box = canvas.getBoundingClientRect();
    const ratio2 = canvas.width / box.width;
    setZoom(state.zoom * 2 ** (-e.deltaY / 400), [(e.clientX - box.left) * ratio2, (e.clientY - box.top) * ratio2]);
  }, { passive: false });
  new ResizeObserver(requestDraw).observe(canvas);
}

// ---- start ---------------------------------------------------------------------------------

async function start() {
  canvas = $('view');
  const manifest = await fetchChecked('viewer.json', 'json');
  if (manifest.format !== 'photomat-viewer' || manifest.version !== 1) {
    throw new Error('viewer.json is not a photomat viewer description (version 1)');
  }
  state.manifest = manifest;
  gl = canvas.getContext('webgl2', { antialias: false, alpha: false, premultipliedAlpha: false, preserveDrawingBuffer: true });
  if (!gl) throw new Error('this browser has no WebGL2');
  gl.bindVertexArray(gl.createVertexArray());
  mapProgram = program(MAP_SHADER);
  viewTileProgram = program(VIEW_TILE_SHADER);

  for (const m of manifest.methods) {
    const table = m.basis.kind === 'table' ? float32s(await fetchChecked(m.basis.file, 'buffer'), m.basis.file) : null;
    const basis = makeBasis(m.basis, table);
    const check = checkBasis(basis, m.check);
    state.checks.push({ method: m.name, ...check });
    if (!check.ok) console.error(`photomat viewer: ${m.name}: light basis differs from photomat by ${check.maxError}`);
    state.methods.set(m.name, { json: m, basis });
  }
  for (const v of manifest.views) state.views.set(v.name, { json: v });

  buildInterface();
  setLight(45, 0);
  fitImage();
  await selectMethod(manifest.methods[0].name);
  draw();
}

// For people at the console and for the browser test (viewer/test): everything the controls do.
const ready = start().catch((error) => {
  fail(error.message);
  throw error;
});

window.photomatViewer = {
  ready,
  methods: () => [...state.methods.keys()],
  views: () => ['relit', ...state.views.keys()],
  checks: () => state.checks.map((c) => ({ ...c })),
  setMethod: (name) => selectMethod(name),
  setView: (name) => selectView(name),
  setLight: (slant, tilt) => setLight(slant, tilt),
  setExposure: (stops) => setExposure(stops),
  fit: () => fitImage(),
  actualPixels: () => actualPixels(),
  centre: () => centreImage(),
  // The light disc in CSS pixels of the page: its centre and the radius of its rim (slant 90).
  lightDisc: () => {
    const { widget, centre, radius } = hemisphereGeometry();
    const box = widget.getBoundingClientRect();
    const scale = box.width / widget.width;
    return { x: box.left + centre * scale, y: box.top + centre * scale, radius: radius * scale };
  },
  state: () => ({
    method: state.method, view: state.view, slant: slantDegrees(state.light), tilt: tiltDegrees(state.light),
    light: [...state.light], zoom: state.zoom, origin: [...state.origin], canvas: [canvas.width, canvas.height],
  }),
  // Sets the zoom (canvas pixels per image pixel) and the canvas pixel of the image's top-left.
  setZoomOrigin: (zoom, origin) => {
    resizeCanvas();
    state.zoom = zoom;
    state.origin = [...origin];
    $('zoom-readout').textContent = `${Math.round(zoom * 100)} %`;
    updateWantedTiles();
    requestDraw();
  },
  // Deep-zoom: the tiles the view wants that have not loaded yet.
  tilesPending: () => tilesPending(),
  level: () => {
    const pyramid = shownSource()?.json.data?.pyramid;
    return pyramid ? levelForZoom(pyramid) : 0;
  },
  // Draws now and returns canvas pixels [x, x + width) x [y, y + height) (RGBA, rows from the top).
  readCanvas: (x, y, width, height) => {
    draw();
    const bottomUp = new Uint8Array(width * height * 4);
    gl.readPixels(x, canvas.height - y - height, width, height, gl.RGBA, gl.UNSIGNED_BYTE, bottomUp);
    const rows = new Uint8Array(width * height * 4);
    for (let r = 0; r < height; ++r) {
      rows.set(bottomUp.subarray((height - 1 - r) * width * 4, (height - r) * width * 4), r * width * 4);
    }
    return { width, height, rgba: Array.from(rows) };
  },
  // Draws now and returns the image's pixels as the canvas holds them (RGBA, rows from the top).
  // Needs zoom 1 (actualPixels) and the whole image on the canvas.
  readImagePixels: () => {
    draw();
    const { width, height } = state.manifest;
    const [x, y] = state.origin;
    if (state.zoom !== 1 || !Number.isInteger(x) || !Number.isInteger(y) || x < 0 || y < 0 ||
        x + width > canvas.width || y + height > canvas.height) {
      throw new Error('readImagePixels needs zoom 1 with the whole image on the canvas');
    }
    const bottomUp = new Uint8Array(width * height * 4);
    gl.readPixels(x, canvas.height - y - height, width, height, gl.RGBA, gl.UNSIGNED_BYTE, bottomUp);
    const rows = new Uint8Array(width * height * 4);
    for (let r = 0; r < height; ++r) {
      rows.set(bottomUp.subarray((height - 1 - r) * width * 4, (height - r) * width * 4), r * width * 4);
    }
    return { width, height, rgba: Array.from(rows) };
  },
};
