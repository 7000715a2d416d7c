// What the browser tests share: the page test (test.mjs, which runs the
// flows in flows/) and the measurement scripts (fit_timing, anim_profile,
// texture_timing, screenshots).
//   - a static server for WEBDIR on 127.0.0.1 (a free port), with the cross-
//     origin isolation headers or without, and files it can be told to break;
//   - Debian's Chromium with the flags TOOLCHAIN.md verified (SwiftShader
//     WebGL2, no network side channels), in a fresh profile folder;
//   - check() and the summary, waits on the page's state, screenshots and
//     the canvas' pixels;
//   - a Session: one server and one browser for a run of flows, the main
//     page and the fixtures (e.g. the fitted head) that flows share, and the
//     checks every run ends with (no console errors, no foreign request).
// The test inputs (scans, photos, PNG decoding) are in fixtures.mjs, re-exported here.
import { chromium } from 'playwright-core';
import http from 'node:http';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { decodePng } from './fixtures.mjs';

export * from './fixtures.mjs';

export const READY_TIMEOUT_MS = 180000;  // SwiftShader compiles shaders on the CPU
export const JOB_TIMEOUT_MS = 120000;
export const SHOT_DIR = process.env.LK_SCREENSHOT_DIR || '';
// The real scans and photos beside the repository (../shared/data; LK_SHARED_DATA
// overrides), never committed: flows that read them skip where they are absent.
export const SHARED_DATA = process.env.LK_SHARED_DATA ||
  path.resolve(path.dirname(fileURLToPath(import.meta.url)), '../../../shared/data');

// ---------------------------------------------------------- static server --
const MIME = {
  '.html': 'text/html; charset=utf-8', '.js': 'text/javascript; charset=utf-8',
  '.mjs': 'text/javascript; charset=utf-8', '.css': 'text/css; charset=utf-8',
  '.wasm': 'application/wasm', '.png': 'image/png', '.json': 'application/json', '.txt': 'text/plain',
  '.webmanifest': 'application/manifest+json',
};

// Serves the files under root; anything outside it or missing is a 404.
// Like scripts/serve.py, every response carries COOP: same-origin + COEP:
// require-corp, so the page is cross-origin isolated and its worker runs the
// threaded core; { isolation: false } leaves them out (a host without the
// headers: the single-threaded core). broken: {path: '404' | 'hang' |
// 'corrupt'} answers that file with a 404, never (a browser that cannot
// start a worker from it), or with bytes that are not the file; it is read
// per request, so a test may change it while the page runs.
// server.requests lists every path asked; server.closeAll() also ends the
// unanswered requests.
export async function serveDir(root, { isolation = true, broken = {} } = {}) {
  const requests = [], held = [];
  const isolationHeaders = isolation
    ? { 'cross-origin-opener-policy': 'same-origin', 'cross-origin-embedder-policy': 'require-corp' } : {};
  const server = http.createServer((req, res) => {
    requests.push(req.url);
    const url = new URL(req.url, 'http://x');
    const rel = decodeURIComponent(url.pathname === '/' ? '/index.html' : url.pathname);
    const file = path.join(root, path.normalize(rel));
    if (broken[rel] === 'hang') {
      held.push(res);
      return;
    }
    if (broken[rel] === 'corrupt') {  // the right name and type, wrong bytes (a broken upload or cache)
      res.writeHead(200, { 'content-type': MIME[path.extname(file)] || 'application/octet-stream',
                           'cache-control': 'no-store', ...isolationHeaders });
      res.end(Buffer.concat([Buffer.from('<!doctype html><title>Moved</title>'), Buffer.alloc(4000, 0x41)]));
      return;
    }
    if (broken[rel] === '404' || !file.startsWith(root) || !fs.existsSync(file) || fs.statSync(file).isDirectory()) {
      res.writeHead(404, { 'content-type': 'text/plain', ...isolationHeaders });
      res.end('not found');
      return;
    }
    res.writeHead(200, { 'content-type': MIME[path.extname(file)] || 'application/octet-stream',
                         'cache-control': 'no-store', ...isolationHeaders });
    fs.createReadStream(file).pipe(res);
  });
  server.requests = requests;
  server.closeAll = () => {
    for (const res of held) res.destroy();
    server.close();
  };
  await new Promise((ok) => server.listen(0, '127.0.0.1', ok));
  return server;
}

// Removes `--name value` from args and returns value, or fallback if absent.
export function takeOption(args, name, fallback) {
  const i = args.indexOf(name);
  if (i < 0) return fallback;
  const v = args[i + 1];
  args.splice(i, 2);
  return v;
}

