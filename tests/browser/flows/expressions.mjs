// Expressions (issue 38, in the page) on the fitted head: opening the panel
// bakes the 77 shapes at the level shown; the smile preset changes the
// canvas and lifts both mouth corners (along the head's up); a slider
// (by keyboard) adds one shape's weight and the blend is rest + the sum of
// the weighted offsets on that vertex; Talk plays frames and ends at rest,
// words typed beside it are said (their visemes) and words without a letter
// are refused with the reason,
// Stop and Animate stop it; open mouth turns the lower teeth with the jaw;
// neutral gives the rest positions exactly. The
// blend's ms per frame at levels 3 and 2 are printed as notes; the control
// mesh (level 0) smiles too.
import path from 'node:path';
import { bannerText, canvasImage, check, differingFraction, JOB_TIMEOUT_MS, note, runAlone, SHOT_DIR } from '../harness.mjs';
import { fittedHead } from './fit.mjs';

const expr = (page) => page.evaluate(() => {
  const e = window.likeness.expressions;
  return { level: e.level, names: e.names.length, bakeMs: e.bakeMs, weights: { ...e.weights }, talking: e.talking,
           talkFrames: e.talkFrames, talkPeaks: { ...e.talkPeaks }, stats: { ...e.stats }, pressed: document.getElementById('btn-talk').getAttribute('aria-pressed') };
});

// The largest difference between the blended and the rest positions (0: the rest exactly).
const fromRest = (page) => page.evaluate(() => {
  const e = window.likeness.expressions, p = e.positions(), r = e.restPositions();
  const level = window.likeness.fit.meshes.levels[e.level - 1].positions;
  let d = 0, fitted = 0;
  for (let i = 0; i < p.length; i++) { d = Math.max(d, Math.abs(p[i] - r[i])); fitted = Math.max(fitted, Math.abs(r[i] - level[i])); }
  return { d, fitted, n: p.length };
});

async function talkMs(page, level) {
  await page.click('#btn-talk');
  // Talk starts once the shapes of this level are baked, and ends by itself.
  await page.waitForFunction(() => window.likeness.expressions.talking, null, { timeout: JOB_TIMEOUT_MS });
  await page.waitForFunction(() => !window.likeness.expressions.talking, null, { timeout: JOB_TIMEOUT_MS });
  const e = await expr(page);
  note(`Talk on level ${level}: ${e.talkFrames} frames, per frame blend ${(e.stats.blendMs / e.stats.frames).toFixed(2)} ms + ` +
       `viewer ${e.stats.path === 'gpu' ? 'set_morph_weights' : 'update_positions'} ${(e.stats.uploadMs / e.stats.frames).toFixed(2)} ms ` +
       `(${e.stats.path} path)`);
  return e;
}

// Largest channel difference and the fraction of pixels differing by more than 2 in some channel.
function pixelDiff(a, b) {
  if (a.width !== b.width || a.height !== b.height) return { max: 255, fraction: 1 };
  let max = 0, n = 0;
  for (let i = 0; i < a.data.length; i += 4) {
    const d = Math.max(Math.abs(a.data[i] - b.data[i]), Math.abs(a.data[i + 1] - b.data[i + 1]), Math.abs(a.data[i + 2] - b.data[i + 2]));
    max = Math.max(max, d);
    if (d > 2) n++;
  }
  return { max, fraction: n / (a.width * a.height) };
}

// The cost of a full expression change (one preset to another, every shape's
// weight changing) on each path: the page's side (JS blend + update_positions
// on the CPU path, the weights on the GPU path) and the draw (the viewer's
// profiling reads a pixel back, so it includes the vertex shader's blend;
// SwiftShader here: the GPU is the CPU). Frames 3-10 of 10 averaged.
async function frameCosts(page) {
  return page.evaluate(async () => {
    const L = window.likeness, e = L.expressions, v = L.viewer, out = {};
    const poses = [{ smile: 1 }, { surprise: 1 }, { openMouth: 1 }, { anger: 1 }];
    v.set_profiling(true);
    for (const path of ['cpu', 'gpu']) {
      e.setPath(path);
      // The GPU path's morph targets are sent over frames first (another level: sent again).
      while (e.gpuPending) await new Promise((r) => setTimeout(r, 50));
      let js = 0, draw = 0, wall = 0, n = 0;
      for (let i = 0; i < 10; i++) {
        const f0 = v.frames_drawn(), t0 = performance.now();
        await e.set(poses[i % poses.length]);
        while (v.frames_drawn() === f0) await new Promise((r) => requestAnimationFrame(r));
        if (i < 2) continue;
        js += e.stats.lastBlendMs + e.stats.lastUploadMs;
        draw += v.last_draw_ms();
        wall += performance.now() - t0;
        n++;
      }
      out[path] = { js: js / n, draw: draw / n, wall: wall / n, path: e.stats.path };
    }
    v.set_profiling(false);
    await e.set({});
    return out;
  });
}

// The parts of one sending of the morph targets (expressions.morphUpload).
const uploadText = (u) => `${u.entries.toLocaleString('en')} entries, ${(u.textureBytes / 1048576).toFixed(1)} MB of texture; ` +
  `${u.wallMs.toFixed(0)} ms from the first pose to uploaded, in ${u.calls} calls over as many frames, ${u.busyMs.toFixed(0)} ms of them busy, ` +
  `the longest call ${u.longestCallMs.toFixed(1)} ms but the last (attributes and the GL error check, which waits for the GPU ` +
  `process: ${u.lastCallMs.toFixed(1)} ms, of it ${u.syncMs.toFixed(1)} in the viewer); the page's packing ${u.pagePackMs.toFixed(1)} ms, copy into wasm ${u.copyMs.toFixed(1)}, ` +
  `split by shape ${u.splitMs.toFixed(1)}, prepare (normal offsets) ${u.prepareMs.toFixed(1)} in ${u.steps} steps (longest ` +
  `${u.longestStepMs.toFixed(1)}), entries sorted by vertex ${u.packMs.toFixed(1)}, texels written and uploaded ${u.uploadMs.toFixed(1)} ` +
  `in ${u.bands} bands (longest ${u.longestBandMs.toFixed(1)}) ms` +
  (u.longestGapMs !== undefined ? `; the longest gap between the page's frames meanwhile ${u.longestGapMs.toFixed(0)} ms` : '');

