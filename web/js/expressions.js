// Expressions (issue 38, in the page): presets, sliders for ARKit's shapes
// and the visemes, and Talk, played from the muscle layer's shapes baked on
// the kept head (the worker's faceShapes job: each shape's moved vertices
// and their offsets in the scan frame, at one level), fetched once per head
// and level.
//
// The blend runs on the GPU on a hardware GL: the shapes go to the viewer
// once per head and level as morph targets (a float data texture read by
// the vertex shader, normal offsets computed there at full weight; sent
// over frames, see sendTargets, the CPU path drawing meanwhile), and a
// frame is only the weights (set_morph_weights, a uniform array): no vertex
// upload, no loop over vertices here. The CPU blend (positions = rest + sum
// of w_i * offsets_i over the shapes with a weight, handed to the viewer's
// update_positions, which renormalizes and uploads the moved vertices) is
// kept for positions() (tests, the console), for ?morph=cpu, as the
// fallback when the viewer refuses the morph targets (GL limits; a console
// note says why), and by default on software GL (SwiftShader, llvmpipe:
// there the vertex shader's blend runs on the CPU and a draw measured 1.4-4
// times slower than the CPU blend's; see pickPath). The measured cost per
// frame, both paths, is in docs/design/page.md. The lower teeth and
// tongue ride on the jaw: the shapes' jaw motions blended as I + sum of
// w_i (M_i - I) (what the GLB's morph targets on the teeth do); the
// eyeballs turn with the gaze shapes (eyeLook*) the same way; the tongue
// out bends the tongue's own vertices (moveTongue), on the GPU path as
// the tongue component's morph targets.
import { app, page, ui, showError } from './state.js';
import { runJob } from './worker_client.js';
import { onHeadShown, showStage, view } from './head_view.js';
import { onAnimationStop, stopAnimation } from './animation.js';
import { pageSpeech, preferredLanguage } from './speech.js';

// Talk says the words typed beside it (read to visemes by TalkingHead's
// lip-sync, speech.js; the worker makes the clip: anim/clips.h
// speech_clip), or without words plays the core's Talk clip
// (core/anim/clips.h: "hello, nice to
// meet you", visemes cross-fading, two blinks) and, with it, its Gaze clip
// (the eyes to the left, the right and up; other shapes than Talk's),
// fetched with the shapes: the same keys the exported GLB's "Talk" and
// "Gaze" animations hold, one source for both. {shapes, times, values,
// slopes} (values and slopes key-major).
let talkClip = null, gazeClip = null;
// What Talk is playing: the demo (Talk with Gaze) or the typed words' clip
// (the worker's sayClip job, anim/clips.h speech_clip), alone.
let playing = { clip: null, gaze: null };

// A clip's weights at t seconds, added into w: glTF's cubic Hermite
// (CUBICSPLINE) between the clip's keys, as a glTF player computes the
// GLB's clip.
function clipWeights(c, t, w = {}) {
  if (!c) return w;
  const T = c.times, n = c.shapes.length, last = T.length - 1;
  const x = Math.min(Math.max(t, T[0]), T[last]);
  let k = 0;
  while (k + 1 < last && T[k + 1] <= x) k++;
  const h = T[k + 1] - T[k], u = (x - T[k]) / h, u2 = u * u, u3 = u2 * u;
  const h00 = 2 * u3 - 3 * u2 + 1, h10 = u3 - 2 * u2 + u, h01 = -2 * u3 + 3 * u2, h11 = u3 - u2;
  for (let s = 0; s < n; s++) {
    const i0 = k * n + s, i1 = (k + 1) * n + s;
    const v = h00 * c.values[i0] + h10 * h * c.slopes[i0] + h01 * c.values[i1] + h11 * h * c.slopes[i1];
    if (v > 0) w[c.shapes[s]] = (w[c.shapes[s]] || 0) + v;
  }
  return w;
}