// Removes `--name` from args; true if it was there.
export function takeFlag(args, name) {
  const i = args.indexOf(name);
  if (i >= 0) args.splice(i, 1);
  return i >= 0;
}

// ---------------------------------------------------------------- browser --
// Closes what launchChromium and serveDir opened, and the profile folder.
export async function closeChromium(context, server) {
  await context.close();
  if (server) server.closeAll();
  fs.rmSync(context.userDir, { recursive: true, force: true });
}

// The context's profile folder is context.userDir (remove it with closeChromium).
// hasTouch: a touch screen; isMobile: a phone's browser (its viewport
// meta tag honoured, pointer: coarse); args: more Chromium flags (e.g. --disable-webgl);
// serviceWorkers 'block' by default (page.route does not see what a service
// worker fetches), 'allow' for the offline flow.
// Env LK_CHROMIUM_FLAGS adds Chromium flags for an experiment (space-separated,
// e.g. "--js-flags=--no-wasm-dynamic-tiering").
export async function launchChromium(name, viewport, { hasTouch = false, isMobile = false, args = [], serviceWorkers = 'block' } = {}) {
  const userDir = fs.mkdtempSync(path.join(os.tmpdir(), `likeness-${name}-`));
  const context = await chromium.launchPersistentContext(userDir, {
    executablePath: '/usr/bin/chromium', headless: true,
    args: ['--no-sandbox', '--disable-quic', '--no-first-run', '--disable-background-networking',
           '--disable-component-update', '--disable-sync', '--use-angle=swiftshader', '--enable-unsafe-swiftshader',
           ...args, ...(process.env.LK_CHROMIUM_FLAGS || '').split(' ').filter(Boolean)],
    viewport, deviceScaleFactor: 1, hasTouch, isMobile, serviceWorkers,
  });
  context.userDir = userDir;
  return context;
}

// ----------------------------------------------------------------- checks --
export const results = [];
export function check(name, ok, detail = '') {
  results.push({ name, ok: !!ok, detail });
  console.log(`${ok ? 'PASS' : 'FAIL'}  ${name}${detail ? '  (' + detail + ')' : ''}`);
  return !!ok;
}

// Something not exercised, or a number worth seeing beside the checks.
export function note(text) { console.log('note  ' + text); }

// ------------------------------------------------------------------- page --
export async function state(page) { return page.evaluate(() => document.body.dataset.state); }

export async function waitForState(page, wanted, timeout = JOB_TIMEOUT_MS) {
  await page.waitForFunction((w) => w.includes(document.body.dataset.state), wanted, { timeout });
  return state(page);
}

// Waits until the job an action started has finished (the state leaves
// "working"; it does so synchronously, or the job starts first).
export async function settled(page) {
  await page.waitForFunction(() => document.body.dataset.state !== 'working', null, { timeout: JOB_TIMEOUT_MS });
}

export async function setFile(page, name, buffer, mimeType = 'application/octet-stream') {
  await page.setInputFiles('#file-input', { name, mimeType, buffer });
  await settled(page);
  return state(page);
}

// The error banner's text when it is shown, else ''.
export async function bannerText(page) {
  return page.evaluate(() => {
    const b = document.getElementById('error-banner');
    const visible = !b.hidden && b.getBoundingClientRect().height > 0;
    return visible ? document.getElementById('error-text').textContent : '';
  });
}

export async function shot(page, name) {
  if (!SHOT_DIR) return;
  fs.mkdirSync(SHOT_DIR, { recursive: true });
  await page.screenshot({ path: path.join(SHOT_DIR, name) });
}

// The canvas as {width, height, data RGBA}, without the toolbar and hint on it.
const HIDE_OVERLAYS = '.toolbar, .hint { visibility: hidden !important; }';
export async function canvasImage(page) {
  // Give the viewer a few animation frames to draw what it was just given.
  await page.evaluate(() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(() => requestAnimationFrame(r)))));
  const png = await page.locator('#canvas').screenshot({ style: HIDE_OVERLAYS });
  return decodePng(png);
}

