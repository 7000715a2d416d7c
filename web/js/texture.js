// The Texture stage (tarini2002 Sec. 3): every face photo with
// correspondences is calibrated and the fitted head textured in the worker;
// the viewer then shows the skin on the chosen level.
import { app, ui, beginJob, clearError, endJob, live, setStage, setStatus, showError, stageItem } from './state.js';
import { runJob } from './worker_client.js';
import { facePhotos, photoPoints, renderPhotos, texturable } from './photos.js';
import { clicker, closeClicker, updateClicker } from './clicker.js';
import { stopAnimation } from './animation.js';
import { showComponents, showStage } from './head_view.js';
import { photoCount } from './wording.js';
import { pageOption } from './project_inputs.js';

// The eye texture shown came from the user's own eye photo (a close-up
// set to "Eye (iris)", or one an opened project made from a photo the page
// still holds with that role): it wins over the iris found in the face
// photos. One found in the face photos, or one an opened or restored
// project brought without its eye photo, gives way to the iris found in
// the photos of the head now shown.
export function eyeFromUser() {
  const e = app.eyePhoto;
  if (!e || e.fromFacePhotos) return false;
  return !e.fromProject || app.photos.some((p) => p.role === 'eye' && p.name === e.name && !p.eyeFromViews);
}

export function forgetTexture() {
  app.texture = null;
  setStage('texture', 'waiting', 0);
  stageItem('texture').querySelector('.stage-stats').textContent = '';
  ui.textureTotal.textContent = '';
}

