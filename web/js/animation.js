// Animation (jeong2002 Sec. 6: local update of the multires head), with
// adaptive detail while the head moves on a slow (software) GPU.
import { app, params, ui, showError } from './state.js';
import { runJob } from './worker_client.js';
import { fitMesh, showStage, view } from './head_view.js';

// The worker owns the MultiresMesh; each frame asks it for one pose and
// uploads the returned level positions into the shown mesh.
// Frames are double-buffered: the next pose is requested as soon as one is
// handed to the viewer, so the worker computes frame n+1 while frame n is
// uploaded and drawn. At most one job is in flight, and a pose is uploaded
// only after the previous one was drawn, so no work is thrown away (on two
// cores a worker running ahead would steal the CPU the drawing needs).
//
// Adaptive detail while moving: without a GPU (SwiftShader, llvmpipe, VMs)
// a level-3 frame costs 140-250 ms, so while the head moves the page steps
// down along a ladder of cheaper renderings (subdivision level and
// drawing-buffer scale, in the order measured in docs/journal.md "Adaptive
// detail while animating") whenever the frames of a short window are
// slower than the budget, and back up when there is headroom.
// Only what is drawn while moving changes: the Level select, export and
// texturing always use the chosen level, and stopping shows the chosen
// level at full resolution again. "Full detail while animating" turns it off.
const ADAPT_BUDGET_MS = Number(params.get('anim_budget_ms')) > 0 ? Number(params.get('anim_budget_ms')) : 1000 / 15;
const ADAPT_WINDOW = 4;          // frames averaged before a decision (2-4 fps: about a second)
const ADAPT_UP_FRACTION = 0.55;  // step up only below this share of the budget...
const ADAPT_MEMORY_MS = 15000;   // ...and not onto a step measured too slow within this time
// The ladder for a chosen level: each step is what is drawn while moving.
// Measured on SwiftShader (docs/journal.md): level 3 -> 2 nearly triples the
// frame rate for the smallest visible change (0.3 % of pixels), while a
// lower scale on level 3 gains little (its triangles, not its pixels, cost);
// so the level drops to 2 first (what the paper animated), then the scale,
// then the level again.
function adaptLadder(chosen) {
  const moving = Math.min(chosen, 2);
  const steps = [{ level: chosen, scale: 1 }];
  if (moving < chosen) steps.push({ level: moving, scale: 1 });
  steps.push({ level: moving, scale: 0.75 }, { level: moving, scale: 0.5 });
  for (let l = moving - 1; l >= Math.min(1, moving); --l) steps.push({ level: l, scale: 0.5 });
  return steps;
}
app.animation.adaptive = { enabled: true, budgetMs: ADAPT_BUDGET_MS, step: 0, level: null, scale: 1,
                           frameMs: 0, changes: 0, ladder: [] };
// Last settled step per chosen level, so the next start begins there.
const adaptStartStep = {};
let adaptIntervals = [], adaptLastPoseT = 0, adaptSlow = {};

// The level drawn now: the chosen one, or the adaptation's while moving.
export function shownLevel() {
  const a = app.animation;
  return a.running && a.adaptive.level !== null ? a.adaptive.level : Number(ui.level.value);
}

// Puts step `step` of the ladder on screen: the scale at once; a new level
// with its first pose (applyPose swaps the mesh, so the head never jumps
// back to the rest pose), dropping a pose of the old level in flight.
function applyAdaptStep(step) {
  const ad = app.animation.adaptive;
  const s = ad.ladder[step];
  if (!s) return;
  const levelChanged = s.level !== shownLevel();
  ad.step = step;
  ad.scale = s.scale;
  app.viewer.set_render_scale(s.scale);
  ad.level = s.level;
  adaptIntervals = [];
  adaptLastPoseT = 0;
  if (levelChanged) {
    animGeneration++;               // an in-flight pose of the old level is dropped
    requestPose();
  }
}