// The background is a vertical gradient, so each row's background color is
// read at the right edge (the toolbar and hint sit on the left). A pixel
// differing from it by more than 24 in some channel is "foreground".
export function analyse(img) {
  const { width, height, data } = img;
  let fg = 0, green = 0, sum = 0, sum2 = 0;
  for (let y = 0; y < height; y++) {
    const ref = [0, 0, 0];
    for (let x = width - 5; x < width - 1; x++) for (let k = 0; k < 3; k++) ref[k] += data[(y * width + x) * 4 + k] / 4;
    for (let x = 0; x < width; x++) {
      const i = (y * width + x) * 4, r = data[i], g = data[i + 1], b = data[i + 2];
      if (Math.max(Math.abs(r - ref[0]), Math.abs(g - ref[1]), Math.abs(b - ref[2])) > 24) {
        fg++;
        const lum = 0.2126 * r + 0.7152 * g + 0.0722 * b;
        sum += lum; sum2 += lum * lum;
      }
      if (g > r + 60 && g > b + 60) green++;
    }
  }
  const n = width * height;
  const mean = fg ? sum / fg : 0;
  return { fgFraction: fg / n, greenFraction: green / n, lumStd: fg ? Math.sqrt(Math.max(0, sum2 / fg - mean * mean)) : 0 };
}

// The share of pixels whose colours differ by more than 30 (summed over RGB).
export function differingFraction(a, b) {
  if (a.width !== b.width || a.height !== b.height) return 1;
  let d = 0;
  for (let i = 0; i < a.data.length; i += 4) {
    if (Math.abs(a.data[i] - b.data[i]) + Math.abs(a.data[i + 1] - b.data[i + 1]) +
        Math.abs(a.data[i + 2] - b.data[i + 2]) > 30) d++;
  }
  return d / (a.width * a.height);
}

// The last fit as comparable text: every stage's numbers at full precision
// (not the times) and a checksum of every mesh's vertex and index bytes.
export async function fitFingerprint(page) {
  return page.evaluate(() => {
    const fit = window.likeness.fit;
    const report = JSON.stringify(fit.stages.map((s) => Object.fromEntries(Object.entries(s)
      .filter(([k, v]) => typeof v === 'number' && !/ms$/i.test(k)))));
    // FNV-1a over the bytes of every typed array in the meshes, in key order.
    let hash = 0x811c9dc5, bytes = 0;
    const visit = (v) => {
      if (ArrayBuffer.isView(v)) {
        const b = new Uint8Array(v.buffer, v.byteOffset, v.byteLength);
        for (let i = 0; i < b.length; i++) { hash ^= b[i]; hash = Math.imul(hash, 0x01000193) >>> 0; }
        bytes += b.length;
      } else if (v && typeof v === 'object') for (const k of Object.keys(v).sort()) visit(v[k]);
    };
    visit(fit.meshes);
    return { report, meshes: `${bytes} bytes, fnv ${hash.toString(16)}`, fitMs: fit.fitMs };
  });
}

// ---------------------------------------------------------------- session --
// One run of flows: the page's server (COOP/COEP), one Chromium (1280 x 800,
// a touch screen) opened on first use, and what the flows share through
// once(): the main page, the fitted head. Every page of that browser is
// checked for requests off the page's origins; watched pages for console errors.
export class Session {
  constructor(webdir) {
    this.webdir = webdir;
    this.ownOrigins = [];
    this.consoleErrors = [];
    this.requests = [];
    this.foreign = [];
    this.servers = [];
    this.shared = new Map();
  }

  async open() {
    const { origin } = await this.serve();
    this.origin = origin;
  }

  // The value of make(), made once per session (a promise: flows await it).
  once(key, make) {
    if (!this.shared.has(key)) this.shared.set(key, make());
    return this.shared.get(key);
  }

  // A server of WEBDIR (serveDir's options); its origin counts as the page's own.
  async serve(options) {
    const server = await serveDir(this.webdir, options);
    const origin = `http://127.0.0.1:${server.address().port}`;
    this.servers.push(server);
    this.ownOrigins.push(origin);
    return { server, origin };
  }

  context() {
    return this.once('context', async () => this.watchRequests(await launchChromium('test', { width: 1280, height: 800 }, { hasTouch: true })));
  }

  // Counts a browser context's requests, and those off the page's origins
  // (a flow's own browser too); returns the context.
  watchRequests(context) {
    context.on('request', (req) => {
      const url = req.url();
      this.requests.push(url);
      if (!(this.ownOrigins.some((o) => url.startsWith(o + '/')) || url.startsWith('data:') || url.startsWith('blob:'))) this.foreign.push(url);
    });
    return context;
  }

  // Console errors and uncaught exceptions of this page fail the run.
  watch(page) {
    page.on('console', (m) => { if (m.type() === 'error') this.consoleErrors.push(m.text()); });
    if (process.env.LK_CONSOLE) page.on('console', (m) => console.log('console:', m.type(), m.text()));  // debugging a flow
    page.on('pageerror', (e) => this.consoleErrors.push('uncaught: ' + e.message));
    return page;
  }

