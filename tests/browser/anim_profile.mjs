// Measures the animation of the fitted head in Chromium (SwiftShader, this
// machine): fits the page's built-in sample (WEBDIR/sample/scan.ply) or a
// given scan, picks a level, hides the scan points, animates for a few
// seconds and prints the frame rate the page shows, what the adaptive detail
// settled on (level and drawing-buffer scale while moving), and, with
// --profile (?profile=1: the viewer reads back a pixel after each draw),
// where a frame's time goes: the worker job round trip (of which: the core's
// local update, the rest of the worker's job, the message transfer), the
// viewer's upload and the draw.
//   --full-detail   adaptation off (?full_detail=1): the chosen level at full resolution
//   --budget MS     the adaptation's frame budget (?anim_budget_ms; default 1000/15)
//   --both N        N alternating runs of adaptation on and off in the same page
//   --grid          with adaptation off, every level 1-3 x scale 1/0.75/0.5 (--levels 3,2,1
//                   --scales 1,0.75,0.5 to choose): fps while
//                   moving, and the rest pose's difference from level 3 at full
//                   resolution (the visual loss the adaptation's ladder trades)
// Not a test: a measurement.
// Usage: node anim_profile.mjs WEBDIR [SCAN.ply] [--level 3] [--seconds 6] [--profile] [--msaa N]
//                              [--full-detail] [--budget MS] [--both N] [--grid [--levels L,..] [--scales S,..]]
import { closeChromium, decodePng, launchChromium, serveDir, takeFlag, takeOption } from './harness.mjs';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';

const args = process.argv.slice(2);
const option = (name, fallback) => takeOption(args, name, fallback);
const flag = (name) => takeFlag(args, name);
const level = Number(option('--level', 3));
const seconds = Number(option('--seconds', 6));
const msaa = option('--msaa', '');  // samples; default: the page's choice (none on software WebGL)
const budget = option('--budget', '');
const both = Number(option('--both', 0));
const profile = flag('--profile');
const fullDetail = flag('--full-detail');
const grid = flag('--grid');
const gridLevels = option('--levels', '3,2,1').split(',').map(Number);
const gridScales = option('--scales', '1,0.75,0.5').split(',').map(Number);
const [webdir, scan] = args;
if (!webdir) {
  console.error('usage: node anim_profile.mjs WEBDIR [SCAN.ply] [--level 3] [--seconds 6] [--profile] [--msaa N] ' +
                '[--full-detail] [--budget MS] [--both N] [--grid]');
  process.exit(2);
}
const root = path.resolve(webdir);
if (!scan && !fs.existsSync(path.join(root, 'sample', 'scan.ply'))) {
  console.error(`no ${root}/sample/scan.ply (scripts/demo makes it) and no SCAN given`);
  process.exit(2);
}
const load = () => os.loadavg()[0].toFixed(1);

// Animates for `seconds` (after a warm-up) and returns fps and what the page showed.
async function measure(page, warmupMs = 1000) {
  await page.check('#animate');
  await page.waitForTimeout(warmupMs);  // past the first frames (allocations, shader warm-up, first steps)
  const start = await page.evaluate(() => ({ frames: window.likeness.animation.frames, t: performance.now(),
                                             p: Object.assign({}, window.likeness.animation.profile) }));
  const steps = [];
  const t0 = Date.now();
  while (Date.now() - t0 < seconds * 1000) {  // what it is drawing, sampled each 0.5 s
    await page.waitForTimeout(500);
    steps.push(await page.evaluate(() => { const ad = window.likeness.animation.adaptive; return `${ad.level}@${ad.scale}`; }));
  }
  const end = await page.evaluate(() => ({ frames: window.likeness.animation.frames, t: performance.now(),
                                           p: Object.assign({}, window.likeness.animation.profile),
                                           adaptive: Object.assign({}, window.likeness.animation.adaptive, { ladder: undefined }),
                                           text: document.getElementById('anim-stats').textContent,
                                           update: window.likeness.viewer.last_update ? window.likeness.viewer.last_update() : null }));
  await page.uncheck('#animate');
  const frames = end.frames - start.frames;
  const counts = {};
  for (const s of steps) counts[s] = (counts[s] || 0) + 1;
  return { frames, secs: (end.t - start.t) / 1000, fps: frames * 1000 / (end.t - start.t), start, end,
           drawn: Object.entries(counts).map(([k, n]) => `level ${k.replace('@', ' x')} ${Math.round(100 * n / steps.length)}%`).join(', ') };
}

function report(m, label) {
  const ad = m.end.adaptive;
  console.log(`${label}: ${m.frames} frames in ${m.secs.toFixed(1)} s = ${m.fps.toFixed(1)} fps (load ${load()}); ` +
              `page shows "${m.end.text}"; ` + (ad.enabled ? `adaptive: ended on level ${ad.level} x${ad.scale} (step ${ad.step}), ` +
              `${ad.changes} change(s), window ${ad.frameMs.toFixed(0)} ms; drawn while measured: ${m.drawn}` : 'adaptation off'));
  if (m.end.update) console.log(`  last frame: ${m.end.update.moved} vertices moved, ${m.end.update.renormalized} renormalized, ${m.end.update.uploaded} sent`);
  const n = m.end.p.frames - m.start.p.frames;
  if (n > 0) {
    const per = (k) => (m.end.p[k] - m.start.p[k]) / n;
    const job = per('jobMs'), worker = per('workerMs'), core = per('coreMs');
    console.log(`  per frame (${n} frames): job round trip ${job.toFixed(1)} ms = core update ${core.toFixed(1)} + ` +
                `rest of worker job ${(worker - core).toFixed(1)} + messages ${(job - worker).toFixed(1)}; ` +
                `viewer upload ${per('uploadMs').toFixed(1)} ms; draw ${per('drawMs').toFixed(1)} ms` +
                `${profile ? '' : ' (draw is only timed with --profile)'}`);
  }
}

