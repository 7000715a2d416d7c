// Times the whole scan -> head fit in Chromium (SwiftShader, this machine)
// on the page's built-in sample (WEBDIR/sample/scan.ply, put there by
// scripts/demo) or on a given PLY: clicks "Try the sample" / sets the file,
// runs "Fit head" RUNS times and prints per-stage ms and Table 1 numbers as
// measured by the worker (performance.now() around each stage), plus the
// page's wall time from the click to "done". Not a test: a measurement.
// --shots DIR also writes the docs pictures: DIR/web_fit_result.png (the
// page after the fit), web_fit_panel.png (the Pipeline card),
// web_fit_stages.png (Align result over the scan, wireframe) and
// web_fit_animate.png (mid-animation, points off).
// The page is served with the cross-origin isolation headers, so the worker
// runs the threaded core (worker.js); --no-isolation serves it without them
// (the single-threaded core, as on a host that does not send them).
// The page warms the fit's code up in a throw-away worker after start-up
// (docs/journal.md, "The first fit"): --wait-warmup waits for it to end before the
// first fit (a user who takes a few seconds to pick a file), --query warmup=0
// turns it off (any extra page parameters: --query 'a=1&b=2').
// Usage: node fit_timing.mjs WEBDIR [SCAN.ply] [--runs N] [--shots DIR] [--no-isolation]
//                            [--query Q] [--wait-warmup]
import { closeChromium, launchChromium, serveDir, takeFlag, takeOption } from './harness.mjs';
import fs from 'node:fs';
import path from 'node:path';

