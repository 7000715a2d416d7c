// Measures the animation of the fitted head in Chromium (SwiftShader, this
// machine): fits the page's built-in sample (WEBDIR/sample/scan.ply) or a
// given scan, picks a level, hides the scan points, animates for a few
// seconds and prints the frame rate the page shows, and, with --profile
// (?profile=1: the viewer glFinish()es each draw), where a frame's time goes:
// the worker job round trip (of which: the core's local update, the rest of
// the worker's job, the message transfer), the viewer's upload and the draw.
// Not a test: a measurement.
// Usage: node anim_profile.mjs WEBDIR [SCAN.ply] [--level 3] [--seconds 6] [--profile] [--msaa N]
import { launchChromium, serveDir } from './harness.mjs';
import fs from 'node:fs';
import path from 'node:path';

const args = process.argv.slice(2);
function option(name, fallback) {
  const i = args.indexOf(name);
  if (i < 0) return fallback;
  const v = args[i + 1];
  args.splice(i, 2);
  return v;
}
const level = Number(option('--level', 3));
const seconds = Number(option('--seconds', 6));
const msaa = option('--msaa', '');  // samples; default: the page's choice (none on software WebGL)
const pi = args.indexOf('--profile');
const profile = pi >= 0;
if (profile) args.splice(pi, 1);
const [webdir, scan] = args;
if (!webdir) { console.error('usage: node anim_profile.mjs WEBDIR [SCAN.ply] [--level 3] [--seconds 6] [--profile]'); process.exit(2); }
const root = path.resolve(webdir);
if (!scan && !fs.existsSync(path.join(root, 'sample', 'scan.ply'))) {
  console.error(`no ${root}/sample/scan.ply (scripts/demo makes it) and no SCAN given`);
  process.exit(2);
}
const server = await serveDir(root);
const context = await launchChromium('anim', { width: 1280, height: 1000 });
let status = 0;
try {
  const page = context.pages()[0] || await context.newPage();
  if (process.env.LK_CONSOLE) page.on('console', (m) => console.log('console:', m.text()));
  await page.goto(`http://127.0.0.1:${server.address().port}/index.html?autofit=0${profile ? '&profile=1' : ''}${msaa !== '' ? '&msaa=' + Number(msaa) : ''}`);
  await page.waitForFunction(() => document.body.dataset.state === 'ready', null, { timeout: 180000 });
  if (scan) await page.setInputFiles('#file-input', path.resolve(scan));
  else await page.click('#btn-sample');
  await page.waitForFunction(() => ['done', 'error'].includes(document.body.dataset.state) && window.likeness.model, null, { timeout: 180000 });
  await page.click('#btn-fit');
  await page.waitForFunction(() => document.body.dataset.state !== 'working', null, { timeout: 600000 });
  if (!(await page.evaluate(() => !!window.likeness.fit))) throw new Error('fit failed: ' + await page.textContent('#error-text'));
  await page.selectOption('#level', String(level));
  await page.uncheck('#show-points');
  await page.check('#animate');
  await page.waitForTimeout(1000);  // past the first frames (allocations, shader warm-up)
  const start = await page.evaluate(() => ({ frames: window.likeness.animation.frames, t: performance.now(),
                                             p: Object.assign({}, window.likeness.animation.profile) }));
  await page.waitForTimeout(seconds * 1000);
  const end = await page.evaluate(() => ({ frames: window.likeness.animation.frames, t: performance.now(),
                                           p: Object.assign({}, window.likeness.animation.profile),
                                           text: document.getElementById('anim-stats').textContent,
                                           update: window.likeness.viewer.last_update ? window.likeness.viewer.last_update() : null }));
  await page.uncheck('#animate');
  const frames = end.frames - start.frames;
  const fps = frames * 1000 / (end.t - start.t);
  console.log(`msaa ${await page.evaluate(() => window.likeness.msaa)}, level ${level}: ${frames} frames in ${((end.t - start.t) / 1000).toFixed(1)} s = ${fps.toFixed(1)} fps` +
              `${profile ? ' (profiling: draws are glFinish()ed)' : ''}; page shows "${end.text}"`);
  // What the viewer's last update_positions did (indexed path: vertices
  // that moved, normals recomputed, GPU vertices re-sent).
  if (end.update) console.log(`last frame: ${end.update.moved} vertices moved, ${end.update.renormalized} renormalized, ${end.update.uploaded} sent`);
  const n = end.p.frames - start.p.frames;
  if (n > 0) {
    const per = (k) => (end.p[k] - start.p[k]) / n;
    const job = per('jobMs'), worker = per('workerMs'), core = per('coreMs');
    console.log(`per frame (${n} frames): job round trip ${job.toFixed(1)} ms = core update ${core.toFixed(1)} + ` +
                `rest of worker job ${(worker - core).toFixed(1)} + messages ${(job - worker).toFixed(1)}; ` +
                `viewer upload ${per('uploadMs').toFixed(1)} ms; draw ${per('drawMs').toFixed(1)} ms` +
                `${profile ? '' : ' (draw is only timed with --profile)'}`);
  }
} catch (e) {
  console.error(String(e && e.message ? e.message : e));
  status = 1;
} finally {
  await context.close();
  server.close();
  fs.rmSync(context.userDir, { recursive: true, force: true });
}
process.exit(status);
