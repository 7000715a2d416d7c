// Fitting the generic head to the loaded scan (jeong2002 Sec. 4-5) in the
// worker: the Pipeline rows follow its stages, then the fitted head is shown
// over the scan, its checks start, and photos with points are textured when
// Auto-run is on.
import { app, ui, beginJob, endJob, live, refreshControls, setStage, setStatus, showError, stageItem } from './state.js';
import { runJob } from './worker_client.js';
import { stopAnimation } from './animation.js';
import { closeClicker } from './clicker.js';
import { renderPhotos, texturable } from './photos.js';
import { forgetTexture, runTexture } from './texture.js';
import { showComponents, showStage } from './head_view.js';
import { checkFitQuality } from './checks.js';
import { forPage } from './wording.js';
import { pageOption } from './project_inputs.js';
import { axisVector, defaultFacing, parallel, showAxes, snapAxis } from './axes.js';

// Core stage names -> the Pipeline rows, and the mesh each row shows.
export const FIT_STAGES = [
  { core: 'initial_alignment', row: 'align', mesh: 'aligned' },
  { core: 'local_fitting', row: 'local_fit', mesh: 'local' },
  { core: 'global_fitting', row: 'global_fit', mesh: 'control' },
  { core: 'subdivision', row: 'subdivide', mesh: 'level' },
];
const rowOf = (core) => (FIT_STAGES.find((s) => s.core === core) || {}).row;

// A head from photos runs other stages than a scan's fit: its rows say what
// ran (photos_head.js); a scan's fit or a project gets the scan rows back.
const PHOTO_ROWS = {
  load: ['Face points', 'MediaPipe Face Mesh in the page: 468 points per photo, from the page\'s own origin'],
  align: ['Self-calibration', 'fua1998 with uncalibrated photos: one shared focal and a pose per photo, bundle-adjusted ' +
                              'with the landmarks\' 3-D positions (core/photos/self_calibration.h)'],
  local_fit: ['Shape fit', 'fua1998 Sec. 2-3.3: the control mesh deformed so that its landmarks project onto the photos ' +
                           '(least squares, Levenberg-Marquardt; core/photos/shape_fit.h)'],
};
export function nameRows(photos) {
  for (const [row, [name, title]] of Object.entries(PHOTO_ROWS)) {
    const li = stageItem(row);
    const el = li.querySelector('.stage-name');
    if (li.dataset.scanName === undefined) { li.dataset.scanName = el.textContent; li.dataset.scanTitle = li.title || ''; }
    el.textContent = photos ? name : li.dataset.scanName;
    li.title = photos ? title : li.dataset.scanTitle;
  }
}

function stageStats(row) { return stageItem(row).querySelector('.stage-stats'); }

// The fit died with its worker, or a new scan came: rows keep their numbers
// until the next fit, but nothing can be animated or exported.
export function forgetFit(why) {
  stopAnimation(false);
  closeClicker();
  app.fit = null;
  ui.distanceLegend.hidden = true;
  forgetTexture();
  if (app.viewer) app.viewer.clear_components();
  ui.fitView.hidden = true;
  ui.fitQuality.hidden = true;
  for (const st of FIT_STAGES) {
    stageItem(st.row).classList.remove('viewable', 'shown');
    stageItem(st.row).querySelector('.stage-name').disabled = true;
  }
  if (why) setStatus(why);
  refreshControls();
}

