// A head from photos alone (issue 37, fua1998): the page's main flow when
// no scan is loaded. Each face photo's landmarks (landmarks.js, found when
// it was dropped) go to the worker's 'photos' job, which runs the core's
// photos job (self-calibration, then the shape fit: `likeness photos`) and
// keeps the result as the head project; it is shown like a fitted head.
// Photos without a face are left out; each photo's row says whether it was
// used or why not. With Auto-run on it starts once every photo's landmarks
// are in, with no click.
import { app, ui, beginJob, endJob, live, setStage, setStatus, showError, stageItem } from './state.js';
import { runJob } from './worker_client.js';
import { landmarksJson } from './landmarks.js';
import { DETECT_PX, facePhotos, findingFacePoints, renderPhotos } from './photos.js';
import { FIT_STAGES, showHead } from './fit.js';
import { checkFitQuality } from './checks.js';
import { stopAnimation } from './animation.js';
import { forPage } from './wording.js';
import { runTexture } from './texture.js';

// (A face photo set to "Eye (iris)" for its eye colour, photo_roles.js,
// stays a face photo of the head.)
const withPoints = () => app.photos.filter((p) => ((p.role || 'face') === 'face' || p.eyeFromViews) && p.detect && p.detect.points);

function stats(row, text) {
  const el = stageItem(row).querySelector('.stage-stats');  // the load row has none
  if (el) el.textContent = text;
}

// The rows while the job runs, and after it failed.
function rowsWaiting(n) {
  setStage('load', n + ' photo' + (n === 1 ? '' : 's'), 1, 'complete');
  stats('load', '');
  for (const st of FIT_STAGES) {
    setStage(st.row, 'waiting', 0);
    stats(st.row, '');
    stageItem(st.row).classList.remove('coming', 'viewable', 'shown');
    stageItem(st.row).querySelector('.stage-name').disabled = true;
  }
  setStage('align', 'running', 0, 'active');
}

// Rows of a finished head: what ran, with the core's figures. The core runs
// both stages in one call: their time is one figure, on the Self-calibration row.
function rowsDone(r, n, prior) {
  const used = r.photos.filter((p) => p.used).length;
  const [c0, c1] = r.calibrationRmsPx, [f0, f1] = r.shapeFitRmsPx;
  setStage('align', used + ' of ' + n + ' photos', 1, 'complete');
  stats('align', 'focal ' + Math.round(r.focalPx) + ' px' + (prior ? ' (the photos\' EXIF says ' + Math.round(prior) + ' px)' : '') +
        ' · landmark error ' + c0.toFixed(1) + ' → ' + c1.toFixed(1) +
        ' px (generic head → bundle adjustment) · both stages ' + (r.photosMs / 1000).toFixed(2) + ' s');
  setStage('local_fit', 'done', 1, 'complete');
  stats('local_fit', 'landmark error on the fitted mesh ' + f0.toFixed(1) + ' → ' + f1.toFixed(1) + ' px · stiffness ' +
        r.shapeFitStages.map((s) => s.stiffness).join(', ') + silhouetteStats(r.silhouettes));
  // No scan: the scan fit's global stage did not run; its row is no result.
  const g = stageItem('global_fit');
  setStage('global_fit', 'not run (no scan)', 0);
  g.classList.remove('viewable', 'shown');
  g.querySelector('.stage-name').disabled = true;
  setStage('subdivide', r.meshes.levels.length + ' levels', 1, 'complete');
  stats('subdivide', 'Butterfly levels of the fitted control mesh; no scan, so no detail displacements');
}

// The head's rim against the photos' outlines (a plain background gives
// them; a room behind the person does not).
function silhouetteStats(sil) {
  if (!sil || !sil.photos) return ' · no outline (the photos\' backgrounds are not plain)';
  const [a, b] = sil.rimToOutlinePx;
  return ' · the outline in ' + sil.photos + ' photo' + (sil.photos === 1 ? '' : 's') + ': head edge to outline ' +
         a.toFixed(1) + ' → ' + b.toFixed(1) + ' px';
}

// The focal prior from the photos' EXIF (the median over those that give
// one, as `likeness photos` takes it), 0: none.
function exifFocal(photos) {
  const f = photos.map((p) => p.exifFocalPx || 0).filter((x) => x > 0).sort((a, b) => a - b);
  return f.length ? f[Math.floor(f.length / 2)] : 0;
}

// Each photo's outline on a plain background (the worker finds it when the
// photo is dropped): found again for photos restored from a kept or saved
// project, which keep their points but not their outline.
async function findOutlines(photos) {
  for (const p of photos) {
    if (p.outline) continue;
    const buffer = await p.file.arrayBuffer();
    const r = await runJob({ type: 'outline', name: p.name, buffer, smallPx: DETECT_PX }, [buffer]);
    p.outline = r.ok ? r.outline : { message: r.message || r.code };
  }
}

