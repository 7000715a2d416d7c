// Save project / Open project: "Save project" downloads the fitted (and,
// after the texture flow, textured) head as a .likeness.glb; a freshly
// loaded page opens it and shows the same head without fitting (same level
// sizes and positions, the same skin), animates, smiles (Expressions) and exports it; a cut file
// is refused with its reason and the head stays; the checks measured again
// agree with the original's; the file chosen among others in the Inputs
// card opens too; "Fit head" on the opened head fits the scan points it
// keeps again.
import fs from 'node:fs';
import { bannerText, check, JOB_TIMEOUT_MS, runAlone, settled, shot, state } from '../harness.mjs';
import { fittedHead } from './fit.mjs';

// What identifies the head a page shows: level sizes, the finest level's
// position sums, the skin's size and a checksum of its pixels.
function headPrint(page) {
  return page.evaluate(() => {
    const f = window.likeness.fit, t = window.likeness.texture;
    if (!f) return null;
    const finest = f.meshes.levels[f.meshes.levels.length - 1].positions;
    let sum = 0, abs = 0;
    for (let i = 0; i < finest.length; i++) { sum += finest[i] * ((i % 7) + 1); abs += Math.abs(finest[i]); }
    let skin = null;
    if (t) {
      let h = 0;
      for (let i = 0; i < t.skin.pixels.length; i++) h = (h * 31 + t.skin.pixels[i]) >>> 0;
      skin = `${t.skin.width}x${t.skin.height}x${t.skin.channels} #${h}`;
    }
    return { levels: f.meshes.levels.map((m) => m.vertexCount), control: f.meshes.control.vertexCount, sum, abs, skin,
             stages: f.stages.map((s) => s.name + ' ' + s.meanPct.toFixed(4)) };
  });
}