export async function runFit() {
  const state = document.body.dataset.state;
  if (!app.scan || state === 'working' || state === 'loading' || app.startupFailed) return;
  // A head opened from a project (or restored) keeps its scan's points in
  // the worker, not the file: those are fitted again.
  const file = app.scan.file;
  if (!file && !app.scan.kept) {
    showError('This head keeps no scan to fit again (it was made from photos): drop a scan to fit one.');
    return;
  }
  stopAnimation();
  const name = file ? file.name : app.scan.name;
  const job = beginJob('fit');
  if (!job) return;
  nameRows(false);
  for (const st of FIT_STAGES) {
    setStage(st.row, 'waiting', 0);
    stageStats(st.row).textContent = '';
  }
  ui.fitTotal.textContent = '';
  ui.fitQuality.hidden = true;
  setStatus('Fitting the generic head to ' + name + (file ? '' : ' (the scan kept with the head)') + '…');
  const t0 = performance.now();
  let result;
  try {
    // The worker reads the File in slices (worker.js, streamScan).
    // ?thin=X fits a dense cloud on cell averages (FitHeadOptions::thin_cells_per_edge,
    // off by default: not lossless, docs/design/page.md).
    const thin = pageOption('thin') > 0 ? { thinCells: pageOption('thin') } : {};  // ?thin, else a restored project's
    const axes = { up: axisVector(ui.scanUp.value), facing: axisVector(ui.scanFacing.value) };
    const request = file ? { type: 'fitFile', file, options: { levels: 3, ...thin, ...axes } }
                         : { type: 'refit', options: { levels: 3, name, ...axes } };
    result = await runJob(request, [],
      (stage, fraction) => {
        if (stage === 'read') {
          const mb = (n) => (n / 1048576).toFixed(0) + ' MB';
          setStatus('Reading ' + name + ' for the fit: ' + mb(fraction * file.size) + ' of ' + mb(file.size) + '…');
          return;
        }
        const row = rowOf(stage);
        if (!row) return;
        // Earlier rows are complete once a later stage starts.
        for (const st of FIT_STAGES) {
          if (st.row === row) break;
          const li = stageItem(st.row);
          if (!li.classList.contains('complete')) setStage(st.row, 'done', 1, 'complete');
        }
        setStage(row, fraction >= 1 ? 'measuring' : Math.round(fraction * 100) + '%', fraction, 'active');
      });
  } catch (e) {
    if (e && e.cancelled) {
      for (const st of FIT_STAGES) setStage(st.row, 'cancelled', 0);
      setStatus('Fit cancelled. ' + (app.model ? app.model.name + ' is still shown.' : ''));
      endJob(job);
      return;
    }
    result = { ok: false, code: 'Internal', message: name + ': ' + (e && e.message ? e.message : e) };
  }
  const wallMs = performance.now() - t0;
  if (!live(job)) return;
  if (!result.ok) {
    const failedRow = FIT_STAGES.find((st) => stageItem(st.row).classList.contains('active'));
    for (const st of FIT_STAGES) {
      if (!stageItem(st.row).classList.contains('complete')) setStage(st.row, st === failedRow ? 'failed' : 'waiting', 0, st === failedRow ? 'failed' : undefined);
    }
    let message = forPage(result.message || result.code);
    if (result.code === 'not a head' || result.code === 'NotAHead') message = 'This does not look like a head scan, so no head was fitted: ' + message;
    setStatus('The fit failed.' + (app.model ? ' ' + app.model.name + ' is still shown.' : ''));
    showError(message);
    return;
  }
  app.project = null;
  showHead(result, name, wallMs);
  setStatus(name + ': head fitted in ' + (result.fitMs / 1000).toFixed(2) + ' s. Click a stage to see its mesh; ' +
            'pick a level, animate or export.');
  endJob(job);
  renderPhotos();
  // Sent before anything else can reach the worker, so the checks see the
  // head at rest; not awaited: the page stays usable meanwhile.
  checkFitQuality(app.fit);
  if (ui.autoFit.checked && texturable().length) await runTexture();
}
app.fitHead = () => runFit();

