// Expressions (issue 38, in the page): presets, sliders for ARKit's shapes
// and the visemes, and Talk, played from the muscle layer's shapes baked on
// the kept head (the worker's faceShapes job: each shape's moved vertices
// and their offsets in the scan frame, at one level), fetched once per head
// and level.
//
// The blend runs on the CPU, in JavaScript: positions = rest + sum of
// w_i * offsets_i over the shapes with a weight (sparse), handed to the
// viewer's update_positions, which renormalizes and uploads the moved
// vertices. GPU blending (morph targets in the renderer's vertex shader, so
// that playback costs no CPU per frame, as issue 38 asks) is NOT done; the
// measured cost per frame is in docs/design/page.md. The lower teeth and
// tongue ride on the jaw: the shapes' jaw motions blended as I + sum of
// w_i (M_i - I) (what the GLB's morph targets on the teeth do); the tongue
// does not come out (tongueOut moves the skin only here).
import { app, page, ui, showError } from './state.js';
import { runJob } from './worker_client.js';
import { onHeadShown, showStage, view } from './head_view.js';
import { onAnimationStop, stopAnimation } from './animation.js';

// "hello, nice to meet you": [time (s), viseme, weight] keys; the weights
// cross-fade smoothly from one key to the next (viseme_sil is the rest).
const PHRASE = [
  [0.00, 'viseme_sil', 0], [0.12, 'viseme_kk', 0.5], [0.22, 'viseme_E', 0.9], [0.32, 'viseme_nn', 0.7],
  [0.46, 'viseme_O', 1.0], [0.62, 'viseme_U', 0.5], [0.80, 'viseme_sil', 0],          // hello,
  [0.92, 'viseme_nn', 0.8], [1.04, 'viseme_aa', 1.0], [1.16, 'viseme_I', 0.8], [1.28, 'viseme_SS', 0.9],  // nice
  [1.38, 'viseme_DD', 0.8], [1.48, 'viseme_U', 0.8],                                   // to
  [1.58, 'viseme_PP', 1.0], [1.72, 'viseme_I', 1.0], [1.84, 'viseme_DD', 0.7],         // meet
  [1.92, 'viseme_I', 0.6], [2.08, 'viseme_U', 1.0], [2.30, 'viseme_sil', 0],            // you
  [2.60, 'viseme_sil', 0],
];
// Blinks: start (s); each closes in 70 ms and opens in 130 ms, as people do.
const BLINKS = [0.40, 2.20];
const BLINK_CLOSE = 0.07, BLINK_OPEN = 0.13;
const TALK_END = PHRASE[PHRASE.length - 1][0];

const smooth = (x) => x * x * (3 - 2 * x);

// The weights at t seconds into Talk.
export function talkWeights(t) {
  const w = {};
  const add = (name, v) => { if (v > 0 && name !== 'viseme_sil') w[name] = (w[name] || 0) + v; };
  let k = 0;
  while (k + 1 < PHRASE.length && PHRASE[k + 1][0] <= t) k++;
  if (k + 1 < PHRASE.length) {
    const [t0, a, wa] = PHRASE[k], [t1, b, wb] = PHRASE[k + 1];
    const s = smooth(Math.min(1, Math.max(0, (t - t0) / (t1 - t0))));
    add(a, (1 - s) * wa);
    add(b, s * wb);
  }
  for (const b of BLINKS) {
    const u = t - b;
    const v = u < 0 ? 0 : u < BLINK_CLOSE ? smooth(u / BLINK_CLOSE) : u < BLINK_CLOSE + BLINK_OPEN ? 1 - smooth((u - BLINK_CLOSE) / BLINK_OPEN) : 0;
    add('blink', v);
  }
  return w;
}