// The canvas as the user sees it (a lower drawing-buffer scale is stretched
// back to the CSS size by the browser).
async function canvasPixels(page) {
  await page.evaluate(() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(() => requestAnimationFrame(r)))));
  await page.waitForTimeout(300);
  return decodePng(await page.locator('#canvas').screenshot({ style: '.toolbar, .hint { visibility: hidden !important; }' }));
}
function difference(a, b) {
  let sum = 0, over = 0;
  for (let i = 0; i < a.data.length; i += 4) {
    const d = Math.abs(a.data[i] - b.data[i]) + Math.abs(a.data[i + 1] - b.data[i + 1]) + Math.abs(a.data[i + 2] - b.data[i + 2]);
    sum += d;
    if (d > 30) over++;
  }
  const n = a.width * a.height;
  return { mean: sum / (3 * n), over: over / n };
}

const server = await serveDir(root);
const context = await launchChromium('anim', { width: 1280, height: 1000 });
let status = 0;
try {
  const page = context.pages()[0] || await context.newPage();
  if (process.env.LK_CONSOLE) page.on('console', (m) => console.log('console:', m.text()));
  const query = ['autofit=0', profile ? 'profile=1' : '', msaa !== '' ? 'msaa=' + Number(msaa) : '',
                 fullDetail ? 'full_detail=1' : '', budget ? 'anim_budget_ms=' + Number(budget) : ''].filter(Boolean).join('&');
  await page.goto(`http://127.0.0.1:${server.address().port}/index.html?${query}`);
  await page.waitForFunction(() => document.body.dataset.state === 'ready', null, { timeout: 180000 });
  if (scan) await page.setInputFiles('#file-input', path.resolve(scan));
  else await page.click('#btn-sample');
  await page.waitForFunction(() => ['done', 'error'].includes(document.body.dataset.state) && window.likeness.model, null, { timeout: 180000 });
  await page.click('#btn-fit');
  await page.waitForFunction(() => document.body.dataset.state !== 'working', null, { timeout: 600000 });
  if (!(await page.evaluate(() => !!window.likeness.fit))) throw new Error('fit failed: ' + await page.textContent('#error-text'));
  await page.uncheck('#show-points');
  const canvas = await page.evaluate(() => { const c = document.getElementById('canvas'); return `${c.width}x${c.height}`; });
  console.log(`msaa ${await page.evaluate(() => window.likeness.msaa)}, canvas ${canvas}, budget ` +
              `${(await page.evaluate(() => window.likeness.animation.adaptive.budgetMs)).toFixed(1)} ms`);
  if (grid) {
    await page.check('#full-detail');
    await page.selectOption('#level', '3');
    const reference = await canvasPixels(page);
    for (const lv of gridLevels) {
      for (const scale of gridScales) {
        await page.selectOption('#level', String(lv));
        await page.evaluate((s) => window.likeness.viewer.set_render_scale(s), scale);
        const rest = difference(reference, await canvasPixels(page));
        const m = await measureFixed(page, scale);
        console.log(`level ${lv} x${scale}: ${m.fps.toFixed(1)} fps (load ${load()}); rest pose vs level 3 x1: ` +
                    `mean |diff| ${rest.mean.toFixed(2)}/255, ${(100 * rest.over).toFixed(2)} % of pixels differ by > 30`);
      }
    }
    await page.uncheck('#full-detail');
  } else if (both > 0) {
    await page.selectOption('#level', String(level));
    for (let i = 0; i < both; ++i) {
      for (const off of [false, true]) {
        await page.setChecked('#full-detail', off);
        report(await measure(page, off ? 1000 : 3000), `level ${level}, adaptation ${off ? 'off' : 'on'} (run ${i + 1})`);
      }
    }
  } else {
    await page.selectOption('#level', String(level));
    report(await measure(page, fullDetail ? 1000 : 3000), `level ${level}, adaptation ${fullDetail ? 'off' : 'on'}` +
           (profile ? ' (profiling: each draw is waited for)' : ''));
  }
  // After stopping: the chosen level at full resolution.
  const after = await page.evaluate(() => ({ w: document.getElementById('canvas').width, level: document.getElementById('level').value,
                                             status: document.getElementById('status').textContent }));
  console.log(`stopped: canvas ${after.w} wide, level select ${after.level}, status "${after.status.trim()}"`);
} catch (e) {
  console.error(String(e && e.message ? e.message : e));
  status = 1;
} finally {
  await closeChromium(context, server);
}
process.exit(status);

// Adaptation off, drawing-buffer scale held at `scale` while animating.
async function measureFixed(page, scale) {
  await page.check('#animate');
  await page.evaluate((s) => window.likeness.viewer.set_render_scale(s), scale);
  await page.waitForTimeout(1000);
  const f0 = await page.evaluate(() => [window.likeness.animation.frames, performance.now()]);
  await page.waitForTimeout(seconds * 1000);
  const f1 = await page.evaluate(() => [window.likeness.animation.frames, performance.now()]);
  await page.uncheck('#animate');
  return { fps: (f1[0] - f0[0]) * 1000 / (f1[1] - f0[1]) };
}