// Sent over frames, the work comes in units no bigger than one shape's
// prepare or one band of 32 rows of the 4096-texel-wide RGBA32F texture
// (2 MiB), over at least minCalls calls. Checked by structure, not by the
// clock: under a loaded machine a single band's GL call has taken 119 ms.
const BAND_BYTES = 32 * 4096 * 16;
const inSmallUnits = (u, shapes, minCalls) => u.steps === shapes && u.bands === Math.ceil(u.textureBytes / BAND_BYTES) &&
  u.calls >= minCalls;
const unitsText = (u, once) => `${u.calls} calls, ${u.steps} prepare steps, ${u.bands} bands for ` +
  `${(u.textureBytes / 1048576).toFixed(1)} MB; the longest call ${u.longestCallMs.toFixed(1)} ms against ` +
  `${once.callMs.toFixed(1)} ms at once`;

// The same morph targets sent at once (the viewer's set_morph_targets, the
// page's way before): one call, where its time goes.
async function sendAtOnce(page, level) {
  const once = await page.evaluate(() => {
    const v = window.likeness.viewer, e = window.likeness.expressions;
    const names = e.names, total = names.reduce((a, n) => a + e.shape(n).indices.length, 0);
    const counts = new Uint32Array(names.length), indices = new Uint32Array(total), offsets = new Float32Array(3 * total);
    let at = 0;
    names.forEach((n, i) => {
      const s = e.shape(n);
      counts[i] = s.indices.length;
      indices.set(s.indices, at);
      offsets.set(s.offsets, 3 * at);
      at += s.indices.length;
    });
    const t0 = performance.now();
    const err = v.set_morph_targets(counts, indices, offsets);
    const r = { err, callMs: performance.now() - t0, ...v.last_morph_upload() };
    e.setPath('gpu');  // the weights again (the upload zeroed them)
    return r;
  });
  note(`the same at level ${level} sent at once (set_morph_targets, the page's way before): one call of ${once.callMs.toFixed(0)} ms = ` +
       `copy into wasm ${once.copyMs.toFixed(1)} + split ${once.splitMs.toFixed(1)} + prepare with packing ${once.prepareMs.toFixed(1)} + ` +
       `GL upload ${once.uploadMs.toFixed(1)} ms${once.err ? ' (' + once.err + ')' : ''}`);
  return once;
}

// Sends the morph targets (the GPU path forced) and waits for them, timing
// the gaps between the page's animation frames meanwhile (a stall shows as a long gap).
const sendTargets = (page) => page.evaluate(async () => {
  const e = window.likeness.expressions;
  let last = performance.now(), longestGapMs = 0, sending = true;
  const tick = () => {
    const t = performance.now();
    longestGapMs = Math.max(longestGapMs, t - last);
    last = t;
    if (sending) requestAnimationFrame(tick);
  };
  requestAnimationFrame(tick);
  e.setPath('gpu');
  while (e.gpuPending || e.stats.path !== 'gpu') await new Promise((r) => setTimeout(r, 50));
  sending = false;
  return { ...e.morphUpload, longestGapMs };
});

async function reportCosts(page, level) {
  const c = await frameCosts(page);
  note(`full expression change on level ${level} (SwiftShader): CPU path: page ${c.cpu.js.toFixed(2)} ms (JS blend + update_positions), ` +
       `draw ${c.cpu.draw.toFixed(1)} ms, change to frame ${c.cpu.wall.toFixed(1)} ms; GPU path: page ${c.gpu.js.toFixed(3)} ms (weights), ` +
       `draw ${c.gpu.draw.toFixed(1)} ms (with the blend in the vertex shader), change to frame ${c.gpu.wall.toFixed(1)} ms`);
  check(`level ${level}: both paths drew the full expression changes, the GPU one without a vertex upload`,
        c.cpu.path === 'cpu' && c.gpu.path === 'gpu' && c.gpu.js < c.cpu.js, JSON.stringify(c));
  return c;
}