const PRESETS = [...document.querySelectorAll('#expressions [data-preset]')].map((b) => b.dataset.preset);
function groupOf(name) {
  if (name.startsWith('viseme_')) return 'viseme';
  if (PRESETS.includes(name)) return 'expression';
  for (const g of ['eye', 'jaw', 'mouth', 'brow']) if (name.startsWith(g)) return g;
  return 'other';
}

// The baked shapes of the head shown: {fit, level, shapes: Map name ->
// {indices, offsets}, names, rest (the level's rest positions), out (the
// last blend)}.
let baked = null;
let baking = null;  // {fit, level, promise}
let talkT0 = 0, talkGeneration = 0;

const ex = app.expressions = {
  weights: {},          // shape name -> weight, only the non-zero ones
  level: null,          // the level of the baked shapes (null: none yet)
  names: [],
  bakeMs: null,         // the worker's bake of the last level fetched
  talking: false,
  talkFrames: 0,
  talkPeaks: {},        // the last Talk's largest weight per shape drawn
  jawMatrix: null,      // the lower teeth's and tongue's last matrix (column-major 4x4, scan frame)
  // Per drawn pose: the JS blend and the viewer's update_positions (ms, sums over frames).
  stats: { frames: 0, blendMs: 0, uploadMs: 0, lastBlendMs: 0, lastUploadMs: 0 },
  // For the tests and the console: copies of the last blended and the rest positions, a shape's data.
  positions: () => (baked ? baked.out.slice() : null),
  restPositions: () => (baked ? baked.rest.slice() : null),
  shape: (name) => (baked && baked.shapes.get(name)) || null,
  talkWeights: (t) => talkWeights(t),
  talkSeconds: TALK_END,
};

function levelMesh(level) {
  const m = app.fit.meshes;
  return level === 0 ? m.control : m.levels[level - 1];
}

function fresh(b) { return !!b && !!app.fit && b.fit === app.fit && b.level === Number(ui.level.value); }

// The shapes baked at the chosen level, fetched from the worker once per
// head and level. Resolves to the baked set, or null (no head, another head
// meanwhile, or an error, shown).
function ensureShapes() {
  if (fresh(baked)) return Promise.resolve(baked);
  if (!app.fit) return Promise.resolve(null);
  const fit = app.fit, level = Number(ui.level.value);
  if (baking && baking.fit === fit && baking.level === level) return baking.promise;
  ui.exprStats.textContent = 'Baking the expressions on ' + (level === 0 ? 'the control mesh' : 'level ' + level) + '…';
  const promise = runJob({ type: 'faceShapes', level }, []).then((r) => {
    if (baking && baking.promise === promise) baking = null;
    if (app.fit !== fit) return null;
    const mesh = levelMesh(level);
    if (!r.ok || r.vertexCount !== mesh.vertexCount) {
      showError('Expressions: ' + (r.ok ? 'the baked shapes have ' + r.vertexCount + ' vertices, the level ' + mesh.vertexCount : r.message));
      return null;
    }
    const shapes = new Map(r.shapes.map((s) => [s.name, { indices: s.indices, offsets: s.offsets, jaw: s.jawMatrix || null }]));
    const rest = new Float32Array(mesh.positions);
    baked = { fit, level, shapes, names: r.shapes.map((s) => s.name), rest, out: rest.slice() };
    Object.assign(ex, { level, names: baked.names, bakeMs: r.bakeMs });
    ui.exprStats.textContent = baked.names.length + ' shapes baked on ' + (level === 0 ? 'the control mesh' : 'level ' + level) +
      ' (' + mesh.vertexCount.toLocaleString('en') + ' vertices) in ' + Math.round(r.bakeMs) + ' ms.';
    buildSliders();
    return fresh(baked) ? baked : null;
  }, () => { if (baking && baking.promise === promise) baking = null; return null; });
  baking = { fit, level, promise };
  return promise;
}