// Back to the chosen level at full resolution (nothing temporary left).
function restoreFullDetail() {
  const ad = app.animation.adaptive;
  const wasLevel = ad.level;
  ad.level = null;
  ad.step = 0;
  ad.scale = 1;
  ad.frameMs = 0;
  adaptIntervals = [];
  adaptLastPoseT = 0;
  if (app.viewer) app.viewer.set_render_scale(1);
  return (wasLevel !== null && wasLevel !== Number(ui.level.value)) || view.level !== Number(ui.level.value);
}

// Called once per pose put on screen: measures the frame time over a short
// window and steps down (too slow) or up (headroom).
function adaptAfterFrame(now) {
  const a = app.animation, ad = a.adaptive;
  if (adaptLastPoseT > 0) adaptIntervals.push(now - adaptLastPoseT);
  adaptLastPoseT = now;
  if (!ad.enabled || adaptIntervals.length < ADAPT_WINDOW) return;
  const ms = adaptIntervals.reduce((s, x) => s + x, 0) / adaptIntervals.length;
  adaptIntervals.shift();
  ad.frameMs = ms;
  if (ms > ad.budgetMs && ad.step + 1 < ad.ladder.length) {
    adaptSlow[ad.step] = { ms, t: now };
    ad.changes++;
    applyAdaptStep(ad.step + 1);
  } else if (ms < ADAPT_UP_FRACTION * ad.budgetMs && ad.step > 0) {
    const slow = adaptSlow[ad.step - 1];
    if (slow && now - slow.t < ADAPT_MEMORY_MS) return;
    ad.changes++;
    applyAdaptStep(ad.step - 1);
  }
  adaptStartStep[Number(ui.level.value)] = ad.step;
}

export function setAdaptive(on) {
  const a = app.animation, ad = a.adaptive;
  ad.enabled = on;
  for (const k of Object.keys(adaptStartStep)) delete adaptStartStep[k];  // start over from full detail
  if (!a.running) return;
  if (!on && ad.step !== 0) applyAdaptStep(0);
  adaptIntervals = [];
  adaptLastPoseT = 0;
}

function animStatsText(a, r) {
  const ad = a.adaptive;
  const parts = [(a.fps < 10 ? a.fps.toFixed(1) : a.fps.toFixed(0)) + ' fps'];
  if (!ad.enabled) parts.push('full detail');
  else if (ad.step > 0) {
    const chosen = Number(ui.level.value);
    if (ad.level !== chosen) parts.push((ad.level === 0 ? 'control mesh' : 'level ' + ad.level) + ' while moving');
    if (ad.scale !== 1) parts.push(Math.round(ad.scale * 100) + ' % resolution');
  }
  parts.push('update ' + a.updateMs.toFixed(1) + ' ms');
  parts.push(r.changed.toLocaleString('en') + ' of ' + r.vertexCount.toLocaleString('en') + ' vertices');
  return parts.join(' · ');
}

let animT0 = 0, animFpsT = 0, animFpsFrames = 0, animGeneration = 0, animDrawnAtUpload = -1;
function requestPose() {
  const a = app.animation;
  if (!a.running || !app.fit) return;
  const generation = animGeneration;
  const t = (performance.now() - animT0) / 1000;
  const amount = 0.5 - 0.5 * Math.cos(t * Math.PI);  // open and close every 2 s
  const tJob = performance.now();
  const level = shownLevel();
  runJob({ type: 'animate', amount, level }, []).then((r) => {
    if (!a.running || generation !== animGeneration) return;
    if (!r.ok) { stopAnimation(); showError('Animation: ' + r.message); return; }
    a.profile.jobMs += performance.now() - tJob;
    applyPose(r, generation, level);
  }, () => stopAnimation());
}