// The weights at t seconds into Talk alone (what the GLB's Talk plays).
export function talkWeights(t) { return clipWeights(talkClip, t); }
// What Talk plays at t: the demo's Talk and Gaze together, or the words.
function demoWeights(t) { return clipWeights(playing.gaze, t, clipWeights(playing.clip, t)); }
const clipEnd = (c) => (c ? c.times[c.times.length - 1] : 0);
// Talk's keys where the lids are shut (blink 1): a frame that would step
// over one draws it instead, so a slow GPU (100-200 ms a frame on
// SwiftShader at level 3, against a 200 ms blink) still shows every blink.
function shutKeys(c) {
  const s = c ? c.shapes.indexOf('blink') : -1;
  return s < 0 ? [] : Array.from(c.times).filter((_, k) => c.values[k * c.shapes.length + s] >= 0.999);
}
const talkEnd = () => Math.max(clipEnd(playing.clip), clipEnd(playing.gaze));

const PRESETS = [...document.querySelectorAll('#expressions [data-preset]')].map((b) => b.dataset.preset);
function groupOf(name) {
  if (name.startsWith('viseme_')) return 'viseme';
  if (PRESETS.includes(name)) return 'expression';
  for (const g of ['eye', 'jaw', 'mouth', 'brow']) if (name.startsWith(g)) return g;
  return 'other';
}

// The baked shapes of the head shown: {fit, level, shapes: Map name ->
// {indices, offsets}, names, index (name -> shape number), rest (the
// level's rest positions), out (the last CPU blend), weightArray (the GPU's
// weights), gpuModel (the viewer's model_serial its morph targets are on),
// restPose (the viewer's model:pose serials when it last showed the rest)}.
let baked = null;
let baking = null;  // {fit, level, promise}
let talkT0 = 0, talkGeneration = 0;

const ex = app.expressions = {
  weights: {},          // shape name -> weight, only the non-zero ones
  level: null,          // the level of the baked shapes (null: none yet)
  names: [],
  bakeMs: null,         // the worker's bake of the last level fetched
  talking: false,
  saying: '',           // the words the last Talk said ('' : the demo phrase)
  sayNote: '',          // what the page said about them (cut at 400 letters, nothing to say)
  talkFrames: 0,
  talkPeaks: {},        // the last Talk's largest weight per shape drawn
  talkBlinkFrame: null, // the last Talk's frame drawn with the largest blink weight: {t, weights}
  lids: [],             // each eye's [upper, lower] lid vertex (middle rim column) of the baked level
  jawMatrix: null,      // the lower teeth's and tongue's last matrix (column-major 4x4, scan frame)
  eyeMatrices: null,    // the eyeballs' last matrices [left, right] (the same)
  // Per drawn pose: the JS blend and the viewer's update_positions (ms, sums over frames).
  stats: { frames: 0, blendMs: 0, uploadMs: 0, lastBlendMs: 0, lastUploadMs: 0 },
  // Where the blend runs: 'gpu' (morph targets in the vertex shader) or
  // 'cpu'; null until the first pose picks it (pickPath: ?morph=cpu|gpu,
  // else the GL's renderer). pathReason says why; gpuNote why the GPU path
  // was refused, if it was.
  path: null,
  pathReason: null,
  glRenderer: null,
  gpuNote: null,
  morphUploadMs: null,  // the last sending of the morph targets, first pose to uploaded (once per head and level)
  morphUpload: null,    // its parts (ms; see sendTargets), entries, textureBytes
  gpuPending: false,    // the morph targets are being sent (the CPU path draws meanwhile)
  // For the tests and the console: the blend computed on the CPU and the rest positions, a shape's data.
  positions: () => (baked ? blendCpu(baked).slice() : null),
  restPositions: () => (baked ? baked.rest.slice() : null),
  shape: (name) => (baked && baked.shapes.get(name)) || null,
  talkWeights: (t) => talkWeights(t),
  demoWeights: (t) => demoWeights(t),
  get talkSeconds() { return talkEnd(); },
  get talkKeys() { return playing.clip ? Array.from(playing.clip.times) : []; },  // the clip Talk plays: its key times (s)
  tonguePositions: null,  // the tongue component's last positions on the CPU path (scan frame, before the jaw's matrix)
  // The same computed on demand, whichever path draws (tests, the console).
  tongueBlend: () => {
    const c = app.componentsData, rest = c && c.tongue && c.tongue.positions;
    return baked && rest ? tongueBlend(baked, rest) || rest : null;
  },
  tongueStats: { path: null, frames: 0, ms: 0, lastMs: 0, uploads: 0 },  // uploads: the tongue's vertices sent (CPU path)
  tongueHeld: false,      // tests: the tongue left at rest, to see what its push changes on screen
  // Tests: set weights as the presets and sliders do; switch the path and redraw.
  set: (weights) => setWeights(weights),
  setPath: (path) => { ex.path = path; ex.pathReason = 'set by setPath'; return fresh(baked) && draw(); },
};