// rest + sum w_i offsets_i into baked.out, then onto the screen when the
// viewer shows this level's mesh. Returns false when it could not be drawn.
function draw() {
  const b = baked;
  if (!fresh(b) || app.shownStage !== 'subdivide' || view.level !== b.level) return false;
  const t0 = performance.now();
  const out = b.out;
  out.set(b.rest);
  for (const [name, w] of Object.entries(ex.weights)) {
    const s = b.shapes.get(name);
    if (!s || !w) continue;
    const idx = s.indices, off = s.offsets;
    for (let k = 0, o = 0; k < idx.length; k++, o += 3) {
      const i = 3 * idx[k];
      out[i] += w * off[o];
      out[i + 1] += w * off[o + 1];
      out[i + 2] += w * off[o + 2];
    }
  }
  const t1 = performance.now();
  const err = app.viewer.update_positions(out);
  const t2 = performance.now();
  if (err) { stopTalk(); showError('Expressions: ' + err); return false; }
  moveJaw(b);
  const st = ex.stats;
  st.frames++;
  st.lastBlendMs = t1 - t0;
  st.lastUploadMs = t2 - t1;
  st.blendMs += st.lastBlendMs;
  st.uploadMs += st.lastUploadMs;
  return true;
}

// The lower teeth and tongue (app.jawComponents) on the blended jaw motion.
const IDENTITY = new Float32Array([1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]);
function moveJaw(b) {
  const m = IDENTITY.slice();
  for (const [name, w] of Object.entries(ex.weights)) {
    const jaw = w && b.shapes.get(name) && b.shapes.get(name).jaw;
    if (jaw) for (let i = 0; i < 16; i++) m[i] += w * (jaw[i] - IDENTITY[i]);
  }
  ex.jawMatrix = m;
  for (const i of app.jawComponents || []) app.viewer.set_component_matrix(i, m);
}

function statsText() {
  const st = ex.stats, n = Object.keys(ex.weights).length;
  return n + (n === 1 ? ' shape' : ' shapes') + ' on level ' + baked.level + ': blend ' + st.lastBlendMs.toFixed(1) +
    ' ms + viewer update ' + st.lastUploadMs.toFixed(1) + ' ms (JavaScript, on the CPU).';
}

// New weights onto the head: Animate stops (both would write the head), the
// subdivided head is shown, the shapes fetched if needed.
async function setWeights(weights, { fromTalk = false } = {}) {
  if (!app.fit) return;
  if (!fromTalk) stopTalk(false);
  if (app.animation.running) stopAnimation(false);  // clears the weights (onAnimationStop): set them after
  if (app.shownStage !== 'subdivide') showStage('subdivide');
  ex.weights = weights;
  if (!fromTalk) syncSliders();
  const b = await ensureShapes();
  if (b && ex.weights === weights && draw() && !ex.talking) ui.exprStats.textContent = statsText();
}

function syncSliders() {
  for (const input of ui.exprSliders.querySelectorAll('input[type=range]')) {
    const w = ex.weights[input.dataset.shape] || 0;
    input.value = String(w);
    input.nextElementSibling.value = w.toFixed(2);
  }
}

// One group's sliders (the select picks the group), labelled by the shapes' exact names.
function buildSliders() {
  const box = ui.exprSliders;
  box.textContent = '';
  if (!baked) return;
  for (const name of baked.names.filter((n) => groupOf(n) === ui.exprGroup.value && n !== 'neutral' && n !== 'viseme_sil')) {
    const id = 'expr-w-' + name;
    const label = document.createElement('label');
    label.htmlFor = id;
    label.textContent = name;
    const input = document.createElement('input');
    Object.assign(input, { type: 'range', id, min: '0', max: '1', step: '0.01', value: String(ex.weights[name] || 0) });
    input.dataset.shape = name;
    const out = document.createElement('output');
    out.htmlFor = id;
    out.value = (ex.weights[name] || 0).toFixed(2);
    input.addEventListener('input', () => {
      const w = { ...ex.weights };
      const v = Number(input.value);
      if (v > 0) w[name] = v; else delete w[name];
      out.value = v.toFixed(2);
      setWeights(w).catch(() => {});
    });
    box.append(label, input, out);
  }
}

