// The fit of a synthetic head scan (`likeness synth-scan --seed 2`, 60k
// points; skipped with a note when no native `likeness` can make it): the
// scan loads without fitting (Auto-run off), "Fit head" reaches "done" and
// its checks start while Animate and export stay on; every stage row shows
// its numbers, the global fit beats the alignment, the canvas shows the
// head, the scan points toggle, the Align row and the level selector switch
// meshes. fittedHead() is that fit, made once per session and shared with
// the flows that need a fitted head (fit-checks, fit-threads, export,
// animation, expressions, texture, eye-smile, fit-cancel).
import os from 'node:os';
import path from 'node:path';
import { bannerText, canvasImage, check, differingFraction, note, runAlone, setFile, settled, shot, SHOT_DIR,
         state } from '../harness.mjs';
import { syntheticScan } from '../synth_scan.mjs';

// {page, synth, fit, pointsShown} (fit null when it failed), or {skip: why}.
export function fittedHead(s) {
  return s.once('fitted head', async () => {
    const page = await s.page();
    const synth = syntheticScan(s.webdir, 2);
    if (synth.skip) {
      note('the fit is not exercised: ' + synth.skip);
      return { skip: synth.skip };
    }
    await page.uncheck('#auto-fit');
    const sLoad = await setFile(page, 'synthetic_head.ply', synth.bytes);
    check('the synthetic scan loads without fitting (Auto-run off)', sLoad === 'done' &&
          (await page.evaluate(() => !window.likeness.fit)), `state ${sLoad}`);
    const pointsShown = await canvasImage(page);
    const tFit = Date.now();
    await page.click('#btn-fit');
    await settled(page);
    const sFit = await state(page);
    const fit = await page.evaluate(() => window.likeness.fit && { fitMs: window.likeness.fit.fitMs,
      stages: window.likeness.fit.stages.map((s) => `${s.name} ${s.meanPct.toFixed(3)}/${s.maxPct.toFixed(2)}% ${Math.round(s.ms)} ms`),
      levels: window.likeness.fit.meshes.levels.map((m) => m.vertexCount), control: window.likeness.fit.meshes.control.vertexCount });
    check('"Fit head" reaches "done"', sFit === 'done' && !!fit,
          `state ${sFit} after ${Date.now() - tFit} ms; ${fit ? 'fit ' + Math.round(fit.fitMs) + ' ms in wasm: ' + fit.stages.join(', ') : await bannerText(page)}`);
    if (fit) await checksRunEarly(page, 'synthetic scan');
    return { page, synth, fit, pointsShown };
  });
}

// Right after a fit: its checks run in the worker ("checking…", or already
// done) while Animate and export stay available.
export async function checksRunEarly(page, label) {
  const early = await page.evaluate(() => ({
    checking: !window.likeness.fit.quality && document.getElementById('fit-quality').classList.contains('checking') &&
              /checking/.test(document.getElementById('quality-summary').textContent),
    done: !!window.likeness.fit.quality,
    animate: !document.getElementById('animate').disabled, exportObj: !document.getElementById('btn-export-obj').disabled,
    state: document.body.dataset.state }));
  check(`${label}: after the fit the checks run ("checking…") while Animate and export stay available`,
        (early.checking || early.done) && early.animate && early.exportObj && early.state === 'done', JSON.stringify(early));
}

async function run(s) {
  const { page, fit, pointsShown } = await fittedHead(s);
  if (!fit) return;
  const rows = await page.evaluate(() => ['align', 'local_fit', 'global_fit', 'subdivide'].map((r) => {
    const li = document.querySelector(`#stages li[data-stage="${r}"]`);
    return { r, tag: li.querySelector('.stage-tag').textContent, stats: li.querySelector('.stage-stats').textContent,
             value: li.querySelector('progress').value, paper: li.title };
  }));
  check('each stage row shows mean/max % and ms, a full bar and the paper\'s figures',
        rows.every((x) => /^\d+ ms$/.test(x.tag) && /mean \d+\.\d+ % · max \d+\.\d+ %/.test(x.stats) && x.value === 1 &&
                   /Table 1/.test(x.paper)), rows.map((x) => `${x.r}: ${x.tag}, ${x.stats}`).join('; '));
  // Accuracy must improve from the rigid alignment to the global fit.
  const meanOf = (name) => Number(/ (\d+\.\d+)\//.exec(fit.stages.find((t) => t.startsWith(name)))[1]);
  check('the global fit is closer to the scan than the alignment', meanOf('global_fitting') < 0.5 * meanOf('initial_alignment'),
        `${meanOf('initial_alignment')} % -> ${meanOf('global_fitting')} %`);
  const fitted = await canvasImage(page);
  const fitDiff = differingFraction(pointsShown, fitted);
  check('the canvas shows the fitted head', fitDiff > 0.02, `${(100 * fitDiff).toFixed(1)}% of pixels changed`);
  await shot(page, 'web_fit_result.png');
  await page.screenshot({ path: SHOT_DIR ? path.join(SHOT_DIR, 'web_fit_panel.png') : path.join(os.tmpdir(), 'lk_panel.png'),
                          clip: await page.locator('#stages').evaluate((el) => {
                            const r = el.closest('.card').getBoundingClientRect();
                            return { x: r.x, y: r.y, width: r.width, height: r.height };
                          }) });
  // Scan points off: fewer pixels differ from the bare mesh.
  await page.uncheck('#show-points');
  const noPoints = await canvasImage(page);
  await page.check('#show-points');
  check('the scan points toggle', differingFraction(fitted, noPoints) > 0.003,
        `${(100 * differingFraction(fitted, noPoints)).toFixed(2)}% changed`);
  // Stage rows: the alignment's mesh differs from the subdivided one.
  await page.click('#stages li[data-stage="align"]');
  const alignShown = await canvasImage(page);
  const stAlign = await page.textContent('#status');
  check('clicking "Align" shows the aligned generic head', stAlign.includes('Align result (' + fit.control.toLocaleString('en') + ' vertices') &&
        differingFraction(fitted, alignShown) > 0.005, `"${stAlign.trim()}", ${(100 * differingFraction(fitted, alignShown)).toFixed(1)}% changed`);
  await page.click('#stages li[data-stage="subdivide"]');
  // Levels: the control mesh and level 3 look different in wireframe.
  await page.check('#wireframe');
  await page.selectOption('#level', '0');
  const lv0 = await canvasImage(page);
  const st0 = await page.textContent('#status');
  await page.selectOption('#level', '3');
  const lv3 = await canvasImage(page);
  const st3 = await page.textContent('#status');
  await page.uncheck('#wireframe');
  check('the level selector switches control mesh / level 3', st0.includes('control mesh (' + fit.control.toLocaleString('en') + ' vertices') &&
        st3.includes('level 3 (' + fit.levels[2].toLocaleString('en') + ' vertices') && differingFraction(lv0, lv3) > 0.01,
        `"${st0.trim()}" / "${st3.trim()}", ${(100 * differingFraction(lv0, lv3)).toFixed(1)}% changed`);
}

export const flow = { name: 'fit', title: 'the fit of a synthetic scan, its stage rows and views', run };
runAlone(import.meta.url, flow);