// GL drivers that draw on the CPU: Chromium's SwiftShader (headless, or no
// usable GPU driver), Mesa's llvmpipe and softpipe, Windows' basic driver.
const SOFTWARE_GL = /swiftshader|llvmpipe|softpipe|software|basic render driver/i;

// The GL's renderer string: the unmasked one (WEBGL_debug_renderer_info)
// where the browser gives it, else RENDERER. The viewer's context is the
// canvas' (getContext returns the existing one; called only once the
// viewer runs, so it never creates a context of its own).
function glRenderer() {
  const gl = document.getElementById('canvas').getContext('webgl2');
  if (!gl) return '';
  const info = gl.getExtension('WEBGL_debug_renderer_info');
  return String((info && gl.getParameter(info.UNMASKED_RENDERER_WEBGL)) || gl.getParameter(gl.RENDERER) || '');
}

// Picks the blend once, at the first pose: ?morph=cpu or ?morph=gpu forces
// one (tests, comparisons); otherwise software GL blends on the CPU, where
// the vertex shader's blend is itself CPU work and measured slower than
// the JavaScript blend (flow expressions prints both at levels 2 and 3),
// and any other GL on the GPU (a real GPU's blend is a few texel fetches
// per vertex: assumed faster, not measured here, there is no GPU on the
// test machine). A console note says which and why.
function pickPath() {
  if (ex.path) return;
  const forced = new URLSearchParams(location.search).get('morph');
  if (forced === 'cpu' || forced === 'gpu') {
    ex.path = forced;
    ex.pathReason = '?morph=' + forced;
  } else {
    let r = '';
    try { r = glRenderer(); } catch (e) { r = ''; }
    ex.glRenderer = r;
    const soft = SOFTWARE_GL.test(r);
    ex.path = soft ? 'cpu' : 'gpu';
    ex.pathReason = soft ? 'software GL (' + r + '): its vertex shader runs on the CPU, the JavaScript blend draws faster'
      : 'a hardware GL (' + (r || 'renderer not given') + ')';
  }
  console.info('Expressions: blending on the ' + ex.path.toUpperCase() + ', ' + ex.pathReason + ' (?morph=cpu or ?morph=gpu forces one).');
}

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
    const shapes = new Map(r.shapes.map((s) => [s.name, { indices: s.indices, offsets: s.offsets, jaw: s.jawMatrix || null,
                                                          eyes: s.eyeMatrices || null, tongue: s.tongueOffsets || null }]));
    talkClip = (r.clips || []).find((c) => c.name === 'Talk') || null;
    gazeClip = (r.clips || []).find((c) => c.name === 'Gaze') || null;
    if (!ex.talking) playing = { clip: talkClip, gaze: gazeClip };
    const rest = new Float32Array(mesh.positions);
    const names = r.shapes.map((s) => s.name);
    baked = { fit, level, shapes, names, index: new Map(names.map((n, i) => [n, i])), rest, out: rest.slice(),
              weightArray: new Float32Array(names.length), gpuModel: -1, restPose: '' };
    Object.assign(ex, { level, names: baked.names, bakeMs: r.bakeMs, lids: r.lids || [] });
    ui.exprStats.textContent = baked.names.length + ' shapes baked on ' + (level === 0 ? 'the control mesh' : 'level ' + level) +
      ' (' + mesh.vertexCount.toLocaleString('en') + ' vertices) in ' + Math.round(r.bakeMs) + ' ms.';
    buildSliders();
    return fresh(baked) ? baked : null;
  }, () => { if (baking && baking.promise === promise) baking = null; return null; });
  baking = { fit, level, promise };
  return promise;
}