  // A new watched page at origin/index.html + query, once "ready" (or "error").
  async newPage(query = '', { origin = this.origin } = {}) {
    const page = this.watch(await (await this.context()).newPage());
    await page.goto(origin + '/index.html' + query);
    await waitForState(page, ['ready', 'error'], READY_TIMEOUT_MS);
    return page;
  }

  // The main page (index.html without parameters), opened once:
  // {page, state, wallMs} as it started.
  mainPage() {
    return this.once('main page', async () => {
      const context = await this.context();
      const page = this.watch(context.pages()[0] || await context.newPage());
      const t0 = Date.now();
      await page.goto(this.origin + '/index.html');
      const s = await waitForState(page, ['ready', 'error'], READY_TIMEOUT_MS).catch((e) => 'not ready: ' + e.message.split('\n')[0]);
      return { page, state: s, wallMs: Date.now() - t0 };
    });
  }

  // The main page, ready: flows that need it stop here when it did not start.
  async page() {
    const main = await this.mainPage();
    if (main.state !== 'ready') throw new Error('the page did not start (state ' + main.state + ')');
    return main.page;
  }

  async close() {
    const context = this.shared.has('context') && await this.shared.get('context').catch(() => null);
    if (context) {
      await context.close().catch(() => {});
      fs.rmSync(context.userDir, { recursive: true, force: true });
    }
    for (const server of this.servers) if (server.listening) server.closeAll();
  }
}

// Runs the flows in order in one session and exits 0 when every check
// passed. argv: WEBDIR [flow name ...] (names: only those flows; each sets
// up what it needs). A flow that throws fails with its message; the next
// one still runs.
export async function runFlows(flows, argv = process.argv.slice(2)) {
  const webdir = path.resolve(argv[0] || '');
  if (!fs.existsSync(path.join(webdir, 'index.html'))) {
    console.error(`FAILED: ${webdir}/index.html not found`);
    process.exit(1);
  }
  const only = argv.slice(1);
  const unknown = only.filter((n) => !flows.some((f) => f.name === n));
  if (unknown.length) {
    console.error(`FAILED: no flow named ${unknown.join(', ')} (flows: ${flows.map((f) => f.name).join(', ')})`);
    process.exit(2);
  }
  const s = new Session(webdir);
  await s.open();
  const t0 = Date.now();
  for (const flow of flows.filter((f) => !only.length || only.includes(f.name))) {
    console.log(`\n== ${flow.name}: ${flow.title}`);
    const first = results.length, tFlow = Date.now();
    try {
      await flow.run(s);
    } catch (e) {
      check(`${flow.name}: the flow ran to the end`, false, e && e.message ? e.message.split('\n')[0] : String(e));
    }
    const mine = results.slice(first);
    for (const r of mine) r.flow = flow.name;  // named again at the end when failed
    console.log(`== ${flow.name}: ${mine.filter((r) => r.ok).length}/${mine.length} checks passed in ${((Date.now() - tFlow) / 1000).toFixed(1)} s`);
  }
  if (s.shared.has('context') || s.requests.length) {  // a flow with a browser of its own counts too
    console.log('\n== the whole run');
    check('no console errors', s.consoleErrors.length === 0, s.consoleErrors.slice(0, 5).join(' | '));
    check('every request goes to the page\'s own origin', s.foreign.length === 0 && s.requests.length > 0,
          s.foreign.length ? s.foreign.slice(0, 5).join(', ') : `${s.requests.length} requests, all to ${s.ownOrigins.join(' and ')}`);
  }
  await s.close();
  const failed = results.filter((r) => !r.ok);
  // Repeated last, so the tail of a long log (all CI keeps) names what failed.
  for (const r of failed) console.log(`FAILED  ${r.flow ? r.flow + ': ' : ''}${r.name}${r.detail ? '  (' + String(r.detail).slice(0, 600) + ')' : ''}`);
  console.log(`\nbrowser test: ${results.length - failed.length}/${results.length} checks passed in ` +
              `${((Date.now() - t0) / 1000).toFixed(0)} s` + (SHOT_DIR ? `; screenshots in ${SHOT_DIR}` : ''));
  process.exit(failed.length ? 1 : 0);
}

// At the end of a flow file: `node flows/<file>.mjs WEBDIR` runs that flow alone.
export function runAlone(moduleUrl, flow) {
  if (process.argv[1] && path.resolve(process.argv[1]) === fileURLToPath(moduleUrl)) runFlows([flow]);
}
