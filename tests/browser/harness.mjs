// What the measurement scripts (fit_timing, anim_profile, texture_timing,
// screenshots) share: a static server for WEBDIR on 127.0.0.1 (a free port)
// and Debian's Chromium with the flags TOOLCHAIN.md verified (SwiftShader
// WebGL2, no network side channels), in a fresh profile folder.
import { chromium } from 'playwright-core';
import http from 'node:http';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import zlib from 'node:zlib';

const MIME = { '.html': 'text/html', '.js': 'text/javascript', '.css': 'text/css', '.wasm': 'application/wasm',
               '.json': 'application/json', '.png': 'image/png', '.txt': 'text/plain' };

// Serves the files under root; anything outside it or missing is a 404.
// Like scripts/serve.py, every response carries COOP: same-origin + COEP:
// require-corp, so the page is cross-origin isolated and its worker runs the
// threaded core; { isolation: false } leaves them out (a host without the
// headers: the single-threaded core). server.requests lists every path asked.
export async function serveDir(root, { isolation = true } = {}) {
  const requests = [];
  const isolationHeaders = isolation
    ? { 'cross-origin-opener-policy': 'same-origin', 'cross-origin-embedder-policy': 'require-corp' } : {};
  const server = http.createServer((req, res) => {
    requests.push(req.url);
    const file = path.join(root, path.normalize(decodeURIComponent(new URL(req.url, 'http://x').pathname)));
    if (!file.startsWith(root) || !fs.existsSync(file) || fs.statSync(file).isDirectory()) { res.writeHead(404, isolationHeaders); res.end(); return; }
    res.writeHead(200, { 'content-type': MIME[path.extname(file)] || 'application/octet-stream', ...isolationHeaders });
    fs.createReadStream(file).pipe(res);
  });
  await new Promise((ok) => server.listen(0, '127.0.0.1', ok));
  server.requests = requests;
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

// Closes what launchChromium and serveDir opened, and the profile folder.
export async function closeChromium(context, server) {
  await context.close();
  server.close();
  fs.rmSync(context.userDir, { recursive: true, force: true });
}

// The context's profile folder is context.userDir (remove it with closeChromium).
// Env LK_CHROMIUM_FLAGS adds Chromium flags for an experiment (space-separated,
// e.g. "--js-flags=--no-wasm-dynamic-tiering").
export async function launchChromium(name, viewport) {
  const userDir = fs.mkdtempSync(path.join(os.tmpdir(), `likeness-${name}-`));
  const context = await chromium.launchPersistentContext(userDir, {
    executablePath: '/usr/bin/chromium', headless: true,
    args: ['--no-sandbox', '--disable-quic', '--no-first-run', '--disable-background-networking',
           '--disable-component-update', '--disable-sync', '--use-angle=swiftshader', '--enable-unsafe-swiftshader',
           ...(process.env.LK_CHROMIUM_FLAGS || '').split(' ').filter(Boolean)],
    viewport, deviceScaleFactor: 1,
  });
  context.userDir = userDir;
  return context;
}

// An 8-bit RGB/RGBA PNG (as page.screenshot writes) -> {width, height, data RGBA}.
export function decodePng(buf) {
  let pos = 8, width = 0, height = 0, colorType = 0;
  const idat = [];
  while (pos < buf.length) {
    const len = buf.readUInt32BE(pos);
    const type = buf.toString('ascii', pos + 4, pos + 8);
    const data = buf.subarray(pos + 8, pos + 8 + len);
    if (type === 'IHDR') {
      width = data.readUInt32BE(0); height = data.readUInt32BE(4);
      if (data[8] !== 8 || data[12] !== 0) throw new Error('unsupported PNG (bit depth/interlace)');
      colorType = data[9];
    } else if (type === 'IDAT') idat.push(data);
    pos += 12 + len;
  }
  const channels = colorType === 6 ? 4 : colorType === 2 ? 3 : 0;
  if (!channels) throw new Error('unsupported PNG color type ' + colorType);
  const raw = zlib.inflateSync(Buffer.concat(idat));
  const stride = width * channels;
  const out = Buffer.alloc(width * height * 4);
  const prev = Buffer.alloc(stride), cur = Buffer.alloc(stride);
  for (let y = 0; y < height; y++) {
    const filter = raw[y * (stride + 1)];
    const line = raw.subarray(y * (stride + 1) + 1, (y + 1) * (stride + 1));
    for (let i = 0; i < stride; i++) {
      const a = i >= channels ? cur[i - channels] : 0, b = prev[i], c = i >= channels ? prev[i - channels] : 0;
      let v = line[i];
      if (filter === 1) v += a;
      else if (filter === 2) v += b;
      else if (filter === 3) v += (a + b) >> 1;
      else if (filter === 4) {
        const p = a + b - c, pa = Math.abs(p - a), pb = Math.abs(p - b), pc = Math.abs(p - c);
        v += pa <= pb && pa <= pc ? a : pb <= pc ? b : c;
      }
      cur[i] = v & 255;
    }
    for (let x = 0; x < width; x++) {
      out[(y * width + x) * 4] = cur[x * channels];
      out[(y * width + x) * 4 + 1] = cur[x * channels + 1];
      out[(y * width + x) * 4 + 2] = cur[x * channels + 2];
      out[(y * width + x) * 4 + 3] = channels === 4 ? cur[x * channels + 3] : 255;
    }
    cur.copy(prev);
  }
  return { width, height, data: out };
}