// rest + sum w_i offsets_i into b.out (the CPU blend).
function blendCpu(b) {
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
  return out;
}

const poseKey = (v) => v.model_serial() + ':' + v.pose_serial();

// The GPU path made ready on the model shown: the morph targets sent
// (once per model: another level or head view replaces the model; spread
// over frames, false meanwhile), then the rest positions on it (anything
// else that moved it, the CPU path or Animate, is undone once). False (and
// the CPU path from then on) when refused.
function gpuReady(b) {
  const v = app.viewer;
  if (!(b.gpuModel === v.model_serial() && v.morph_target_count() === b.names.length) && !sendTargets(b)) return false;
  if (b.restPose !== poseKey(v)) {
    const err = v.update_positions(b.rest);
    if (err) return gpuRefused(err);
    b.restPose = poseKey(v);
  }
  return true;
}

// Per frame, at most about this long preparing the morph targets.
const MORPH_SLICE_MS = 12;

// The morph targets onto the model shown, a slice per frame (the viewer's
// begin_morph_targets / continue_morph_targets; sent at once they stalled
// the page 0.5-2.9 s at level 3: the viewer's prepare of the normal
// offsets and texels, and the GL upload): true once uploaded. Meanwhile the CPU path draws
// the pose and the next frame goes on.
function sendTargets(b) {
  const v = app.viewer;
  let job = b.job;
  const now = () => performance.now();
  if (!job || job.model !== v.model_serial()) {
    // The viewer takes the mesh as it is at begin as the rest: put the rest on first.
    if (b.restPose !== poseKey(v)) {
      const err = v.update_positions(b.rest);
      if (err) return gpuRefused(err);
      b.restPose = poseKey(v);
    }
    const t0 = now();
    if (!b.flat) {
      let total = 0;
      for (const n of b.names) total += b.shapes.get(n).indices.length;
      const counts = new Uint32Array(b.names.length), indices = new Uint32Array(total), offsets = new Float32Array(3 * total);
      let at = 0;
      b.names.forEach((n, i) => {
        const s = b.shapes.get(n);
        counts[i] = s.indices.length;
        indices.set(s.indices, at);
        offsets.set(s.offsets, 3 * at);
        at += s.indices.length;
      });
      b.flat = { counts, indices, offsets };
    }
    const t1 = now();
    const err = v.begin_morph_targets(b.flat.counts, b.flat.indices, b.flat.offsets);
    const t2 = now();
    if (err) return gpuRefused(err);
    job = b.job = { model: v.model_serial(), t0, packMs: t1 - t0, calls: 1, busyMs: t2 - t0, longestMs: t2 - t0 };
    ex.gpuPending = true;
  } else {
    const t0 = now();
    const r = v.continue_morph_targets(MORPH_SLICE_MS);
    const dt = now() - t0;
    job.calls++;
    job.busyMs += dt;
    // The last call (the GL error check, which waits for the GPU process) apart.
    if (r.done) job.lastMs = dt; else job.longestMs = Math.max(job.longestMs, dt);
    if (r.error) {
      b.job = null;
      ex.gpuPending = false;
      return gpuRefused(r.error);
    }
    if (r.done) {
      b.job = null;
      ex.gpuPending = false;
      b.gpuModel = v.model_serial();
      ex.morphUploadMs = now() - job.t0;
      // Where it went (docs/design/page.md, "No stall on upload"): the
      // page's packing, the viewer's copy, split, prepare (normal offsets),
      // packing into texels and GL upload; the calls and the longest one.
      ex.morphUpload = { pagePackMs: job.packMs, wallMs: ex.morphUploadMs, busyMs: job.busyMs, calls: job.calls,
                         longestCallMs: job.longestMs, lastCallMs: job.lastMs, ...(v.last_morph_upload ? v.last_morph_upload() : {}) };
      return true;
    }
  }
  requestAnimationFrame(() => { if (baked === b && b.job === job && ex.path === 'gpu') draw(); });
  return false;
}

function gpuRefused(err) {
  ex.path = 'cpu';
  ex.gpuNote = err;
  console.info('Expressions: blending on the CPU, the viewer refused the morph targets: ' + err);
  return false;
}