export async function makeHeadFromPhotos(trigger = 'button') {
  const state = document.body.dataset.state;
  if (state === 'working' || state === 'loading' || app.startupFailed) return;
  if (app.scan) {
    showError('A scan is loaded: the head is fitted to it (Fit head). A head from photos alone is made when no scan is loaded.');
    return;
  }
  const photos = withPoints();
  if (!photos.length) {
    showError('No photo has face points yet: drop photos of a face (front, three-quarter and side views), and wait ' +
              'for their face points.');
    return;
  }
  stopAnimation();
  const job = beginJob('photos head');
  if (!job) return;
  for (const p of app.photos) p.photosHead = null;
  // Face photos without points are left out, and say so.
  for (const p of facePhotos()) if (!p.detect || !p.detect.points) p.photosHead = { used: false, leftOut: true };
  rowsWaiting(photos.length);
  ui.photosHeadTotal.textContent = '';
  setStatus('Making a head from the face points of ' + photos.length + ' photo' + (photos.length === 1 ? '' : 's') + '…');
  const prior = exifFocal(photos);
  const t0 = performance.now();
  let result;
  try {
    await findOutlines(photos);
    if (!live(job)) return;
    const list = photos.map((p) => ({ name: p.name, text: JSON.stringify(landmarksJson(p.name, p.width, p.height, p.detect.points)),
                                      outline: p.outline && p.outline.points ? p.outline.points : null }));
    result = await runJob({ type: 'photos', photos: list, options: { levels: 3, focalPx: prior } }, []);
  } catch (e) {
    if (e && e.cancelled) {
      for (const st of FIT_STAGES) setStage(st.row, 'cancelled', 0);
      setStatus('Head from photos cancelled.');
      return;
    }
    result = { ok: false, code: 'Internal', message: e && e.message ? e.message : String(e) };
  }
  const wallMs = performance.now() - t0;
  if (!live(job)) return;
  // Each photo's verdict beside it (the worker keeps the order it was given).
  (result.photos || []).forEach((row, k) => { if (photos[k]) photos[k].photosHead = row; });
  const usedCount = (result.photos || []).filter((p) => p.used).length;
  app.photosHead = { trigger, ok: !!result.ok, photos: photos.length, used: usedCount, focalPx: result.focalPx || 0,
                     exifFocalPx: prior,
                     wallMs, photosMs: result.photosMs || 0, message: result.ok ? '' : result.message,
                     notes: result.notes || [] };
  renderPhotos();
  if (!result.ok) {
    setStage('align', 'failed', 0, 'failed');
    const refused = (result.photos || []).filter((p) => p.refusal).map((p) => p.name + ': ' + p.refusal);
    setStatus('No head was made from the photos.' + (app.fit ? ' The head shown before is still shown.' : ''));
    showError('No head from these photos: ' + forPage(result.message || result.code) +
              (refused.length ? ' (' + refused.join('; ') + ')' : '') +
              '. A head needs two or more photos of the same person\'s face, from different sides.');
    return;
  }
  app.project = null;
  const named = 'head from ' + usedCount + (usedCount === 1 ? ' photo' : ' photos');
  app.model = { name: named, kind: 'photos', vertexCount: result.meshes.control.vertexCount,
                triangleCount: result.meshes.control.triangleCount };
  showHead(result, named, wallMs, true);
  app.fit.fromPhotos = true;
  rowsDone(result, photos.length, prior);
  ui.fitTotal.textContent = 'head from ' + usedCount + ' of ' + photos.length + ' photos in ' + (result.photosMs / 1000).toFixed(2) +
                            ' s in the worker · focal ' + Math.round(result.focalPx) + ' px · the generic head\'s size ' +
                            '(photos without a known focal do not give the scale)';
  ui.photosHeadTotal.textContent = usedCount + ' of ' + photos.length + ' photos used · ' + (wallMs / 1000).toFixed(1) + ' s';
  setStatus('Head made from ' + usedCount + ' photos in ' + (result.photosMs / 1000).toFixed(2) + ' s: no scan, no click. ' +
            'Texture it from the same photos, pick a level, animate or export; click a photo to correct its points' +
            (ui.autoFit.checked ? ': the head is made again when you close it.' : ' and make it again.'));
  endJob(job);
  checkFitQuality(app.fit);
  // With Auto-run on, the skin from the same photos, their cameras known: no click.
  if (ui.autoFit.checked) await runTexture();
}

// Auto-run: once every dropped photo has its landmarks, with no scan loaded
// and the page at rest (a banner is left for the user to read).
// While photos are being taken (capture.js), once the views are enough.
export function photosHeadAfterLandmarks() {
  if (!ui.autoFit.checked || app.scan || app.photos.some(findingFacePoints) || !withPoints().length) return;
  if (app.capturing && !(app.viewGuide && app.viewGuide.enough)) return;
  const state = document.body.dataset.state;
  if (state !== 'ready' && state !== 'done') return;
  makeHeadFromPhotos('auto');
}

export function wirePhotosHead() {
  ui.photosHead.addEventListener('click', () => makeHeadFromPhotos('button'));
  app.afterLandmarks = photosHeadAfterLandmarks;
}
