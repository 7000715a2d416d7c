// Start-up: the page reaches "ready" and says how long it took, runs the
// threaded core when cross-origin isolated, draws the generic head shaded;
// the view follows the mouse (orbit, Reset view), the keyboard (arrows, R;
// Tab still leaves the canvas), a touch screen (one finger orbits, a pinch
// zooms) and the Wireframe toggle.
import fs from 'node:fs';
import path from 'node:path';
import { analyse, bannerText, canvasImage, check, differingFraction, note, runAlone, shot, state } from '../harness.mjs';

async function run(s) {
  const { page, state: s0, wallMs } = await s.mainPage();
  const { loadMs, timings } = await page.evaluate(() => ({ loadMs: window.likeness.loadMs, timings: window.likeness.timings }));
  const parts = Object.entries(timings || {}).map(([k, v]) => `${k} ${Math.round(v)}`).join(', ');
  if (!check('page reaches "ready"', s0 === 'ready', s0 === 'ready' ? `app load ${Math.round(loadMs)} ms (${parts}), wall ${wallMs} ms`
                                                                : 'state ' + s0 + ': ' + await bannerText(page))) {
    throw new Error('the page did not start');
  }
  await shot(page, 'web_start.png');
  // Start-up figures (issue 39 asks for interactive under 2 s from a local
  // server): printed, not asserted, since the machine's load decides them.
  const paint = await page.evaluate(() =>
    (performance.getEntriesByType('paint').find((e) => e.name === 'first-contentful-paint') || {}).startTime);
  const wasm = fs.readdirSync(s.webdir).filter((f) => f.endsWith('.wasm'))
    .map((f) => `${f} ${(fs.statSync(path.join(s.webdir, f)).size / 1024).toFixed(0)} KB`);
  const viewerSteps = await page.evaluate(() => window.likeness.viewer.startup_times());
  note(`start-up: first paint ${Math.round(paint)} ms, ready (viewer and core up, head drawn) ${Math.round(loadMs)} ms; ` +
       `wasm files: ${wasm.join(', ')}; the viewer's main: ` + viewerSteps.map(([k, ms]) => `${k} ${ms.toFixed(0)}`).join(', ') + ' ms');
  check('the viewer reports its start-up steps (SDL, window, WebGL context, renderer, generic head)',
        viewerSteps.length === 5 && viewerSteps.every(([, ms]) => Number.isFinite(ms) && ms >= 0), JSON.stringify(viewerSteps));
  // The face-landmark detector (vendor/face_mesh/, 17 MB with its models) is fetched
  // only once photos are dropped, never for the start (issue 39).
  const early = await page.evaluate(() => performance.getEntriesByType('resource').map((e) => e.name)
    .filter((n) => n.includes('face_mesh')));
  check('the landmark model is not fetched at start-up', early.length === 0,
        early.length ? early.slice(0, 3).join(', ') : 'no vendor/face_mesh/ request before a photo');
  // Served with COOP/COEP: the page is cross-origin isolated and the worker
  // runs the threaded core, one thread per core up to 4.
  const isolated = await page.evaluate(() => ({ coi: window.crossOriginIsolated, cores: navigator.hardwareConcurrency,
                                                 worker: window.likeness.workerThreads }));
  const wantThreads = Math.max(1, Math.min(4, isolated.cores));
  check('cross-origin isolated: the worker runs the threaded core', isolated.coi === true && isolated.worker &&
        isolated.worker.variant === 'threads' && isolated.worker.threads === wantThreads,
        `crossOriginIsolated ${isolated.coi}, ${isolated.cores} cores, worker ${JSON.stringify(isolated.worker)}`);
  // The first part loads non-head files: no automatic fit for them.
  await page.uncheck('#auto-fit');
  const head = await canvasImage(page);
  const headStats = analyse(head);
  check('canvas shows the head (not blank)', headStats.fgFraction > 0.03,
        `${(100 * headStats.fgFraction).toFixed(1)}% of ${head.width}x${head.height} px differ from the background`);
  check('head is shaded (not one flat color)', headStats.lumStd > 8, `luminance std ${headStats.lumStd.toFixed(1)}`);

  // Orbit by dragging.
  const box = await page.locator('#canvas').boundingBox();
  await page.mouse.move(box.x + box.width / 2, box.y + box.height / 2);
  await page.mouse.down();
  for (let i = 1; i <= 10; i++) await page.mouse.move(box.x + box.width / 2 + 18 * i, box.y + box.height / 2);
  await page.mouse.up();
  const orbited = await canvasImage(page);
  const orbitDiff = differingFraction(head, orbited);
  check('dragging orbits the view', orbitDiff > 0.005, `${(100 * orbitDiff).toFixed(1)}% of pixels changed`);
  await page.click('#btn-reset');
  const reset = await canvasImage(page);
  const resetDiff = differingFraction(head, reset);
  check('"Reset view" restores the start view', resetDiff < 0.002, `${(100 * resetDiff).toFixed(2)}% of pixels differ from the start`);

  // Keyboard: arrows orbit the focused canvas, R resets, Tab still moves on.
  await page.focus('#canvas');
  for (let i = 0; i < 4; i++) await page.keyboard.press('ArrowRight');
  const keyed = await canvasImage(page);
  check('arrow keys orbit the focused canvas', differingFraction(reset, keyed) > 0.005,
        `${(100 * differingFraction(reset, keyed)).toFixed(1)}% of pixels changed`);
  await page.keyboard.press('r');
  check('R resets the view', differingFraction(reset, await canvasImage(page)) < 0.002);
  await page.keyboard.press('Tab');
  const focused = await page.evaluate(() => document.activeElement && document.activeElement.id);
  check('Tab moves focus on from the canvas', focused !== 'canvas', `focus on #${focused}`);

  // Touch: one finger orbits, a pinch outwards zooms in (the head grows).
  const cdp = await page.context().newCDPSession(page);
  const cx = box.x + box.width / 2, cy = box.y + box.height / 2;
  const touch = async (type, points) => cdp.send('Input.dispatchTouchEvent', { type, touchPoints: points });
  await touch('touchStart', [{ x: cx, y: cy, id: 1 }]);
  for (let i = 1; i <= 10; i++) await touch('touchMove', [{ x: cx + 18 * i, y: cy, id: 1 }]);
  await touch('touchEnd', []);
  const touched = await canvasImage(page);
  check('a one-finger drag orbits', differingFraction(reset, touched) > 0.005,
        `${(100 * differingFraction(reset, touched)).toFixed(1)}% of pixels changed`);
  await page.click('#btn-reset');
  await touch('touchStart', [{ x: cx - 20, y: cy, id: 1 }, { x: cx + 20, y: cy, id: 2 }]);
  for (let i = 1; i <= 10; i++) await touch('touchMove', [{ x: cx - 20 - 8 * i, y: cy, id: 1 }, { x: cx + 20 + 8 * i, y: cy, id: 2 }]);
  await touch('touchEnd', []);
  const pinched = analyse(await canvasImage(page));
  check('a pinch zooms in', pinched.fgFraction > 1.2 * headStats.fgFraction,
        `foreground ${(100 * headStats.fgFraction).toFixed(1)}% -> ${(100 * pinched.fgFraction).toFixed(1)}%`);
  await page.click('#btn-reset');

  // Wireframe: the edges darken part of the head; off again restores it.
  await page.check('#wireframe');
  const wired = await canvasImage(page);
  const wireDiff = differingFraction(reset, wired);
  await page.uncheck('#wireframe');
  const unwired = differingFraction(reset, await canvasImage(page));
  check('the wireframe toggle draws the edges and removes them', wireDiff > 0.003 && unwired < 0.002,
        `on: ${(100 * wireDiff).toFixed(2)}% changed, off: ${(100 * unwired).toFixed(2)}%`);

  // Multisampling: none on SwiftShader (it doubles a level-3 frame's cost);
  // ?msaa=4 (as a GPU gets by default) gives a multisampled context, drawn.
  const glOf = (pg) => pg.evaluate(() => {
    const c = document.getElementById('canvas'), gl = c.getContext('webgl2');
    return { software: window.likeness.software, msaa: window.likeness.msaa,
             antialias: gl ? gl.getContextAttributes().antialias : null, samples: gl ? gl.getParameter(gl.SAMPLES) : null };
  });
  const gl0 = await glOf(page);
  check('SwiftShader: no multisampling', gl0.software === true && gl0.msaa === 0 && gl0.antialias === false, JSON.stringify(gl0));
  // The throw-away context that tells SwiftShader from a GPU (0.4-2.4 s
  // here) is made on a first visit only; the verdict is remembered, and the
  // next start uses it (checked again on the viewer's own context).
  const firstProbe = await page.evaluate(() => window.likeness.timings.softwareProbeMs);
  const nextPage = await s.newPage('?autofit=0');
  const next = await nextPage.evaluate(() => ({ software: window.likeness.software, msaa: window.likeness.msaa,
                                                probeMs: window.likeness.timings.softwareProbeMs,
                                                remembered: localStorage.getItem('likeness.softwareWebGL') }));
  check('the software-WebGL verdict is remembered: the next start makes no throw-away context, and still no multisampling',
        next.probeMs === undefined && next.remembered === '1' && next.software === true &&
        next.msaa === 0 && await state(nextPage) === 'ready',
        `first start: ${firstProbe === undefined ? 'remembered from an earlier page' : 'probe ' + Math.round(firstProbe) + ' ms'}; next: ${JSON.stringify(next)}`);
  await nextPage.close();
  const msaaPage = await s.newPage('?autofit=0&msaa=4');
  const gl4 = await glOf(msaaPage);
  const msaaHead = await canvasImage(msaaPage);
  await msaaPage.focus('#canvas');
  for (let i = 0; i < 4; i++) await msaaPage.keyboard.press('ArrowRight');
  const msaaKeyed = differingFraction(msaaHead, await canvasImage(msaaPage));
  check('?msaa=4: a multisampled context, the head drawn and the arrow keys working',
        await state(msaaPage) === 'ready' && gl4.msaa === 4 && gl4.antialias === true && gl4.samples === 4 &&
        analyse(msaaHead).fgFraction > 0.03 && msaaKeyed > 0.005,
        `${JSON.stringify(gl4)}, ${(100 * msaaKeyed).toFixed(1)}% of pixels changed by the keys`);
  await msaaPage.close();
}

export const flow = { name: 'startup', title: 'start-up, the head drawn, the view by mouse, keys and touch', run };
runAlone(import.meta.url, flow);