// The weights onto the screen when the viewer shows this level's mesh:
// on the GPU (the weights only) or on the CPU (the blend, uploaded).
// Returns false when it could not be drawn.
function draw() {
  const b = baked;
  if (!fresh(b) || app.shownStage !== 'subdivide' || view.level !== b.level) return false;
  const v = app.viewer;
  pickPath();
  const t0 = performance.now();
  let t1, err;
  // The wireframe's edges are drawn from the uploaded positions, not blended
  // in the shader: with the wireframe on, the CPU path keeps them on the face.
  const gpuDrawn = ex.path === 'gpu' && !ui.wireframe.checked && gpuReady(b);
  if (gpuDrawn) {
    const w = b.weightArray;
    w.fill(0);
    for (const [name, x] of Object.entries(ex.weights)) {
      const i = b.index.get(name);
      if (i !== undefined) w[i] = x;
    }
    t1 = performance.now();
    err = v.set_morph_weights(w);
  } else {
    if (b.gpuModel === v.model_serial()) v.set_morph_weights(new Float32Array(0));  // no GPU pose under the CPU's
    blendCpu(b);
    t1 = performance.now();
    err = v.update_positions(b.out);
  }
  const t2 = performance.now();
  if (err) { stopTalk(); showError('Expressions: ' + err); return false; }
  moveJaw(b, gpuDrawn);
  const st = ex.stats;
  st.frames++;
  st.lastBlendMs = t1 - t0;
  st.lastUploadMs = t2 - t1;
  st.blendMs += st.lastBlendMs;
  st.uploadMs += st.lastUploadMs;
  st.path = gpuDrawn ? 'gpu' : 'cpu';
  return true;
}

// The lower teeth and tongue (app.jawComponents) on the blended jaw
// motion, the eyeballs (app.eyeComponents) on the blended gaze: each
// I + sum of w_i (M_i - I) over the shapes that have one.
const IDENTITY = new Float32Array([1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]);
function blendMatrices(b, pick) {
  const m = IDENTITY.slice();
  for (const [name, w] of Object.entries(ex.weights)) {
    const s = w && b.shapes.get(name), x = s && pick(s);
    if (x) for (let i = 0; i < 16; i++) m[i] += w * (x[i] - IDENTITY[i]);
  }
  return m;
}
function moveJaw(b, gpu) {
  const m = blendMatrices(b, (s) => s.jaw);
  ex.jawMatrix = m;
  for (const i of app.jawComponents || []) app.viewer.set_component_matrix(i, m);
  ex.eyeMatrices = [0, 1].map((e) => blendMatrices(b, (s) => s.eyes && s.eyes[e]));
  (app.eyeComponents || []).forEach((i, e) => { if (i !== null && e < 2) app.viewer.set_component_matrix(i, ex.eyeMatrices[e]); });
  moveTongue(b, gpu);
}

// The tongue out (tongueOut, viseme_TH) bends it, which no matrix carries:
// the worker's tongueOffsets per shape, in the tongue's own frame before
// the jaw's motion (the jaw's matrix then carries them, as the core's
// pose_tongue does). On the GPU path they are the tongue component's own
// morph targets (sent once per head and components), and a frame sends
// its weights only, as for the face; on the CPU path the component's
// vertices are rest + sum of w_i * push_i, sent while pushed and once more
// to put it back. ex.tongueStats: the page's time per frame on the tongue.
let tonguePushed = false;

function tongueNames(b, rest) {
  if (!b.tongueNames) b.tongueNames = b.names.filter((n) => { const t = b.shapes.get(n).tongue; return !!t && t.length === rest.length; });
  return b.tongueNames;
}

