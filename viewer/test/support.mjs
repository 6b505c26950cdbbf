// Shared by the tests: the fixtures make-fixtures.mjs built, a static file server on localhost,
// Debian's Chromium through playwright-core, and PNG decoding.
import { createServer } from 'node:http';
import { readFileSync, existsSync, mkdirSync } from 'node:fs';
import path from 'node:path';
import { PNG } from 'pngjs';
import { chromium } from 'playwright-core';

export function loadFixtures() {
  const folder = process.env.PHOTOMAT_VIEWER_FIXTURES;
  if (!folder || !existsSync(path.join(folder, 'fixtures.json'))) {
    throw new Error('PHOTOMAT_VIEWER_FIXTURES must name a folder made by make-fixtures.mjs (run-browser-tests does both)');
  }
  return JSON.parse(readFileSync(path.join(folder, 'fixtures.json'), 'utf8'));
}

export function screenshotFolder(fixtures) {
  const folder = process.env.PHOTOMAT_SCREENSHOTS ?? path.join(fixtures.out, 'screenshots');
  mkdirSync(folder, { recursive: true });
  return folder;
}

const TYPES = {
  '.html': 'text/html; charset=utf-8',
  '.js': 'text/javascript; charset=utf-8',
  '.mjs': 'text/javascript; charset=utf-8',
  '.css': 'text/css; charset=utf-8',
  '.json': 'application/json',
  '.png': 'image/png',
};

// A plain static file server over `root` on 127.0.0.1 (any free port): what a user's
// `python3 -m http.server` does, nothing more.
export async function serve(root) {
  const server = createServer((request, response) => {
    const url = new URL(request.url, 'http://localhost');
    const file = path.join(root, decodeURIComponent(url.pathname));
    if (!file.startsWith(root) || !existsSync(file)) {
      response.writeHead(404).end('not found');
      return;
    }
    const target = file.endsWith(path.sep) ? path.join(file, 'index.html') : file;
    try {
      const body = readFileSync(target);
      response.writeHead(200, { 'Content-Type': TYPES[path.extname(target)] ?? 'application/octet-stream' });
      response.end(body);
    } catch {
      response.writeHead(404).end('not found');
    }
  });
  await new Promise((resolve) => server.listen(0, '127.0.0.1', resolve));
  return { url: `http://127.0.0.1:${server.address().port}/`, close: () => new Promise((r) => server.close(r)) };
}

// Debian's Chromium (scripts/debian-packages.txt), headless, software WebGL through SwiftShader.
// The background-networking flags keep it from reaching for Google's hosts on a closed network.
export function launchBrowser() {
  return chromium.launch({
    executablePath: process.env.CHROMIUM ?? '/usr/bin/chromium',
    headless: true,
    args: [
      '--no-sandbox', '--disable-gpu', '--use-angle=swiftshader', '--enable-unsafe-swiftshader',
      '--disable-quic', '--no-first-run', '--disable-background-networking', '--disable-component-update',
      '--disable-sync', '--disable-default-apps', '--disable-extensions',
    ],
  });
}

// A page that records console errors, uncaught exceptions, failed requests and any request that
// leaves the static server.
export async function openPage(browser, url, viewport = { width: 1200, height: 820 }) {
  const page = await browser.newPage({ viewport, deviceScaleFactor: 1 });
  const problems = [];
  page.on('console', (message) => {
    if (message.type() === 'error') problems.push(`console error: ${message.text()}`);
  });
  page.on('pageerror', (error) => problems.push(`page error: ${error.message}`));
  page.on('requestfailed', (request) => problems.push(`request failed: ${request.url()}`));
  // Nothing but the folder it is served from: no network access at run time.
  const origin = new URL(url).origin;
  page.on('request', (request) => {
    const requested = request.url();
    if (!requested.startsWith(`${origin}/`) && !requested.startsWith('data:')) {
      problems.push(`request outside the served folder: ${requested}`);
    }
  });
  page.on('response', (response) => {
    if (response.status() >= 400) problems.push(`HTTP ${response.status()}: ${response.url()}`);
  });
  await page.goto(url, { waitUntil: 'load' });
  return { page, problems };
}

export function readPng(file) {
  return PNG.sync.read(readFileSync(file));
}