// ---- Talk -------------------------------------------------------------------
async function startTalk() {
  if (!app.fit || ex.talking) return;
  await setWeights({});
  if (!(await ensureShapes())) return;
  const generation = ++talkGeneration;
  ex.talking = true;
  ex.talkFrames = 0;
  ex.talkPeaks = {};
  ex.stats = { frames: 0, blendMs: 0, uploadMs: 0, lastBlendMs: 0, lastUploadMs: 0 };
  ui.talk.textContent = 'Stop talking';
  ui.talk.setAttribute('aria-pressed', 'true');
  talkT0 = performance.now();
  let drawnAtUpload = -1;
  const frame = () => {
    if (!ex.talking || generation !== talkGeneration) return;
    // A pose only after the last one was drawn (a slow GPU: no blend thrown away).
    if (app.viewer.frames_drawn() === drawnAtUpload) { requestAnimationFrame(frame); return; }
    const t = (performance.now() - talkT0) / 1000;
    if (t >= TALK_END) { stopTalk(); return; }
    ex.weights = talkWeights(t);
    if (!draw()) { stopTalk(); return; }
    drawnAtUpload = app.viewer.frames_drawn();
    ex.talkFrames++;
    for (const [name, w] of Object.entries(ex.weights)) ex.talkPeaks[name] = Math.max(ex.talkPeaks[name] || 0, w);
    const st = ex.stats;
    ui.exprStats.textContent = 'Talking: ' + ex.talkFrames + ' frames, per frame on level ' + baked.level + ': blend ' +
      (st.blendMs / st.frames).toFixed(1) + ' ms + viewer update ' + (st.uploadMs / st.frames).toFixed(1) + ' ms (JavaScript, on the CPU).';
    requestAnimationFrame(frame);
  };
  requestAnimationFrame(frame);
}

// Stops Talk; rest: back to the rest pose (else the caller sets the next).
function stopTalk(rest = true) {
  if (!ex.talking) return;
  ex.talking = false;
  talkGeneration++;
  ui.talk.textContent = 'Talk';
  ui.talk.setAttribute('aria-pressed', 'false');
  if (rest) { ex.weights = {}; draw(); syncSliders(); }
}

// Another job, head or view (stopAnimation is called for each): Talk stops,
// the weights go to zero and the rest pose comes back where it is shown.
function clearExpressions() {
  const posed = ex.talking || Object.keys(ex.weights).length > 0;
  stopTalk(false);
  ex.weights = {};
  syncSliders();
  if (posed) draw();
}

export function wireExpressions() {
  for (const b of ui.expressions.querySelectorAll('[data-preset]')) {
    b.addEventListener('click', () => setWeights(b.dataset.preset === 'neutral' ? {} : { [b.dataset.preset]: 1 }).catch(() => {}));
  }
  ui.talk.addEventListener('click', () => (ex.talking ? stopTalk() : startTalk().catch(() => {})));
  ui.exprGroup.addEventListener('change', buildSliders);
  // Opening the panel bakes the shapes (not while another job runs).
  ui.expressions.addEventListener('toggle', () => {
    if (ui.expressions.open && app.fit && page.snapshot().state !== 'working') ensureShapes().catch(() => {});
  });
  onAnimationStop(clearExpressions);
  ui.animate.addEventListener('change', () => { if (ui.animate.checked) clearExpressions(); });
  // The head shown again at rest (another level, the distance map, the
  // texture): the weights go on again, baked at that level if need be.
  onHeadShown(() => {
    if (ex.talking || !Object.keys(ex.weights).length) return;
    const weights = ex.weights;
    ensureShapes().then((b) => { if (b && ex.weights === weights) draw(); }, () => {});
  });
}
