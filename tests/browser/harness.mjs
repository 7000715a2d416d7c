// What the measurement scripts (fit_timing, anim_profile, texture_timing,
// screenshots) share: a static server for WEBDIR on 127.0.0.1 (a free port)
// and Debian's Chromium with the flags TOOLCHAIN.md verified (SwiftShader
// WebGL2, no network side channels), in a fresh profile folder.
import { chromium } from 'playwright-core';
import http from 'node:http';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';

const MIME = { '.html': 'text/html', '.js': 'text/javascript', '.css': 'text/css', '.wasm': 'application/wasm',
               '.json': 'application/json', '.png': 'image/png', '.txt': 'text/plain' };

// Serves the files under root; anything outside it or missing is a 404.
export async function serveDir(root) {
  const server = http.createServer((req, res) => {
    const file = path.join(root, path.normalize(decodeURIComponent(new URL(req.url, 'http://x').pathname)));
    if (!file.startsWith(root) || !fs.existsSync(file) || fs.statSync(file).isDirectory()) { res.writeHead(404); res.end(); return; }
    res.writeHead(200, { 'content-type': MIME[path.extname(file)] || 'application/octet-stream' });
    fs.createReadStream(file).pipe(res);
  });
  await new Promise((ok) => server.listen(0, '127.0.0.1', ok));
  return server;
}

// The context's profile folder is context.userDir (remove it when done).
export async function launchChromium(name, viewport) {
  const userDir = fs.mkdtempSync(path.join(os.tmpdir(), `likeness-${name}-`));
  const context = await chromium.launchPersistentContext(userDir, {
    executablePath: '/usr/bin/chromium', headless: true,
    args: ['--no-sandbox', '--disable-quic', '--no-first-run', '--disable-background-networking',
           '--disable-component-update', '--disable-sync', '--use-angle=swiftshader', '--enable-unsafe-swiftshader'],
    viewport, deviceScaleFactor: 1,
  });
  context.userDir = userDir;
  return context;
}