async function run(s) {
  const { page, fit } = await fittedHead(s);
  if (!fit) return;
  await page.selectOption('#level', '3');
  await page.uncheck('#show-points');  // the face, not the scan's points over it
  const rest = await canvasImage(page);
  if (SHOT_DIR) await page.locator('#canvas').screenshot({ path: path.join(SHOT_DIR, 'page_expression_rest.png') });
  await page.click('#expressions summary');
  await page.waitForFunction(() => window.likeness.expressions.level !== null &&
                             document.querySelectorAll('#expr-sliders input').length > 0, null, { timeout: JOB_TIMEOUT_MS });
  const baked = await expr(page);
  check('opening Expressions bakes the 77 shapes on the level shown, and shows sliders named by shape', baked.level === 3 &&
        baked.names === 77 && (await page.locator('label[for="expr-w-mouthSmileLeft"]').textContent()) === 'mouthSmileLeft',
        `level ${baked.level}, ${baked.names} shapes in ${Math.round(baked.bakeMs)} ms`);

  const sparse = await page.evaluate(() => {
    const e = window.likeness.expressions;
    const n = e.names.map((name) => e.shape(name).indices.length);
    // Offsets by size (scan units, metres for these scans): how many are of rounding size.
    const under = [1e-7, 1e-6, 1e-5].map((t) => {
      let c = 0;
      for (const name of e.names) {
        const o = e.shape(name).offsets;
        for (let k = 0; k < o.length; k += 3) if (Math.hypot(o[k], o[k + 1], o[k + 2]) < t) c++;
      }
      return c;
    });
    return { offsets: n.reduce((a, b) => a + b, 0), most: Math.max(...n), smile: e.shape('smile').indices.length, under };
  });
  note(`baked shapes at level 3: ${sparse.offsets.toLocaleString('en')} moved vertices over the 77 shapes ` +
       `(${(sparse.offsets * 16 / 1048576).toFixed(1)} MB as indices + offsets), at most ${sparse.most.toLocaleString('en')} ` +
       `in one shape, smile ${sparse.smile.toLocaleString('en')}; offsets shorter than 0.1, 1 and 10 micrometres: ` +
       sparse.under.map((c) => c.toLocaleString('en')).join(', '));
  const notesAuto = [];
  const onConsoleAuto = (m) => { if (m.type() === 'info') notesAuto.push(m.text()); };
  page.on('console', onConsoleAuto);
  await page.click('[data-preset="smile"]');
  await page.waitForFunction(() => window.likeness.expressions.weights.smile === 1 && window.likeness.expressions.stats.frames > 0);
  page.off('console', onConsoleAuto);
  // The first pose picked the blend: SwiftShader (headless Chromium) is
  // software GL, so the CPU blend, said once on the console.
  const auto = await page.evaluate(() => {
    const e = window.likeness.expressions;
    return { path: e.path, reason: e.pathReason, renderer: e.glRenderer, drawn: e.stats.path };
  });
  check('the first pose picks the blend by the GL: the CPU blend on SwiftShader, with a console note', auto.path === 'cpu' &&
        auto.drawn === 'cpu' && /swiftshader/i.test(auto.renderer || '') && notesAuto.some((n) => /blending on the CPU, software GL/.test(n)),
        `${JSON.stringify(auto)}; console: ${JSON.stringify(notesAuto)}`);
  // The GPU path forced from here on (the checks of its images and costs);
  // its first pose sends the 77 shapes: where that time goes.
  const upload3 = await sendTargets(page);
  note('morph targets sent at level 3: ' + uploadText(upload3));
  const once3 = await sendAtOnce(page, 3);
  check('level 3: the morph targets go to the viewer over frames, in steps of one shape and bands of 32 texel rows',
        inSmallUnits(upload3, 77, 10), unitsText(upload3, once3));
  const smile = await canvasImage(page);
  const smileDiff = differingFraction(rest, smile);
  // The vertex each side's mouthSmile moves most is the mouth corner's; the
  // smile moves it along the head's up (fit.headUp, from the worker's frame).
  const corners = await page.evaluate(() => {
    const e = window.likeness.expressions, p = e.positions(), r = e.restPositions(), up = window.likeness.fit.headUp;
    const most = (name) => {
      const s = e.shape(name);
      let best = -1, at = -1;
      for (let k = 0; k < s.indices.length; k++) {
        const len = Math.hypot(s.offsets[3 * k], s.offsets[3 * k + 1], s.offsets[3 * k + 2]);
        if (len > best) { best = len; at = s.indices[k]; }
      }
      return { at, len: best };
    };
    const lift = (v) => (p[3 * v] - r[3 * v]) * up[0] + (p[3 * v + 1] - r[3 * v + 1]) * up[1] + (p[3 * v + 2] - r[3 * v + 2]) * up[2];
    const L = most('mouthSmileLeft'), R = most('mouthSmileRight');
    return { left: lift(L.at), right: lift(R.at), leftLen: L.len, rightLen: R.len, leftAt: L.at, rightAt: R.at };
  });
  check('the smile preset changes the canvas and lifts both mouth corners', smileDiff > 0.002 &&
        corners.left > 0.3 * corners.leftLen && corners.right > 0.3 * corners.rightLen,
        `${(100 * smileDiff).toFixed(2)} % of pixels differ; corners up ${corners.left.toFixed(3)} / ${corners.right.toFixed(3)} ` +
        `(their mouthSmile offsets ${corners.leftLen.toFixed(3)} / ${corners.rightLen.toFixed(3)})`);
  // The smile above was blended on the GPU (morph targets in the vertex
  // shader); the CPU path must draw the same image (one shape at weight 1:
  // the GPU's normal offsets are the CPU's renormalized normals).
  const gpuState = await page.evaluate(() => ({ path: window.likeness.expressions.path, note: window.likeness.expressions.gpuNote,
                                                targets: window.likeness.viewer.morph_target_count(),
                                                uploadMs: window.likeness.expressions.morphUploadMs }));
  await page.evaluate(() => window.likeness.expressions.setPath('cpu'));
  const smileCpu = await canvasImage(page);
  await page.evaluate(() => window.likeness.expressions.setPath('gpu'));
  const smileGpuAgain = await canvasImage(page);
  const gpuCpu = pixelDiff(smile, smileCpu), again = pixelDiff(smile, smileGpuAgain);
  check('the smile blended on the GPU draws the CPU blend\'s image (and again after switching back)', gpuState.path === 'gpu' &&
        gpuState.targets === 77 && gpuCpu.fraction < 0.002 && again.fraction < 0.002,
        `${gpuState.targets} morph targets on the viewer (sent in ${Math.round(gpuState.uploadMs)} ms)${gpuState.note ? ', ' + gpuState.note : ''}; ` +
        `GPU vs CPU: max channel difference ${gpuCpu.max}, ${(100 * gpuCpu.fraction).toFixed(3)} % of pixels by more than 2; ` +
        `GPU after CPU: ${(100 * again.fraction).toFixed(3)} %`);
  // The wireframe's edges are not blended in the shader: with it on, the CPU path draws.
  await page.check('#wireframe');
  await page.waitForTimeout(200);
  const wirePath = await page.evaluate(() => window.likeness.expressions.stats.path);
  await page.uncheck('#wireframe');
  await page.waitForTimeout(200);
  const unwiredPath = await page.evaluate(() => window.likeness.expressions.stats.path);
  check('with the wireframe on the smile is blended on the CPU (its edges follow), off on the GPU again',
        wirePath === 'cpu' && unwiredPath === 'gpu', `wireframe on: ${wirePath}, off: ${unwiredPath}`);
  if (SHOT_DIR) {
    await page.locator('#canvas').screenshot({ path: path.join(SHOT_DIR, 'page_expression_smile.png') });
    await page.locator('#expressions').screenshot({ path: path.join(SHOT_DIR, 'page_expressions_panel.png') });
  }

  // One slider by keyboard: mouthSmileLeft to 0.10, on top of the smile.
  await page.selectOption('#expr-group', 'mouth');
  await page.focus('#expr-w-mouthSmileLeft');
  for (let i = 0; i < 10; i++) await page.keyboard.press('ArrowRight');
  await page.waitForTimeout(200);
  const slid = await expr(page);
  const sum = await page.evaluate((v) => {
    const e = window.likeness.expressions, p = e.positions(), r = e.restPositions();
    const at = (name) => { const s = e.shape(name), k = s.indices.indexOf(v); return k < 0 ? [0, 0, 0] : Array.from(s.offsets.subarray(3 * k, 3 * k + 3)); };
    const a = at('smile'), b = at('mouthSmileLeft');
    let err = 0;
    for (let c = 0; c < 3; c++) err = Math.max(err, Math.abs(p[3 * v + c] - (r[3 * v + c] + a[c] + 0.1 * b[c])));
    return { err, output: document.querySelector('output[for="expr-w-mouthSmileLeft"]').value };
  }, corners.leftAt);
  check('a slider (arrow keys) sets one shape\'s weight; the corner is rest + smile + 0.1 mouthSmileLeft',
        JSON.stringify(slid.weights) === JSON.stringify({ smile: 1, mouthSmileLeft: 0.1 }) && sum.err < 1e-4 && sum.output === '0.10',
        `weights ${JSON.stringify(slid.weights)}, shown ${sum.output}, blend error ${sum.err.toExponential(2)}`);

  // Open mouth: the lower teeth and tongue turn with the jaw. The vertex
  // openMouth moves most (on the chin, whole on the jaw) and the jaw's
  // matrix applied to its rest place move alike, and down.
  await page.click('[data-preset="openMouth"]');
  await page.waitForFunction(() => window.likeness.expressions.weights.openMouth === 1);
  await page.waitForTimeout(200);
  const jaw = await page.evaluate(() => {
    const e = window.likeness.expressions, r = e.restPositions(), m = e.jawMatrix, up = window.likeness.fit.headUp;
    const s = e.shape('openMouth');
    let best = -1, k = -1;
    for (let j = 0; j < s.indices.length; j++) {
      const len = Math.hypot(s.offsets[3 * j], s.offsets[3 * j + 1], s.offsets[3 * j + 2]);
      if (len > best) { best = len; k = j; }
    }
    const v = s.indices[k], p = [r[3 * v], r[3 * v + 1], r[3 * v + 2]];
    const moved = [0, 1, 2].map((c) => m[c] * p[0] + m[4 + c] * p[1] + m[8 + c] * p[2] + m[12 + c] - p[c]);
    const skin = [0, 1, 2].map((c) => s.offsets[3 * k + c]);
    const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    return { jawDown: dot(moved, up), skinDown: dot(skin, up), jawLen: Math.hypot(...moved), skinLen: best,
             cos: dot(moved, skin) / (Math.hypot(...moved) * best), components: (window.likeness.jawComponents || []).length };
  });
  if (SHOT_DIR) await page.locator('#canvas').screenshot({ path: path.join(SHOT_DIR, 'page_expression_open_mouth.png') });
  check('open mouth turns the lower teeth and tongue with the jaw: the chin\'s rest place moves as the chin does, down',
        jaw.components > 0 && jaw.jawDown < 0 && jaw.cos > 0.9 && jaw.jawLen > 0.7 * jaw.skinLen && jaw.jawLen < 1.3 * jaw.skinLen,
        `jaw moves it ${jaw.jawLen.toFixed(4)} (${jaw.jawDown.toFixed(4)} along up), the skin ${jaw.skinLen.toFixed(4)} ` +
        `(${jaw.skinDown.toFixed(4)}), cosine ${jaw.cos.toFixed(3)}; ${jaw.components} parts on the jaw`);

  // The gaze shapes turn the eyeballs (eyeLook*, 25 degrees at full
  // weight in the muscle layer): the left eye out = towards the head's own
  // left, in = towards its right, up = along its up; the other eye stays.
  const gaze = {};
  for (const name of ['eyeLookOutLeft', 'eyeLookInLeft', 'eyeLookUpRight']) {
    await page.evaluate((n) => window.likeness.expressions.set({ [n]: 1 }), name);
    gaze[name] = await page.evaluate(() => {
      const e = window.likeness.expressions, f = window.likeness.fit.headFacing, u = window.likeness.fit.headUp;
      const left = [u[1] * f[2] - u[2] * f[1], u[2] * f[0] - u[0] * f[2], u[0] * f[1] - u[1] * f[0]];
      // Each eye's facing turned by its matrix (column-major 3x3 part).
      const turned = (m) => [0, 1, 2].map((r) => m[r] * f[0] + m[4 + r] * f[1] + m[8 + r] * f[2]);
      const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
      return { eyes: window.likeness.eyeComponents || null, turns: e.eyeMatrices.map((m) => {
        const t = turned(m);
        return { left: dot(t, left), up: dot(t, u), deg: (Math.acos(Math.min(1, dot(t, f))) * 180) / Math.PI };
      }) };
    });
  }
  const g = gaze, r1 = (x) => x.toFixed(2);
  check('the gaze shapes turn the eyeballs: left eye out to the head\'s left, in to its right, the right eye up, about 25 degrees, the other eye still',
        g.eyeLookOutLeft.turns[0].left > 0 && g.eyeLookInLeft.turns[0].left < 0 && g.eyeLookUpRight.turns[1].up > 0 &&
        [g.eyeLookOutLeft.turns[0], g.eyeLookInLeft.turns[0], g.eyeLookUpRight.turns[1]].every((t) => t.deg > 20 && t.deg < 30) &&
        g.eyeLookOutLeft.turns[1].deg < 0.1 && g.eyeLookInLeft.turns[1].deg < 0.1 && g.eyeLookUpRight.turns[0].deg < 0.1 &&
        !!g.eyeLookOutLeft.eyes && g.eyeLookOutLeft.eyes.length === 2 && g.eyeLookOutLeft.eyes.every((i) => i !== null),
        'eye components ' + JSON.stringify(g.eyeLookOutLeft.eyes) + '; ' + Object.entries(g).map(([n, v]) => n + ': ' + v.turns.map((t, i) => (i ? 'right' : 'left') + ' eye ' + r1(t.deg) + ' deg (left ' + r1(t.left) +
          ', up ' + r1(t.up) + ')').join(', ')).join('; '));

  // tongueOut bends the tongue out: its component's own vertices are
  // pushed (before the jaw's matrix, which carries them as the core's
  // pose_tongue does); the frontmost along the face's facing by over 15 mm
  // (scan units are metres here), its rearmost not at all; smile puts the
  // tongue back at rest exactly.
  const tongueAfter = async (w) => {
    await page.evaluate((x) => window.likeness.expressions.set(x), w);
    return page.evaluate(() => {
      const a = window.likeness, e = a.expressions, f = a.fit.headFacing;
      const rest = a.componentsData && a.componentsData.tongue && a.componentsData.tongue.positions, p = e.tonguePositions || e.tongueBlend();
      if (!rest || !p) return { component: a.tongueComponent, none: true };
      const along = (arr, i) => arr[3 * i] * f[0] + arr[3 * i + 1] * f[1] + arr[3 * i + 2] * f[2];
      let tip = 0, root = 0, moved = 0;
      for (let i = 0; i < rest.length / 3; i++) {
        if (along(rest, i) > along(rest, tip)) tip = i;
        if (along(rest, i) < along(rest, root)) root = i;
        moved = Math.max(moved, Math.hypot(p[3 * i] - rest[3 * i], p[3 * i + 1] - rest[3 * i + 1], p[3 * i + 2] - rest[3 * i + 2]));
      }
      return { component: a.tongueComponent, tip: along(p, tip) - along(rest, tip), root: along(p, root) - along(rest, root), moved };
    });
  };
  const tongueOut = await tongueAfter({ tongueOut: 1 });
  if (SHOT_DIR) await page.locator('#canvas').screenshot({ path: path.join(SHOT_DIR, 'page_expression_tongue_out.png') });
  const tongueBack = await tongueAfter({ smile: 1 });
  check('tongueOut pushes the tongue out in the page (its tip forward by over 15 mm, its root still); smile puts it back at rest exactly',
        tongueOut.component !== null && tongueOut.tip > 0.015 && Math.abs(tongueOut.root) < 1e-6 && tongueBack.moved === 0,
        `tongue component ${tongueOut.component}; tongueOut: tip ${(1000 * (tongueOut.tip || 0)).toFixed(1)} mm forward, root ` +
        `${(1000 * (tongueOut.root || 0)).toFixed(3)} mm; after smile the tongue's vertices differ from rest by ${tongueBack.moved}`);

  // On the GPU path the tongue's push is its component's own morph targets
  // (a frame sends its weights, no vertex): tongueOut drawn so changes the
  // picture against the same pose with the tongue held at rest, and draws
  // the CPU path's picture. Per frame, over 20 frames of tongueOut moving:
  // the tongue's vertices are sent on the CPU path every frame, never on
  // the GPU path; the page's time on the tongue is reported.
  const tongueFrames = (path) => page.evaluate(async (p) => {
    const a = window.likeness, e = a.expressions;
    await e.setPath(p);
    const st = e.tongueStats, before = { frames: st.frames, ms: st.ms, uploads: st.uploads };
    for (let k = 1; k <= 20; k++) await e.set({ tongueOut: k / 20 });
    return { path: st.path, frames: st.frames - before.frames, msPerFrame: (st.ms - before.ms) / (st.frames - before.frames),
             uploads: st.uploads - before.uploads, targets: a.viewer.component_morph_target_count(a.tongueComponent) };
  }, path);
  const tongueOnGpu = await tongueFrames('gpu');
  const outGpu = await canvasImage(page);
  await page.evaluate(async () => { const e = window.likeness.expressions; e.tongueHeld = true; await e.set({ tongueOut: 1 }); });
  const heldGpu = await canvasImage(page);
  await page.evaluate(async () => { const e = window.likeness.expressions; e.tongueHeld = false; await e.set({ tongueOut: 1 }); });
  const tongueOnCpu = await tongueFrames('cpu');
  const outCpu = await canvasImage(page);
  await page.evaluate(() => window.likeness.expressions.setPath('gpu'));
  const tongueMoves = pixelDiff(outGpu, heldGpu), tongueSame = pixelDiff(outGpu, outCpu);
  note(`the tongue per frame (tongueOut moving, 20 frames): GPU path ${tongueOnGpu.msPerFrame.toFixed(3)} ms, ` +
       `CPU path ${tongueOnCpu.msPerFrame.toFixed(3)} ms (the page's side: weights, or blend and upload)`);
  check('tongueOut on the GPU path moves the tongue on screen by its morph targets, as the CPU path draws it, without sending its vertices',
        tongueOnGpu.path === 'gpu' && tongueOnGpu.targets >= 1 && tongueOnGpu.uploads === 0 && tongueOnGpu.frames === 20 &&
        tongueOnCpu.path === 'cpu' && tongueOnCpu.uploads === 20 && tongueMoves.fraction > 0.0002 && tongueMoves.max > 40 && tongueSame.fraction < 0.002,
        `GPU path: ${tongueOnGpu.targets} tongue targets, ${tongueOnGpu.uploads} vertex uploads in ${tongueOnGpu.frames} frames; ` +
        `CPU path: ${tongueOnCpu.uploads} in ${tongueOnCpu.frames}; tongue out vs held at rest: ${(100 * tongueMoves.fraction).toFixed(3)} % ` +
        `of pixels differ (max ${tongueMoves.max}); GPU vs CPU: ${(100 * tongueSame.fraction).toFixed(3)} % (max ${tongueSame.max})`);

  // Neutral: the rest positions exactly (the fitted level's), and the rest image.
  await page.click('[data-preset="neutral"]');
  await page.waitForTimeout(200);
  const neutral = await fromRest(page);
  const neutralImage = await canvasImage(page);
  const neutralDiff = differingFraction(rest, neutralImage);
  const sliderZero = await page.inputValue('#expr-w-mouthSmileLeft');
  const jawRest = await page.evaluate(() => Array.from(window.likeness.expressions.jawMatrix).join(','));
  const neutralExact = pixelDiff(rest, neutralImage);
  check('neutral gives the rest positions exactly, the rest image, zeroed sliders and the jaw at rest', neutral.d === 0 &&
        neutral.fitted === 0 && neutralDiff < 0.002 && neutralExact.max === 0 && sliderZero === '0' &&
        jawRest === '1,0,0,0,0,1,0,0,0,0,1,0,0,0,0,1',
        `max |blend - rest| ${neutral.d}, |rest - fitted level| ${neutral.fitted} over ${neutral.n / 3} vertices; ` +
        `${(100 * neutralDiff).toFixed(3)} % of pixels differ (max channel difference ${neutralExact.max}); slider ${sliderZero}`);
  const costs3 = await reportCosts(page, 3);
  // From here the blend the page picks by itself (the CPU one on SwiftShader), as users get it.
  await page.evaluate(() => { window.likeness.expressions.path = null; });

  // Talk to its end (back at rest), then stopped by its button, then by Animate.
  const t3 = await talkMs(page, 3);
  const afterTalk = await fromRest(page);
  // What Talk plays, sampled every millisecond (the frames drawn depend on
  // the GPU): visemes at full weight, the blink closing fully, and no cut:
  // the fastest change is the blink closing (a smoothstep over 70 ms, at
  // most 0.0214 per ms), where a cut would jump by a whole weight.
  const sequence = await page.evaluate(() => {
    const e = window.likeness.expressions, peaks = {};
    let jump = 0, prev = {};
    for (let t = 0; t <= e.talkSeconds; t += 0.001) {
      const w = e.talkWeights(t);
      for (const n of new Set([...Object.keys(w), ...Object.keys(prev)])) jump = Math.max(jump, Math.abs((w[n] || 0) - (prev[n] || 0)));
      for (const [n, v] of Object.entries(w)) peaks[n] = Math.max(peaks[n] || 0, v);
      prev = w;
    }
    return { peaks, jump, end: Object.keys(e.talkWeights(e.talkSeconds)).length };
  });
  const visemes = Object.keys(sequence.peaks).filter((n) => n.startsWith('viseme_') && sequence.peaks[n] >= 0.7);
  const drawn = Object.keys(t3.talkPeaks).filter((n) => n.startsWith('viseme_'));
  check('Talk plays its frames (visemes cross-fading, blinks) and ends at rest', t3.talkFrames >= 5 && !t3.talking &&
        t3.pressed === 'false' && visemes.length >= 8 && sequence.peaks.blink > 0.99 && sequence.jump < 0.03 && sequence.end === 0 &&
        drawn.length >= 3 && afterTalk.d === 0 && Object.keys(t3.weights).length === 0,
        `${t3.talkFrames} frames drew ${drawn.length} visemes; the sequence: ${visemes.length} visemes at 0.7 or more ` +
        `(${visemes.join(' ')}), blink peak ${(sequence.peaks.blink || 0).toFixed(2)}, largest step in 1 ms ${sequence.jump.toFixed(4)}; ` +
        `max |blend - rest| ${afterTalk.d}`);
  // The lids close during the demo: the frame it drew with the largest
  // blink weight, posed again, closes each eye's middle rim gap to under
  // 10 % of its rest opening (the core's eyeBlink check, on the mesh), and
  // the eyes looked left, right and up meanwhile (the Gaze clip played
  // with Talk, as the GLB's Gaze animation holds it).
  const lids = await page.evaluate(async () => {
    const e = window.likeness.expressions, f = e.talkBlinkFrame;
    if (!f || e.lids.length !== 2) return { none: true, lids: e.lids.length, frame: !!f };
    await e.set(f.weights);
    const p = e.positions(), r = e.restPositions();
    const gap = (q, [u, l]) => Math.hypot(q[3 * u] - q[3 * l], q[3 * u + 1] - q[3 * l + 1], q[3 * u + 2] - q[3 * l + 2]);
    const ratios = e.lids.map((pair) => gap(p, pair) / gap(r, pair)), restMm = e.lids.map((pair) => 1000 * gap(r, pair));
    return { t: f.t, blink: f.weights.blink, ratios, restMm, others: Object.keys(f.weights).filter((n) => n !== 'blink') };
  });
  if (SHOT_DIR && !lids.none) await page.locator('#canvas').screenshot({ path: path.join(SHOT_DIR, 'page_talk_blink.png') });
  await page.evaluate(() => window.likeness.expressions.set({}));
  const looked = ['eyeLookOutLeft', 'eyeLookInRight', 'eyeLookInLeft', 'eyeLookOutRight', 'eyeLookUpLeft', 'eyeLookUpRight']
    .map((n) => [n, t3.talkPeaks[n] || 0]);
  check('the talking demo closes the lids on a blink (each eye\'s gap under 10 % of its rest opening in the frame drawn) and turns the eyes with Gaze',
        !lids.none && lids.ratios.every((x) => x < 0.10) && lids.blink >= 0.999 &&
        looked.every(([n, w]) => w > (n.startsWith('eyeLookUp') ? 0.5 : 0.9)),
        lids.none ? JSON.stringify(lids) : `frame at ${lids.t.toFixed(3)} s, blink ${lids.blink.toFixed(3)} with ${lids.others.join(' ')}: ` +
        `lid gaps ${lids.ratios.map((x) => (100 * x).toFixed(1) + ' %').join(', ')} of rest (${lids.restMm.map((x) => x.toFixed(1)).join(', ')} mm); ` +
        `gaze peaks ${looked.map(([n, w]) => n + ' ' + w.toFixed(2)).join(', ')}`);
  await page.click('#btn-talk');
  // This Talk's frames (talkFrames still holds the last Talk's until this
  // one starts, so the count alone could be read too early).
  await page.waitForFunction(() => window.likeness.expressions.talking && window.likeness.expressions.talkFrames >= 5);
  const playing = await expr(page);
  await page.click('#btn-talk');
  const stoppedAt = (await expr(page)).talkFrames;
  await page.waitForTimeout(300);
  const stopped = await expr(page);
  const stopRest = await fromRest(page);
  check('Talk stops on its button, at rest, and draws no more frames', playing.talking && playing.pressed === 'true' &&
        !stopped.talking && stopped.talkFrames === stoppedAt && stopped.pressed === 'false' && stopRest.d === 0,
        `talking ${playing.talking} -> ${stopped.talking}, frames ${stoppedAt} -> ${stopped.talkFrames}, max |blend - rest| ${stopRest.d}`);
  await page.click('#btn-talk');
  await page.waitForFunction(() => window.likeness.expressions.talking && window.likeness.expressions.talkFrames >= 3);
  await page.check('#animate');
  await page.waitForTimeout(500);
  const byAnimate = await page.evaluate(() => ({ talking: window.likeness.expressions.talking, running: window.likeness.animation.running,
                                                 weights: Object.keys(window.likeness.expressions.weights).length }));
  await page.uncheck('#animate');
  await page.waitForTimeout(1500);  // the rest pose comes back from the worker
  check('Animate stops Talk (one thing moves the head at a time)', !byAnimate.talking && byAnimate.running && byAnimate.weights === 0,
        JSON.stringify(byAnimate));

  // Words typed beside Talk: the head says them, read to visemes by
  // TalkingHead's lipsync-en (web/js/speech.js; "papa" is PP aa PP aa, 4.06
  // of its units) and made a clip by the core (anim/clips.h speech_clip:
  // 0.1 s a unit, after a 0.1 s breath, 0.3 s at rest to end), without the
  // demo's gaze, and ends at rest; words with nothing to say get the reason
  // and play nothing; with the box empty again Talk plays the demo phrase.
  await page.fill('#say-text', 'papa');
  const say = await talkMs(page, 3);
  const sayRest = await fromRest(page);
  const sayClip = await page.evaluate(() => {
    // Every 1 ms and at the clip's keys (the visemes' middles, where they peak).
    const e = window.likeness.expressions, peaks = {}, times = e.talkKeys;
    for (let t = 0; t <= e.talkSeconds; t += 0.001) times.push(t);
    for (const t of times)
      for (const [n, v] of Object.entries(e.demoWeights(t))) peaks[n] = Math.max(peaks[n] || 0, v);
    return { peaks, seconds: e.talkSeconds, saying: e.saying };
  });
  const sayDrawn = Object.keys(say.talkPeaks).filter((n) => n.startsWith('viseme_') || n.startsWith('eyeLook'));
  const round2 = (o) => Object.entries(o).map(([n, v]) => n + ' ' + v.toFixed(2)).join(', ');
  check('words typed beside Talk are said: "papa" plays viseme_PP (0.8) and viseme_aa (1.0), nothing else but blinks, in 0.806 s, and ends at rest',
        sayClip.saying === 'papa' && Math.abs(sayClip.seconds - 0.806) < 1e-6 &&
        Object.keys(sayClip.peaks).sort().join(' ') === 'blink viseme_PP viseme_aa' &&
        Math.abs(sayClip.peaks.viseme_PP - 0.8) < 1e-9 && Math.abs(sayClip.peaks.viseme_aa - 1) < 1e-9 &&
        say.talkFrames >= 2 && sayDrawn.length >= 1 && sayDrawn.every((n) => n === 'viseme_PP' || n === 'viseme_aa') &&
        !say.talking && sayRest.d === 0,
        `${sayClip.seconds} s; the clip's peaks: ${round2(sayClip.peaks)}; ${say.talkFrames} frames drew ${round2(say.talkPeaks)}; max |blend - rest| ${sayRest.d}`);
  // In German (TalkingHead's lipsync-de, loaded from the page's origin when
  // first chosen): "Mama" is PP aa PP aa too; the page starts in English
  // (the test browser's language).
  const startLang = await page.inputValue('#say-lang');
  await page.selectOption('#say-lang', 'de');
  await page.fill('#say-text', 'Mama');
  await talkMs(page, 3);
  const deClip = await page.evaluate(() => {
    const e = window.likeness.expressions, peaks = {};
    for (const t of e.talkKeys) for (const [n, v] of Object.entries(e.demoWeights(t))) peaks[n] = Math.max(peaks[n] || 0, v);
    return { peaks, saying: e.saying };
  });
  check('words in German are read by its own reader: "Mama" plays viseme_PP and viseme_aa (the page started in English)',
        startLang === 'en' && deClip.saying === 'Mama' && Object.keys(deClip.peaks).filter((n) => n !== 'blink').sort().join(' ') === 'viseme_PP viseme_aa',
        `started in ${startLang}; the clip's peaks: ${round2(deClip.peaks)}`);
  await page.selectOption('#say-lang', 'en');
  await page.fill('#say-text', '!? ...');
  await page.click('#btn-talk');
  await page.waitForFunction(() => /nothing to say/.test(document.getElementById('expr-stats').textContent), null, { timeout: JOB_TIMEOUT_MS });
  const nothing = await page.evaluate(() => ({ talking: window.likeness.expressions.talking, stats: document.getElementById('expr-stats').textContent }));
  check('words with nothing to say are not said: the reason shows and nothing plays', !nothing.talking, nothing.stats);
  await page.fill('#say-text', '');

  // Level 2: baked again for that level, the blend's cost there.
  await page.selectOption('#level', '2');
  const t2 = await talkMs(page, 2);
  check('at level 2 the shapes are baked for level 2 and Talk plays', t2.level === 2 && t2.talkFrames >= 5,
        `level ${t2.level}, baked in ${Math.round(t2.bakeMs)} ms, ${t2.talkFrames} frames`);
  const costs2 = await reportCosts(page, 2);
  note('morph targets sent at level 2: ' + uploadText(await page.evaluate(() => window.likeness.expressions.morphUpload)));
  const once2 = await sendAtOnce(page, 2);
  const upload2 = await page.evaluate(() => window.likeness.expressions.morphUpload);
  check('level 2: the morph targets go to the viewer over frames, in steps of one shape and bands of 32 texel rows',
        inSmallUnits(upload2, 77, 5), unitsText(upload2, once2));
  // The pick measured: on this software GL the CPU blend's frames drew faster (levels 2 and 3 together).
  check('the blend picked on SwiftShader (CPU) is the faster one measured, levels 2 and 3 together',
        costs2.cpu.wall + costs3.cpu.wall < costs2.gpu.wall + costs3.gpu.wall,
        `change to frame, CPU path: level 2 ${costs2.cpu.wall.toFixed(1)} ms, level 3 ${costs3.cpu.wall.toFixed(1)} ms; ` +
        `GPU path: level 2 ${costs2.gpu.wall.toFixed(1)} ms, level 3 ${costs3.gpu.wall.toFixed(1)} ms`);
  // The control mesh (level 0): baked and posed the same way, here with a
  // viewer that refuses the morph targets (as for GL limits): the page says
  // so on the console and blends on the CPU.
  const notes = [];
  const onConsole = (m) => { if (m.type() === 'info') notes.push(m.text()); };
  page.on('console', onConsole);
  await page.evaluate(() => {
    const v = window.likeness.viewer;
    v.realBeginMorphTargets = v.begin_morph_targets;
    v.begin_morph_targets = () => 'simulated: the entries do not fit a 2048 texture';
  });
  await page.selectOption('#level', '0');
  await page.click('[data-preset="smile"]');
  await page.waitForFunction(() => window.likeness.expressions.level === 0 || document.body.dataset.state === 'error', null,
                             { timeout: JOB_TIMEOUT_MS });
  await page.waitForTimeout(200);
  const control = await page.evaluate(() => {
    const e = window.likeness.expressions, p = e.positions(), r = e.restPositions();
    let moved = 0;
    for (let i = 0; i < p.length; i++) if (p[i] !== r[i]) moved++;
    return { level: e.level, n: p.length / 3, moved, state: document.body.dataset.state };
  });
  const refused = await page.evaluate(() => ({ path: window.likeness.expressions.path, note: window.likeness.expressions.gpuNote,
                                               drawn: window.likeness.expressions.stats.path }));
  await page.click('[data-preset="neutral"]');
  check('on the control mesh (level 0) the smile is baked and shown too', control.level === 0 && control.moved > 0 &&
        control.state === 'done', JSON.stringify(control) + ' ' + (await bannerText(page)));
  check('a viewer that refuses the morph targets: a console note, and the blend on the CPU', refused.path === 'cpu' &&
        refused.drawn === 'cpu' && /simulated/.test(refused.note || '') && notes.some((n) => /blending on the CPU.*simulated/.test(n)),
        `${JSON.stringify(refused)}; console: ${JSON.stringify(notes)}`);
  page.off('console', onConsole);
  await page.evaluate(() => {
    const v = window.likeness.viewer;
    v.begin_morph_targets = v.realBeginMorphTargets;
    window.likeness.expressions.path = null;  // picked again by the GL at the next pose
  });
  await page.selectOption('#level', '3');
  await page.check('#show-points');
  await page.waitForTimeout(300);
}

export const flow = { name: 'expressions', title: 'Expressions: presets, shape sliders, Talk, on the fitted head', run };
runAlone(import.meta.url, flow);