// The tongue's morph targets on its component: true once there (sent
// again when the components were made again); false, and the CPU path for
// the tongue from then on, when the viewer refuses them.
function tongueGpuReady(b, i, rest) {
  const v = app.viewer, names = tongueNames(b, rest), g = b.tongueGpu;
  if (!names.length || (g && g.failed) || !v.set_component_morph_targets) return false;
  // The CPU path's push undone: the targets (and their normals) are made from the rest.
  if (tonguePushed) { v.set_component_positions(i, rest); tonguePushed = false; }
  if (g && g.component === i && g.rest === rest && v.component_morph_target_count(i) === names.length) return true;
  const counts = new Uint32Array(names.length), idx = [], off = [];
  names.forEach((n, k) => {
    const push = b.shapes.get(n).tongue;
    for (let j = 0; j < push.length; j += 3) {
      if (push[j] === 0 && push[j + 1] === 0 && push[j + 2] === 0) continue;
      idx.push(j / 3);
      off.push(push[j], push[j + 1], push[j + 2]);
      counts[k]++;
    }
  });
  const err = v.set_component_morph_targets(i, counts, new Uint32Array(idx), new Float32Array(off));
  if (err) {
    b.tongueGpu = { failed: true };
    console.info('Expressions: the tongue blends on the CPU, the viewer refused its morph targets: ' + err);
    return false;
  }
  b.tongueGpu = { component: i, rest, names, weights: new Float32Array(names.length) };
  return true;
}

function moveTongue(b, gpu) {
  const i = app.tongueComponent, c = app.componentsData, rest = c && c.tongue && c.tongue.positions;
  if (i === null || i === undefined || !rest) return;
  const t0 = performance.now();
  const v = app.viewer, g = b.tongueGpu;
  const onGpu = gpu && !ex.tongueHeld && tongueGpuReady(b, i, rest);
  if (onGpu) {
    const w = b.tongueGpu.weights;
    b.tongueGpu.names.forEach((n, k) => { w[k] = ex.weights[n] || 0; });
    const err = v.set_component_morph_weights(i, w);
    if (err) { console.warn('the tongue not moved: ' + err); return; }
    ex.tonguePositions = null;  // on the GPU: ex.tongueBlend() computes them for the tests
  } else {
    // Off the GPU path: no GPU push left under the CPU's.
    if (g && g.component === i && !g.failed && v.component_morph_target_count(i) > 0) v.set_component_morph_weights(i, new Float32Array(0));
    const out = ex.tongueHeld ? null : tongueBlend(b, rest);
    if (out || tonguePushed) {
      const err = v.set_component_positions(i, out || rest);
      if (err) { console.warn('the tongue not moved: ' + err); return; }
      tonguePushed = !!out;
      ex.tongueStats.uploads++;
    }
    ex.tonguePositions = out || rest;
  }
  const st = ex.tongueStats, dt = performance.now() - t0;
  st.path = onGpu ? 'gpu' : 'cpu';
  st.frames++;
  st.ms += dt;
  st.lastMs = dt;
}

// rest + sum of w_i * push_i over the weighted tongue shapes; null when none pushes.
function tongueBlend(b, rest) {
  let out = null;
  for (const [name, w] of Object.entries(ex.weights)) {
    const s = w && b.shapes.get(name), push = s && s.tongue;
    if (!push || push.length !== rest.length) continue;
    if (!out) out = Float32Array.from(rest);
    for (let k = 0; k < push.length; k++) out[k] += w * push[k];
  }
  return out;
}

// What a frame cost on the page's side (the drawing itself is the GPU's).
function costText(blendMs, uploadMs) {
  return ex.stats.path === 'gpu'
    ? 'weights ' + (blendMs + uploadMs).toFixed(2) + ' ms (blended on the GPU).'
    : 'blend ' + blendMs.toFixed(1) + ' ms + viewer update ' + uploadMs.toFixed(1) + ' ms (JavaScript, on the CPU).';
}

function statsText() {
  const st = ex.stats, n = Object.keys(ex.weights).length;
  return n + (n === 1 ? ' shape' : ' shapes') + ' on level ' + baked.level + ': ' + costText(st.lastBlendMs, st.lastUploadMs);
}

// An outside driver of the weights (Follow my face): its stop function,
// called when the user or the page takes the head over (a preset, a slider,
// Talk, Animate, another head or job).
let driver = null;
export function setDriver(stop) { driver = stop; }
function stopDriver() {
  const d = driver;
  driver = null;
  if (d) d();
}

