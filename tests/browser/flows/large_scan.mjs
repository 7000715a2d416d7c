// A very large scan (issue 39): a 2-million-point binary PLY (48 MB, made by
// `likeness synth-scan --points 2000000`; skipped with a note without the
// native CLI) is chosen from disk on a page of its own, loads, is shown
// thinned, and fits without running out of memory; the flow prints the load
// and fit times and the core's memory (the wasm heap after the fit), which
// the page also shows beside the fit's time.
import { execFileSync } from 'node:child_process';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { bannerText, check, note, runAlone, settled, state } from '../harness.mjs';

const POINTS = 2000000;

async function run(s) {
  const bin = [process.env.LK_LIKENESS_BIN, path.join(s.webdir, '..', 'bin', 'likeness')].filter(Boolean).find((c) => fs.existsSync(c));
  if (!bin) {
    note('the large scan is not exercised: no native likeness binary (set LK_LIKENESS_BIN)');
    return;
  }
  const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'likeness-large-'));
  try {
    execFileSync(bin, ['synth-scan', '--seed', '5', '--points', String(POINTS), '--out', dir], { stdio: 'pipe' });
    const file = path.join(dir, 'scan.ply');
    const page = await s.newPage('?autofit=0');
    const t0 = Date.now();
    await page.setInputFiles('#file-input', file);
    await settled(page);
    const sLoad = await state(page);
    const status = (await page.textContent('#status')).trim();
    check(`a ${POINTS.toLocaleString('en')}-point binary PLY (${(fs.statSync(file).size / 1048576).toFixed(0)} MB) loads`,
          sLoad === 'done' && status.includes(POINTS.toLocaleString('en') + ' points'),
          `state ${sLoad} after ${Date.now() - t0} ms; "${status}" ${await bannerText(page)}`);
    const t1 = Date.now();
    await page.click('#btn-fit');
    await page.waitForFunction(() => document.body.dataset.state !== 'working', null, { timeout: 600000 });
    const fit = await page.evaluate(() => window.likeness.fit && { fitMs: window.likeness.fit.fitMs, heap: window.likeness.fit.heapBytes,
      total: document.getElementById('fit-total').textContent });
    check('... and fits, the core\'s memory shown beside the fit', (await state(page)) === 'done' && !!fit && fit.heap > 0 &&
          /core memory \d+ MB/.test(fit.total),
          fit ? `fit ${(fit.fitMs / 1000).toFixed(1)} s in wasm (wall ${((Date.now() - t1) / 1000).toFixed(1)} s); "${fit.total}"`
            : `state ${await state(page)}: ${await bannerText(page)}`);
    await page.close();
  } finally {
    fs.rmSync(dir, { recursive: true, force: true });
  }
}

export const flow = { name: 'large-scan', title: 'a 2-million-point scan loads and fits, the memory reported', run };
runAlone(import.meta.url, flow);