// Shows a head the worker holds, fitted just now or opened from a project
// file (result.loadMs; its stages carry the saved figures, no times): the
// Pipeline rows, the notes, the levels, the components, the subdivided
// head over app.scan's points, looking at its face.
// photos: a head from photos (no scan: no points under it; photos_head.js
// then names and fills the rows).
export function showHead(result, name, wallMs, photos = false) {
  const opened = result.loadMs !== undefined;
  nameRows(photos);
  app.fit = { name, stages: result.stages, meshes: result.meshes, fitMs: result.fitMs || 0, heapBytes: result.heapBytes || 0,
              parseMs: result.parseMs || 0, wallMs, points: result.points, fittedPoints: result.fittedPoints,
              thinnedTo: result.thinnedTo || 0,
              animatedVertices: result.animatedVertices, landmarks: result.landmarks || [],
              headFacing: result.headFacing || [0, 0, 1], headUp: result.headUp || [0, 1, 0] };
  forgetTexture();
  for (const st of FIT_STAGES) {
    const s = result.stages.find((x) => x.name === st.core);
    setStage(st.row, opened ? 'saved' : s ? Math.round(s.ms) + ' ms' : 'done', 1, 'complete');
    if (s) stageStats(st.row).textContent = 'mean ' + s.meanPct.toFixed(3) + ' % · max ' + s.maxPct.toFixed(2) + ' % of the scan\'s size';
    const li = stageItem(st.row);
    li.classList.add('viewable');
    // The row's name is its button (keyboard, screen readers); the whole row takes clicks.
    li.querySelector('.stage-name').disabled = false;
  }
  ui.fitTotal.textContent = opened
    ? 'opened from ' + name + ' in ' + Math.round(result.loadMs) + ' ms, not fitted again · ' +
      result.fittedPoints.toLocaleString('en') + ' points fitted when saved'
    : 'fit ' + (result.fitMs / 1000).toFixed(2) + ' s (+ parse ' + Math.round(result.parseMs) +
                            ' ms) · ' + result.fittedPoints.toLocaleString('en') + ' points fitted' +
                            // A dense scan fitted on cell averages (the notes say how).
                            (result.thinnedTo ? ' (averages of ' + result.points.toLocaleString('en') + ' scan points)' : '') +
                            (result.heapBytes ? ' · core memory ' + Math.round(result.heapBytes / 1048576) + ' MB' : '') +
                            (app.workerThreads ? ' · ' + app.workerThreads.threads + (app.workerThreads.threads === 1 ? ' thread' : ' threads') +
                             (app.workerThreads.fallback ? ' (threads could not start here)' : '') : '');
  ui.fitView.hidden = false;
  showFitNotes(result.notes || []);
  const levels = result.meshes.levels.length;
  for (const opt of ui.level.options) opt.disabled = Number(opt.value) > levels;
  if (Number(ui.level.value) > levels) ui.level.value = String(levels);
  if (app.scan) app.viewer.set_overlay_points(app.scan.display.positions, app.scan.display.normals, app.scan.display.colors);
  else app.viewer.set_overlay_points(new Float32Array(0), null, null);
  app.viewer.set_overlay_visible(ui.showPoints.checked);
  showComponents(result.components);
  showStage('subdivide');
  // Look at the new head's face: it is shown over the scan in the scan's
  // orientation, which need not face +z (Fran's faces 37 degrees off +x),
  // and the view was framed on the scan, which may be a face only.
  const [f, u] = [app.fit.headFacing, app.fit.headUp];
  lookAlong(f, u);
  // The axes the head was fitted in (the user's, or those the fit turned
  // the scan to), so that fitting again starts from them.
  if (!photos) showAxes(ui.scanUp, ui.scanFacing, snapAxis(u), snapAxis(f));
}

// What the fit decided on its own about the scan (turned to face +z, a
// face-only capture, ...), as `likeness fit` prints them: the user should
// know, and can pass the conventions next time.
function showFitNotes(notes) {
  ui.fitNotes.replaceChildren();
  for (const n of notes) {
    const li = document.createElement('li');
    li.textContent = forPage(n);
    ui.fitNotes.appendChild(li);
  }
  ui.fitNotes.hidden = notes.length === 0;
}

// The view framed on a head that looks along f with u up (scan frame).
function lookAlong(f, u) { app.viewer.set_head_frame(f[0], f[1], f[2], u[0], u[1], u[2]); }

// The loaded scan seen upright as the axes say, before it is fitted: the
// user sees at once whether they are right.
export function lookWithScanAxes() {
  if (app.viewer && app.scan) lookAlong(axisVector(ui.scanFacing.value), axisVector(ui.scanUp.value));
}

// Fit head, and the Pipeline rows: a fitted row shows its stage's mesh.
export function wireFit() {
  ui.fit.addEventListener('click', runFit);
  // New axes fit the loaded scan again when Auto-run is on; a facing along
  // the new up gives way to the usual one for that up (+z up: -y).
  showAxes(ui.scanUp, ui.scanFacing, ui.scanUp.value, ui.scanFacing.value);
  const axesChanged = () => {
    lookWithScanAxes();
    if (app.scan && (app.scan.file || app.scan.kept) && ui.autoFit.checked) runFit();
    else if (app.scan) setStatus('Press Fit head to fit the scan with its axes as set.');
  };
  ui.scanUp.addEventListener('change', () => {
    const up = ui.scanUp.value;
    showAxes(ui.scanUp, ui.scanFacing, up, parallel(up, ui.scanFacing.value) ? defaultFacing(up) : ui.scanFacing.value);
    axesChanged();
  });
  ui.scanFacing.addEventListener('change', axesChanged);
  for (const st of FIT_STAGES) {
    const li = stageItem(st.row);
    li.addEventListener('click', () => { if (li.classList.contains('viewable')) showStage(st.row); });
  }
}
