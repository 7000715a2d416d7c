// Times the Texture stage in Chromium (SwiftShader, this machine) on the
// page's built-in sample: "Try the sample" loads sample/scan.ply with the
// synthetic photos and points files listed in sample/texture.json (scripts/demo
// makes them), "Fit head", then "Texture" RUNS times; prints the worker's
// per-step ms, each photo's calibration and the wall time click-to-done.
// Not a test: a measurement. --shots DIR also writes the docs pictures:
// DIR/web_texture_result.png (the textured head), web_texture_clicks.png (a
// photo in the clicker with its points and reprojection errors) and
// web_fit_animate.png (the textured head mid-animation, eyes and teeth shown).
// Usage: node texture_timing.mjs WEBDIR [--runs N] [--shots DIR]
import { closeChromium, launchChromium, serveDir, takeFlag, takeOption } from './harness.mjs';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';

const args = process.argv.slice(2);
const runs = Math.max(1, Number(takeOption(args, '--runs', 1)) || 1);
const shots = takeOption(args, '--shots', '');
const [webdir] = args;
if (!webdir) { console.error('usage: node texture_timing.mjs WEBDIR [--runs N] [--shots DIR]'); process.exit(2); }
const root = path.resolve(webdir);
if (!fs.existsSync(path.join(root, 'sample', 'texture.json'))) {
  console.error(`no ${root}/sample/texture.json: scripts/demo makes the sample photos`);
  process.exit(2);
}
const server = await serveDir(root);
const context = await launchChromium('texture', { width: 1280, height: 1000 });
let status = 0;
const settle = (page) => page.evaluate(() => new Promise((ok) => requestAnimationFrame(() => requestAnimationFrame(ok))));
try {
  const page = context.pages()[0] || await context.newPage();
  page.on('pageerror', (e) => console.log('page error:', e.message));
  await page.goto(`http://127.0.0.1:${server.address().port}/index.html?autofit=0`);
  await page.waitForFunction(() => document.body.dataset.state === 'ready', null, { timeout: 180000 });
  await page.click('#btn-sample');
  await page.waitForFunction(() => ['done', 'error'].includes(document.body.dataset.state) && window.likeness.photos.length, null, { timeout: 180000 });
  console.log('photos:', (await page.evaluate(() => window.likeness.photos.map((p) => `${p.name} ${p.width}x${p.height}`))).join(', '));
  await page.click('#btn-fit');
  await page.waitForFunction(() => document.body.dataset.state !== 'working', null, { timeout: 600000 });
  if (!(await page.evaluate(() => !!window.likeness.fit))) throw new Error('fit failed: ' + await page.textContent('#error-text'));
  for (let i = 0; i < runs; i++) {
    const t0 = Date.now();
    await page.click('#btn-texture');
    await page.waitForFunction(() => document.body.dataset.state !== 'working', null, { timeout: 600000 });
    const wall = Date.now() - t0;
    const t = await page.evaluate(() => window.likeness.texture && {
      ms: window.likeness.texture.textureMs, steps: window.likeness.texture.steps, size: window.likeness.texture.skin.width,
      calib: window.likeness.photos.map((p) => p.calib && (p.calib.ok ? `${p.name} rms ${p.calib.rms.toFixed(2)} px, ` +
        `${p.calib.inliers} inliers, f ${Math.round(p.calib.focal)} px` : `${p.name}: ${p.calib.message}`)) });
    if (!t) throw new Error('texture failed: ' + await page.textContent('#error-text'));
    console.log(`run ${i + 1}: texture ${Math.round(t.ms)} ms in the worker (${t.size}^2 texels), click-to-done ${wall} ms`);
    console.log('  ' + t.steps.map((s) => `${s.name} ${Math.round(s.ms)}`).join(', ') + ' ms');
    for (const c of t.calib) if (c) console.log('  ' + c);
  }
  if (shots) {
    fs.mkdirSync(shots, { recursive: true });
    await page.uncheck('#show-points');
    await settle(page);
    await page.screenshot({ path: path.join(shots, 'web_texture_result.png') });
    await page.evaluate(() => window.likeness.openClicker(1));
    await page.waitForTimeout(800);
    await settle(page);
    await page.screenshot({ path: path.join(shots, 'web_texture_clicks.png') });
    await page.click('#clicker-close');
    await page.check('#animate');
    await page.waitForTimeout(3000);
    await page.screenshot({ path: path.join(shots, 'web_fit_animate.png') });
    console.log('animation:', await page.textContent('#anim-stats'));
    await page.uncheck('#animate');
  }
} catch (e) {
  console.error(String(e && e.message ? e.message : e));
  status = 1;
} finally {
  await closeChromium(context, server);
}
process.exit(status);