// Calibrates every photo that has correspondences and textures the fitted
// head in the worker; the viewer then shows the skin on the chosen level.
export async function runTexture() {
  const state = document.body.dataset.state;
  if (state === 'working' || state === 'loading' || app.startupFailed) return;
  clearError();
  if (!app.fit) { showError('Fit the head before texturing it: the texture is laid on the fitted head.'); return; }
  // A head from photos is textured from the photos it was made from, with
  // their self-calibrated cameras: no point to click.
  const fromPhotos = !!app.fit.fromPhotos;
  // (A photo that made the head and was then set to "Eye (iris)" stays: its
  // camera is known, and the iris is looked for in it too.)
  const using = fromPhotos ? app.photos.filter((p) => ((p.role || 'face') === 'face' || p.eyeFromViews) && p.photosHead && p.photosHead.used)
    : texturable();
  if (fromPhotos && !using.length) {
    showError('None of the photos made this head (they were removed or changed): make the head from the photos again, then texture it.');
    return;
  }
  if (!facePhotos().length) {
    showError(app.photos.length ? 'No photo has the role "Face (skin)": only face photos texture the skin.'
      : 'Drop one or more photos of the head (JPG or PNG) to texture it.');
    return;
  }
  if (!using.length) {
    showError('No photo is placed on the head yet: click each photo to mark its landmarks (at least 6 each), or drop ' +
              'its matching points (a .txt of the same name).');
    return;
  }
  const few = fromPhotos ? [] : using.filter((p) => photoPoints(p).list.length < 6);
  if (few.length) {
    showError(few.map((p) => p.name + ' has ' + photoPoints(p).list.length + ' point(s)').join('; ') +
              '. Placing a photo on the head needs at least 6 matching points (12-15 spread over the face are best): ' +
              'click more landmarks or skip the photo by clearing its clicks.');
    return;
  }
  const marked = fromPhotos ? using.find((p) => p.role === 'eye' && p.eyeFromViews) : null;
  stopAnimation();
  const job = beginJob('texture');
  if (!job) return;
  stageItem('texture').classList.remove('coming');
  setStage('texture', '0%', 0, 'active');
  setStatus('Texturing the head from ' + photoCount(using.length) + '…');
  const t0 = performance.now();
  let result;
  try {
    const photos = [];
    for (const p of using) {
      if (fromPhotos) {
        p.sent = [];
        photos.push({ name: p.name, buffer: await p.file.arrayBuffer(), checked: !!p.checked });
        continue;
      }
      const pts = photoPoints(p);
      p.sent = pts.list.map((x) => ({ label: x.label }));
      const flat = new Float64Array(pts.list.length * 5);
      pts.list.forEach((x, k) => flat.set([x.u, x.v, x.p[0], x.p[1], x.p[2]], 5 * k));
      photos.push({ name: p.name, buffer: await p.file.arrayBuffer(), points: flat, checked: !!p.checked });
    }
    const size = pageOption('textureSize') || 1024;  // ?texture_size, else a restored project's
    // A head from photos: the worker also looks for the iris in them, unless
    // an eye photo gave one; in the one photo set to "Eye (iris)" when the
    // user marked one of the head's photos (always looked for again then).
    const findEyes = fromPhotos && (!eyeFromUser() || !!marked);
    const options = { size, cameras: fromPhotos, findEyes };
    if (marked) options.irisPhoto = marked.name;
    result = await runJob({ type: 'texture', photos, options }, photos.map((p) => p.buffer),
      (stage, fraction) => {
        // stage is "texture:<step>" (decode, calibrate, chart, bind, resample, ...).
        if (!/^texture/.test(stage)) return;
        const step = stage.slice(8);
        setStage('texture', (step && step !== 'done' ? step + ' ' : '') + Math.round(fraction * 100) + '%', fraction, 'active');
      });
  } catch (e) {
    if (e && e.cancelled) {
      setStage('texture', 'cancelled', 0);
      setStatus('Texturing cancelled.');
      endJob(job);
      return;
    }
    result = { ok: false, code: 'Internal', message: e && e.message ? e.message : String(e) };
  }
  const wallMs = performance.now() - t0;
  if (!live(job)) return;
  // Per-photo calibration outcomes (also on failure: the page marks bad points).
  if (result.calib && !fromPhotos) using.forEach((p, i) => { p.calib = result.calib[i] || null; });
  renderPhotos();
  if (clicker.photo) updateClicker();
  if (!result.ok) {
    setStage('texture', 'failed', 0, 'failed');
    setStatus('Texturing failed; your points and clicks are kept.' + (app.fit ? ' The fitted head is still shown.' : ''));
    showError('Texture: ' + (result.message || result.code));
    return;
  }
  app.texture = { uvs: result.uvs, skin: result.skin, steps: result.steps, textureMs: result.textureMs, workerMs: result.workerMs, wallMs,
                  level: result.level, photos: using.length };
  // The iris found in the photos (the person's eye colour) replaces the generic one.
  let eyes = '';
  app.eyeNote = result.eyeNote || '';
  if (result.eyeTexture && (marked || !eyeFromUser())) {
    app.eyePhoto = { name: result.eyeSource, texture: result.eyeTexture, ms: 0, fromFacePhotos: true };
    if (app.viewer && app.componentsData) showComponents(app.componentsData);
    eyes = ' The eyes\' colour is from ' + result.eyeSource + '.';
  } else if (result.eyeNote) {
    eyes = ' The eyes keep the generic iris: no iris was found in ' + (marked ? marked.name : 'the photos') + '.';
  }
  setStage('texture', Math.round(result.textureMs) + ' ms', 1, 'complete');
  const rms = using.map((p) => p.calib && p.calib.ok ? p.calib.rms : NaN).filter((x) => !Number.isNaN(x));
  const cameras = fromPhotos ? 'cameras from the head\'s self-calibration'
    : 'calibration rms ' + (rms.length ? Math.min(...rms).toFixed(2) + '-' + Math.max(...rms).toFixed(2) : '?') + ' px';
  stageItem('texture').querySelector('.stage-stats').textContent = photoCount(using.length) + ', ' + cameras + ' · ' +
    result.skin.width + '² texels · ' + result.steps.map((x) => x.name + ' ' + Math.round(x.ms)).join(', ') + ' ms';
  ui.textureTotal.textContent = 'textured in ' + (result.textureMs / 1000).toFixed(2) + ' s';
  ui.showPoints.checked = false;
  app.viewer.set_overlay_visible(false);
  closeClicker();
  showStage('subdivide');
  setStatus('Textured from ' + photoCount(using.length) + ' in ' + (result.textureMs / 1000).toFixed(2) + ' s.' + eyes +
            ' Animate it, pick a level, or export the textured head.');
  endJob(job);
}
app.textureHead = () => runTexture();

export function wireTexture() {
  ui.texture.addEventListener('click', runTexture);
}