function applyPose(r, generation, level) {
  const a = app.animation;
  if (!a.running || generation !== animGeneration) return;
  const viewer = app.viewer;
  if (viewer.frames_drawn() === animDrawnAtUpload) {  // the last pose is not on screen yet
    requestAnimationFrame(() => applyPose(r, generation, level));
    return;
  }
  const tUpload = performance.now();
  if (level !== view.level) {  // the adaptation's new level: its mesh, in this pose
    showStage('subdivide', true, r.positions);
    if (view.level !== level) { stopAnimation(); return; }  // showStage said why
  } else {
    const err = viewer.update_positions(r.positions);
    if (err) { stopAnimation(); showError('Animation: ' + err); return; }
  }
  moveJaw(r.jawMatrix);
  animDrawnAtUpload = viewer.frames_drawn();
  const p = a.profile;
  p.frames++;
  p.workerMs += r.workerMs || 0;
  p.coreMs += r.updateMs;
  p.uploadMs += performance.now() - tUpload;
  p.drawMs += viewer.last_draw_ms();
  requestPose();
  a.frames++;
  animFpsFrames++;
  a.updateMs = r.updateMs;
  const now = performance.now();
  if (now - animFpsT > 500 || a.fps === 0) {
    a.fps = animFpsFrames * 1000 / (now - animFpsT);
    animFpsT = now;
    animFpsFrames = 0;
  }
  adaptAfterFrame(now);
  ui.animStats.textContent = animStatsText(a, r);
}

export function startAnimation() {
  if (!app.fit || app.animation.running) return;
  if (app.shownStage !== 'subdivide') showStage('subdivide');
  const a = app.animation;
  Object.assign(a, { running: true, frames: 0, fps: 0,
    profile: { frames: 0, jobMs: 0, workerMs: 0, coreMs: 0, uploadMs: 0, drawMs: 0 } });
  animT0 = animFpsT = performance.now();
  animFpsFrames = 0;
  animGeneration++;
  animDrawnAtUpload = -1;
  ui.animate.checked = true;
  const ad = a.adaptive;
  const chosen = Number(ui.level.value);
  ad.ladder = adaptLadder(chosen);
  ad.level = chosen;
  ad.step = 0;
  ad.changes = 0;
  adaptSlow = {};
  // Begin where the last run at this level settled (no second slideshow).
  const start = ad.enabled ? Math.min(adaptStartStep[chosen] || 0, ad.ladder.length - 1) : 0;
  if (start > 0) applyAdaptStep(start);  // re-shows the mesh and requests the first pose
  else requestPose();
}

function moveJaw(matrix) {
  if (!matrix || !app.jawComponents) return;
  for (const i of app.jawComponents) app.viewer.set_component_matrix(i, matrix);
}

// f() on every stopAnimation, running or not: it is called wherever another
// job starts or the head changes (expressions.js stops Talk then).
const stopListeners = [];
export function onAnimationStop(f) { stopListeners.push(f); }

// Stops and (restPose) puts the head back at rest, the pose export writes,
// at the chosen level and full resolution. reshow=false when the caller
// shows another mesh right after.
export function stopAnimation(restPose = true, reshow = true) {
  const a = app.animation;
  for (const f of stopListeners) f();
  ui.animate.checked = false;
  if (!a.running) return;
  a.running = false;
  animGeneration++;  // a pose still in flight is dropped
  const levelWasTemporary = restoreFullDetail();
  if (levelWasTemporary && reshow && app.fit && app.shownStage === 'subdivide') showStage('subdivide');
  if (!app.fit || !restPose) return;
  const level = Number(ui.level.value);
  runJob({ type: 'animate', amount: 0, level }, []).then((r) => {
    if (r.ok && app.shownStage === 'subdivide' && !app.animation.running && view.level === level &&
        r.vertexCount === fitMesh('subdivide').vertexCount) {
      app.viewer.update_positions(r.positions);
      moveJaw(r.jawMatrix);
    }
  }, () => {});
}

// Another level, or the distance map on or off: the head shown again, an
// animation restarted around it.
export function reshowHead() {
  const wasRunning = app.animation.running;
  if (wasRunning) { app.animation.running = false; animGeneration++; restoreFullDetail(); ui.animate.checked = false; }
  showStage('subdivide');
  if (wasRunning) startAnimation();
}

export function wireAnimation() {
  // ?full_detail=1 starts with the animation's adaptive detail off.
  if (params.get('full_detail') === '1') { ui.fullDetail.checked = true; setAdaptive(false); }
  ui.animate.addEventListener('change', () => (ui.animate.checked ? startAnimation() : stopAnimation()));
  ui.fullDetail.addEventListener('change', () => setAdaptive(!ui.fullDetail.checked));
}