const args = process.argv.slice(2);
const runs = Math.max(1, Number(takeOption(args, '--runs', 1)) || 1);
const shots = takeOption(args, '--shots', '');
const isolation = !takeFlag(args, '--no-isolation');
const query = takeOption(args, '--query', '');
const waitWarmup = takeFlag(args, '--wait-warmup');
const [webdir, scan] = args;
if (!webdir) { console.error('usage: node fit_timing.mjs WEBDIR [SCAN.ply] [--runs N]'); process.exit(2); }
const root = path.resolve(webdir);
if (!scan && !fs.existsSync(path.join(root, 'sample', 'scan.ply'))) {
  console.error(`no ${root}/sample/scan.ply (scripts/demo makes it) and no SCAN given`);
  process.exit(2);
}
const server = await serveDir(root, { isolation });
const context = await launchChromium('timing', { width: 1280, height: 1000 });
let status = 0;
try {
  const page = context.pages()[0] || await context.newPage();
  await page.goto(`http://127.0.0.1:${server.address().port}/index.html?autofit=0${query ? '&' + query : ''}`);
  await page.waitForFunction(() => document.body.dataset.state === 'ready', null, { timeout: 180000 });
  const worker = await page.evaluate(() => ({ coi: window.crossOriginIsolated, cores: navigator.hardwareConcurrency,
                                               ...window.likeness.workerThreads }));
  console.log(`worker core: ${worker.variant}, ${worker.threads} thread(s); crossOriginIsolated ${worker.coi}, ` +
              `navigator.hardwareConcurrency ${worker.cores}`);
  if (scan) await page.setInputFiles('#file-input', path.resolve(scan));
  else await page.click('#btn-sample');
  await page.waitForFunction(() => ['done', 'error'].includes(document.body.dataset.state) && window.likeness.model, null, { timeout: 180000 });
  // The worker's own numbers, read inside it (its core is a top-level
  // binding of worker.js): the wasm heap's size (a first fit grows it) and
  // how many multi-threaded parallel_for loops ran (builds that count them).
  const coreStats = async () => {
    const w = page.workers().find((x) => x.url().includes('worker.js'));
    if (!w) return null;
    return w.evaluate(() => (typeof core === 'object' && core ? {
      heapMB: (core.wasmMemory ? core.wasmMemory.buffer : core.HEAPU8.buffer).byteLength / 1048576,
      loops: core.parallel_loops_run ? core.parallel_loops_run() : null } : null)).catch(() => null);
  };
  if (waitWarmup) {
    await page.waitForFunction(() => !window.likeness.warmup || window.likeness.warmup.state !== 'running', null, { timeout: 180000 });
  }
  const warm = await page.evaluate(() => window.likeness.warmup);
  console.log('warm-up: ' + (warm ? `${warm.state}${warm.ms ? ' after ' + Math.round(warm.ms) + ' ms' : ''}` +
                                    (warm.fitMs ? ` (its fit ${Math.round(warm.fitMs)} ms)` : '') : 'off'));
  // CPU time of this Chromium's processes (all threads: the worker, V8's
  // background compiles, drawing), from /proc: on a shared machine the wall
  // time says little. Linux only; null elsewhere.
  const chromiumCpuMs = () => {
    try {
      let ticks = 0;
      for (const pid of fs.readdirSync('/proc').filter((d) => /^\d+$/.test(d))) {
        let cmd;
        try { cmd = fs.readFileSync(`/proc/${pid}/cmdline`, 'latin1'); } catch { continue; }
        if (!cmd.includes(context.userDir)) continue;
        const stat = fs.readFileSync(`/proc/${pid}/stat`, 'latin1');
        const f = stat.slice(stat.lastIndexOf(')') + 2).split(' ');
        ticks += Number(f[11]) + Number(f[12]);  // utime, stime
      }
      return ticks * 10;  // USER_HZ = 100
    } catch { return null; }
  };
  for (let i = 0; i < runs; i++) {
    const before = await coreStats();
    const cpu0 = chromiumCpuMs();
    const t0 = Date.now();
    await page.click('#btn-fit');
    await page.waitForFunction(() => document.body.dataset.state !== 'working', null, { timeout: 600000 });
    const wall = Date.now() - t0;
    const cpu1 = chromiumCpuMs();
    const fit = await page.evaluate(() => window.likeness.fit);
    if (!fit) { console.log('fit failed:', await page.textContent('#error-text')); status = 1; break; }
    console.log(`run ${i + 1}: ${fit.points} points (${fit.fittedPoints} fitted); parse ${Math.round(fit.parseMs)} ms, ` +
                `fit ${Math.round(fit.fitMs)} ms (stages + their stats), click-to-done ${wall} ms` +
                (cpu0 !== null && cpu1 !== null ? `, Chromium CPU ${cpu1 - cpu0} ms` : ''));
    let sum = 0;
    for (const s of fit.stages) {
      sum += s.ms;
      console.log(`  ${s.name.padEnd(18)} ${s.meanPct.toFixed(3).padStart(7)} % ${s.maxPct.toFixed(3).padStart(7)} % ${Math.round(s.ms).toString().padStart(7)} ms`);
    }
    console.log(`  ${'stages total'.padEnd(36)} ${Math.round(sum).toString().padStart(7)} ms`);
    // The checks run after the fit in the same worker: let them end before
    // the next fit is clicked (or it would queue behind them).
    await page.waitForFunction(() => !window.likeness.fit || window.likeness.fit.quality, null, { timeout: 180000 });
    const after = await coreStats();
    if (before && after) {
      console.log(`  wasm heap ${Math.round(before.heapMB)} -> ${Math.round(after.heapMB)} MB` +
                  (after.loops !== null ? `; ${after.loops - before.loops} multi-threaded parallel_for loops` : ''));
    }
  }
  if (!status) {  // the checks run after the fit (a separate job): wait for them
    await page.waitForFunction(() => window.likeness.fit && window.likeness.fit.quality, null, { timeout: 180000 });
    const q = await page.evaluate(() => window.likeness.fit.quality);
    console.log(q.ok ? `checks: level ${q.level} ${q.triangles} triangles, ${q.flipped} turned over, ${q.degenerate} degenerate, ` +
                       `pairs ${q.crossings.total} (lips ${q.crossings.lips}, ears ${q.crossings.ears}, rest ${q.crossings.rest}), ` +
                       `smooth ${q.smoothCrossings.total}, control ${q.controlCrossings}; ${Math.round(q.checkMs)} ms in the worker`
                     : 'checks failed: ' + q.message);
  }
  if (shots && !status) {
    fs.mkdirSync(shots, { recursive: true });
    const settle = () => page.evaluate(() => new Promise((ok) => requestAnimationFrame(() => requestAnimationFrame(ok))));
    await settle();
    await page.screenshot({ path: path.join(shots, 'web_fit_result.png') });
    await page.locator('#stages').evaluate((el) => el.closest('.card').scrollIntoView());
    await page.locator('#stages').evaluate((el) => el.closest('.card')).then(() => {});
    await page.locator('.card', { has: page.locator('#stages') }).screenshot({ path: path.join(shots, 'web_fit_panel.png') });
    await page.click('#stages li[data-stage="align"]');
    await page.check('#wireframe');
    await settle();
    await page.screenshot({ path: path.join(shots, 'web_fit_stages.png') });
    await page.uncheck('#wireframe');
    await page.click('#stages li[data-stage="subdivide"]');
    await page.uncheck('#show-points');
    await page.check('#animate');
    await page.waitForTimeout(2500);
    await page.screenshot({ path: path.join(shots, 'web_fit_animate.png') });
    console.log('animation:', await page.textContent('#anim-stats'));
    await page.uncheck('#animate');
  }
} finally {
  await closeChromium(context, server);
}
process.exit(status);
