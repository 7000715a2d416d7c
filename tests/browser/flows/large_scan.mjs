// A very large scan (issue 39): a 2-million-point binary PLY (48 MB, made by
// `likeness synth-scan --points 2000000`; skipped with a note without the
// native CLI) is chosen from disk on a page of its own; the worker reads it
// in slices (File.slice) into the core's stream reader, so all of it is read
// and never held whole; it is shown thinned and fits without running out of
// memory. The flow prints the load and fit times, the core's wasm heap after
// the load and after the fit, and the peak memory (VmHWM) of the page's
// renderer process, which holds the page, the worker and the wasm heap.
// A scan larger than the wasm heap can fit is refused from its size, before
// a byte is read (a sparse file: nothing to read anyway).
// LK_LARGE_POINTS=5000000 measures a 5M-point scan by hand (not in CI).
import { execFileSync } from 'node:child_process';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { bannerText, check, likenessBin, note, runAlone, settled, state } from '../harness.mjs';

const POINTS = Number(process.env.LK_LARGE_POINTS) > 0 ? Number(process.env.LK_LARGE_POINTS) : 2000000;
const MB = 1048576;

// Linux: the largest peak resident memory (VmHWM) among the renderer
// processes of the browser whose profile is userDir; null elsewhere.
function rendererPeakBytes(userDir) {
  try {
    const procs = new Map();
    for (const pid of fs.readdirSync('/proc').filter((d) => /^\d+$/.test(d))) {
      try {
        const cmd = fs.readFileSync(`/proc/${pid}/cmdline`, 'utf8');
        const status = fs.readFileSync(`/proc/${pid}/status`, 'utf8');
        const ppid = Number((/PPid:\s+(\d+)/.exec(status) || [])[1]);
        const hwm = Number((/VmHWM:\s+(\d+) kB/.exec(status) || [])[1] || 0) * 1024;
        procs.set(Number(pid), { cmd, ppid, hwm });
      } catch { /* gone meanwhile */ }
    }
    const browser = [...procs].find(([, p]) => p.cmd.includes('--user-data-dir=' + userDir) && !p.cmd.includes('--type='));
    if (!browser) return null;
    let peak = 0;
    for (const [, p] of procs) {
      if (!p.cmd.includes('--type=renderer')) continue;
      let up = p.ppid;
      for (let i = 0; i < 6 && up && up !== browser[0]; i++) up = procs.has(up) ? procs.get(up).ppid : 0;
      if (up === browser[0]) peak = Math.max(peak, p.hwm);
    }
    return peak || null;
  } catch {
    return null;
  }
}

async function run(s) {
  const bin = likenessBin(s.webdir);
  if (!bin) {
    note('the large scan is not exercised: no native likeness binary (set LK_LIKENESS_BIN)');
    return;
  }
  const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'likeness-large-'));
  try {
    execFileSync(bin, ['synth-scan', '--seed', '5', '--points', String(POINTS), '--out', dir], { stdio: 'pipe' });
    const file = path.join(dir, 'scan.ply');
    const size = fs.statSync(file).size;
    const context = await s.context();
    const page = await s.newPage('?autofit=0');
    const t0 = Date.now();
    await page.setInputFiles('#file-input', file);
    await settled(page);
    const loadMs = Date.now() - t0;
    const sLoad = await state(page);
    const status = (await page.textContent('#status')).trim();
    const read = await page.evaluate(() => window.likeness.scanRead || null);
    // The wasm heap after the load, from a job that only reports it (the
    // heap only grows, so this is the load's peak).
    const loadHeap = await page.evaluate(async () => (await window.likeness.runJob({ type: 'quality' }, [])).heapBytes || 0);
    check(`a ${POINTS.toLocaleString('en')}-point binary PLY (${(size / MB).toFixed(0)} MB) loads, read whole in slices`,
          sLoad === 'done' && status.includes(POINTS.toLocaleString('en') + ' points') && !!read && read.bytesRead === size,
          `state ${sLoad} after ${loadMs} ms; "${status}"; ${read ? `${read.bytesRead} of ${size} bytes read, ` +
          `wasm heap ${(read.heapBytes / MB).toFixed(0)} MB` : 'no read record'} ${await bannerText(page)}`);
    const t1 = Date.now();
    await page.click('#btn-fit');
    await page.waitForFunction(() => document.body.dataset.state !== 'working', null, { timeout: 600000 });
    const fit = await page.evaluate(() => window.likeness.fit && { fitMs: window.likeness.fit.fitMs, heap: window.likeness.fit.heapBytes,
      total: document.getElementById('fit-total').textContent });
    const peak = rendererPeakBytes(context.userDir);
    check('... and fits, the core\'s memory shown beside the fit', (await state(page)) === 'done' && !!fit && fit.heap > 0 &&
          /core memory \d+ MB/.test(fit.total),
          fit ? `fit ${(fit.fitMs / 1000).toFixed(1)} s in wasm (wall ${((Date.now() - t1) / 1000).toFixed(1)} s); "${fit.total}"`
            : `state ${await state(page)}: ${await bannerText(page)}`);
    note(`large scan: ${POINTS.toLocaleString('en')} points, ${(size / MB).toFixed(0)} MB: load ${loadMs} ms, wasm heap after ` +
         `the load ${(loadHeap / MB).toFixed(0)} MB, after the fit ${fit ? (fit.heap / MB).toFixed(0) : '?'} MB; ` +
         `renderer peak (VmHWM) ${peak ? (peak / MB).toFixed(0) + ' MB' : 'not measured'}`);
    await page.close();

    // Over the limit the wasm heap sets (2 GiB / 13 = 158 MB, worker.js): refused
    // from the File's size, nothing read.
    const huge = path.join(dir, 'huge.ply');
    fs.closeSync(fs.openSync(huge, 'w'));
    fs.truncateSync(huge, 200 * MB);
    const page2 = await s.newPage('?autofit=0');
    const t2 = Date.now();
    await page2.setInputFiles('#file-input', huge);
    await settled(page2);
    const refused = await page2.evaluate(() => window.likeness.scanRead || null);
    const banner = await bannerText(page2);
    check('a 200 MB scan is refused before a byte is read, saying the limit',
          !!refused && !refused.ok && refused.bytesRead === 0 && /fits scans up to \d+ MB/.test(banner) && !(await page2.evaluate(() => !!window.likeness.model)),
          `${Date.now() - t2} ms; ${JSON.stringify(refused)}; ${banner}`);
    await page2.close();
  } finally {
    fs.rmSync(dir, { recursive: true, force: true });
  }
}

export const flow = { name: 'large-scan', title: 'a 2-million-point scan loads in slices and fits, the memory reported; a too-large one is refused before reading', run };
runAlone(import.meta.url, flow);