async function run(s) {
  const { page, fit } = await fittedHead(s);
  if (!fit) return;
  await settled(page);
  const before = await headPrint(page);
  const handed = await page.evaluate(() => window.likeness.downloads.length);
  const downloadP = page.waitForEvent('download', { timeout: JOB_TIMEOUT_MS });
  await page.click('#btn-save-project');
  const download = await downloadP;
  const bytes = fs.readFileSync(await download.path());
  await page.waitForFunction((n) => window.likeness.downloads.length > n, handed, { timeout: JOB_TIMEOUT_MS });
  check('"Save project" downloads a .likeness.glb (a glTF binary)',
        /\.likeness\.glb$/.test(download.suggestedFilename()) && bytes.toString('latin1', 0, 4) === 'glTF' &&
        bytes.readUInt32LE(8) === bytes.length,
        `${download.suggestedFilename()}, ${bytes.length} bytes`);

  // A freshly loaded page (nothing fitted) opens the file.
  const fresh = await s.newPage();
  const empty = await fresh.evaluate(() => !window.likeness.fit && !window.likeness.scan);
  const t0 = Date.now();
  await fresh.setInputFiles('#project-input', { name: download.suggestedFilename(), mimeType: 'model/gltf-binary', buffer: bytes });
  await settled(fresh);
  const wallMs = Date.now() - t0;
  const after = await headPrint(fresh);
  const opened = await fresh.evaluate(() => ({ state: document.body.dataset.state, project: window.likeness.project,
    fitMs: window.likeness.fit && window.likeness.fit.fitMs,
    tags: [...document.querySelectorAll('#stages li .stage-tag')].map((t) => t.textContent),
    animate: !document.getElementById('animate').disabled, fitButton: !document.getElementById('btn-fit').disabled }));
  const same = !!after && JSON.stringify(after.levels) === JSON.stringify(before.levels) && after.control === before.control &&
    Math.abs(after.sum - before.sum) <= 1e-6 * before.abs && after.skin === before.skin &&
    JSON.stringify(after.stages) === JSON.stringify(before.stages);
  check('"Open project" on a fresh page shows the same head (levels, positions, skin, figures)',
        empty && opened.state === 'done' && same,
        `state ${opened.state}; before ${JSON.stringify(before)}; after ${JSON.stringify(after)}; ${await bannerText(fresh)}`);
  check('...without fitting: the fit rows say "saved", no fit time, opened in a fraction of the fit',
        !!opened.project && opened.fitMs === 0 && opened.tags.filter((t) => t === 'saved').length >= 4 &&
        opened.project.loadMs < fit.fitMs / 2,
        `opened in ${wallMs} ms from the test's hand-over of the file (page ${opened.project && Math.round(opened.project.wallMs)} ms to the head, ` +
        `worker ${opened.project && Math.round(opened.project.loadMs)} ms), fit took ${Math.round(fit.fitMs)} ms; tags ${opened.tags.join('|')}`);
  check('...and it can be animated, and fitted again (from the scan points it keeps)', opened.animate && opened.fitButton,
        JSON.stringify({ animate: opened.animate, fit: opened.fitButton }));
  await shot(fresh, 'web_project_open.png');

  // The checks are measured again on the opened head, and agree.
  const quality = (p) => p.waitForFunction(() => window.likeness.fit && window.likeness.fit.quality, null, { timeout: JOB_TIMEOUT_MS })
    .then(() => p.evaluate(() => {
      const q = window.likeness.fit.quality, d = q.faceToScan || {};
      return { ok: q.ok, flipped: q.flipped, degenerate: q.degenerate, crossings: q.crossings && q.crossings.total,
               vertices: d.vertices, meanMm: d.meanMm && d.meanMm.toFixed(6), maxMm: d.maxMm && d.maxMm.toFixed(6) };
    }));
  const [qBefore, qAfter] = [await quality(page), await quality(fresh)];
  check('the checks measured again on the opened head are the original\'s', qBefore.ok && JSON.stringify(qBefore) === JSON.stringify(qAfter),
        `original ${JSON.stringify(qBefore)}; opened ${JSON.stringify(qAfter)}`);

  // The opened head takes expressions too (the worker bakes the head it keeps).
  await fresh.click('#expressions summary');
  await fresh.click('[data-preset="smile"]');
  const smiled = await fresh.waitForFunction(() => window.likeness.expressions.stats.frames > 0, null, { timeout: JOB_TIMEOUT_MS })
    .then(() => fresh.evaluate(() => {
      const e = window.likeness.expressions, p = e.positions(), r = e.restPositions();
      let moved = 0;
      for (let i = 0; i < p.length; i += 3) if (p[i] !== r[i] || p[i + 1] !== r[i + 1] || p[i + 2] !== r[i + 2]) moved++;
      return { names: e.names.length, moved, smile: e.shape('smile').indices.length };
    }), () => null);
  await fresh.click('[data-preset="neutral"]');
  await fresh.click('#expressions summary');
  check('...and smiles with the Expressions panel', !!smiled && smiled.names === 77 && smiled.moved > 0 && smiled.moved <= smiled.smile,
        JSON.stringify(smiled));

  // Exported from the opened project: the finest level's OBJ has its vertices.
  const exportP = fresh.waitForEvent('download', { timeout: JOB_TIMEOUT_MS });
  await fresh.selectOption('#level', String(before.levels.length));
  await fresh.click('#btn-export-ply');
  const ply = fs.readFileSync(await (await exportP).path());
  check('the opened head exports its finest level', new RegExp('element vertex ' + before.levels[before.levels.length - 1] + '\\b')
    .test(ply.toString('latin1', 0, 400)), `${ply.length} bytes`);

  // A cut file: refused with its reason, the opened head stays.
  await settled(fresh);
  await fresh.setInputFiles('#project-input', { name: 'cut.likeness.glb', mimeType: 'model/gltf-binary', buffer: bytes.subarray(0, 5000) });
  await settled(fresh);
  const banner = await bannerText(fresh);
  const kept = await headPrint(fresh);
  check('a cut project file is refused with its reason and the head stays',
        /truncated Likeness project/.test(banner) && !!kept && kept.sum === after.sum && (await state(fresh)) === 'error',
        banner);

  // The file among dropped or chosen files (the Inputs card) opens too.
  await fresh.setInputFiles('#file-input', { name: download.suggestedFilename(), mimeType: 'model/gltf-binary', buffer: bytes });
  await settled(fresh);
  const dropped = await headPrint(fresh);
  check('a .likeness.glb among the chosen files opens as a project', (await state(fresh)) === 'done' && !!dropped &&
        dropped.sum === after.sum && dropped.skin === after.skin, `${await state(fresh)} ${await bannerText(fresh)}`);

  // "Fit head" on the opened head fits the scan points the project keeps
  // (no scan file): the same alignment, local and global fit as the
  // original (the project keeps the scan's points and triangles, not its
  // normals, which only the displacements read).
  const t1 = Date.now();
  await fresh.click('#btn-fit');
  await fresh.waitForFunction(() => window.likeness.fit && window.likeness.fit.fitMs > 0 || document.body.dataset.state === 'error',
                              null, { timeout: JOB_TIMEOUT_MS });
  await settled(fresh);
  const refit = await fresh.evaluate(() => {
    const f = window.likeness.fit;
    return { state: document.body.dataset.state, fitMs: f && f.fitMs, levels: f && f.meshes.levels.map((m) => m.vertexCount),
             stages: f ? f.stages.map((x) => [x.name, x.meanPct]) : [] };
  });
  // before.stages: 'name mean' with the mean to 4 decimals (headPrint).
  const originalStages = Object.fromEntries(before.stages.map((t) => [t.split(' ')[0], Number(t.split(' ')[1])]));
  const sameStages = ['initial_alignment', 'local_fitting', 'global_fitting'].every((n) => {
    const r = refit.stages.find((x) => x[0] === n);
    return r && r[1].toFixed(4) === originalStages[n].toFixed(4);
  });
  const sub = refit.stages.find((x) => x[0] === 'subdivision');
  check('"Fit head" on an opened project fits its kept scan again: the same alignment and fits as the original, ' +
        'Table 1 after subdivision within 10 %',
        refit.state === 'done' && refit.fitMs > 0 && JSON.stringify(refit.levels) === JSON.stringify(before.levels) && sameStages &&
        !!sub && Math.abs(sub[1] - originalStages.subdivision) <= 0.1 * originalStages.subdivision,
        `${Date.now() - t1} ms; refit ${JSON.stringify(refit.stages.map((x) => x[0] + ' ' + x[1].toFixed(5)))}; ` +
        `original ${JSON.stringify(before.stages)}; ${await bannerText(fresh)}`);
  await fresh.close();
}

export const flow = { name: 'project', title: 'Save project, then Open project on a fresh page without fitting', run };
runAlone(import.meta.url, flow);