// The driver's weights onto the head (the shapes baked first if need be);
// nothing while Animate moves the head.
export async function driveWeights(weights) {
  if (!app.fit || app.animation.running) return;
  if (ex.talking) stopTalk(false);
  if (app.shownStage !== 'subdivide') showStage('subdivide');
  ex.weights = weights;
  syncSliders();
  const b = await ensureShapes();
  if (b && ex.weights === weights && draw()) ui.exprStats.textContent = statsText();
}

// New weights onto the head: Animate stops (both would write the head), the
// subdivided head is shown, the shapes fetched if needed.
async function setWeights(weights, { fromTalk = false } = {}) {
  if (!app.fit) return;
  if (!fromTalk) stopTalk(false);
  stopDriver();
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
  // The typed words, read to visemes by the core; none: the demo phrase.
  const words = ui.sayText.value.trim();
  playing = { clip: talkClip, gaze: gazeClip };
  ex.saying = words;
  ex.sayNote = '';
  if (words) {
    const speech = await pageSpeech(words, ui.sayLang.value);
    const r = speech.error ? { ok: false, message: speech.error }
      : !speech.visemes.length ? { ok: false, message: 'there is nothing to say in those words' }
      : await runJob({ type: 'sayClip', speech: JSON.stringify(speech) }, []);
    if (ex.talking) return;  // pressed twice while the words were read
    if (!r.ok) {
      ex.sayNote = 'Talk: ' + r.message + '.';
      ui.exprStats.textContent = ex.sayNote;
      return;
    }
    playing = { clip: r.clip, gaze: null };
    if (speech.truncated) ex.sayNote = `Only the first ${speech.text.length} characters are said.`;
  }
  const generation = ++talkGeneration;
  ex.talking = true;
  ex.talkFrames = 0;
  ex.talkPeaks = {};
  ex.talkBlinkFrame = null;
  ex.stats = { frames: 0, blendMs: 0, uploadMs: 0, lastBlendMs: 0, lastUploadMs: 0 };
  ui.talk.textContent = 'Stop talking';
  ui.talk.setAttribute('aria-pressed', 'true');
  talkT0 = performance.now();
  let drawnAtUpload = -1, lastT = -1;
  const shut0 = shutKeys(playing.clip);
  const frame = () => {
    if (!ex.talking || generation !== talkGeneration) return;
    // A pose only after the last one was drawn (a slow GPU: no blend thrown away).
    if (app.viewer.frames_drawn() === drawnAtUpload) { requestAnimationFrame(frame); return; }
    const now = (performance.now() - talkT0) / 1000;
    if (now >= talkEnd()) { stopTalk(); return; }
    const shut = shut0.find((k) => k > lastT && k <= now);
    const t = shut !== undefined ? shut : now;
    lastT = t;
    ex.weights = demoWeights(t);
    if (!draw()) { stopTalk(); return; }
    drawnAtUpload = app.viewer.frames_drawn();
    ex.talkFrames++;
    for (const [name, w] of Object.entries(ex.weights)) ex.talkPeaks[name] = Math.max(ex.talkPeaks[name] || 0, w);
    // The frame drawn with the lids most closed (the tests pose it again).
    if ((ex.weights.blink || 0) > ((ex.talkBlinkFrame && ex.talkBlinkFrame.weights.blink) || 0)) ex.talkBlinkFrame = { t, weights: { ...ex.weights } };
    const st = ex.stats;
    ui.exprStats.textContent = (ex.sayNote ? ex.sayNote + ' ' : '') + 'Talking: ' + ex.talkFrames + ' frames, per frame on level ' + baked.level + ': ' +
      costText(st.blendMs / st.frames, st.uploadMs / st.frames);
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
  stopDriver();
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
  // The words are read in the browser's language where TalkingHead reads it.
  ui.sayLang.value = preferredLanguage(navigator.languages);
  // Enter in the words' box says them.
  ui.sayText.addEventListener('keydown', (e) => {
    if (e.key !== 'Enter') return;
    e.preventDefault();
    if (ex.talking) stopTalk();
    startTalk().catch(() => {});
  });
  ui.exprGroup.addEventListener('change', buildSliders);
  ui.wireframe.addEventListener('change', () => { if (Object.keys(ex.weights).length) draw(); });
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
