// The landmark clicker: the photo large beside the 3D view; the landmarks of
// the fitted head are asked in turn, the one asked is marked red on the head.
// Clicks live in photo.clicks, so they survive picking another photo, an
// error, or a new fit of the same scan.
import { app, ui, setStatus } from './state.js';
import { photoPoints, renderPhotos } from './photos.js';
import { stopAnimation } from './animation.js';
import { download } from './export.js';
import { landmarksJson } from './landmarks.js';

// drag: the index of the detected face point being dragged (or -1); moved:
// the drag moved it, so the click that ends it places no landmark.
// corrected: a face point was dragged since the photo was opened.
export const clicker = { photo: null, image: null, current: 0, view: null, drag: -1, moved: false, corrected: false };

const CLICK_NOTE = 'Click where the named point is in the photo; the red dot on the 3D head shows it. Skip points ' +
  'hidden in this photo. Six points at least, 12-15 spread over the face are best. After texturing, each point shows its ' +
  'reprojection error in pixels; red ones were rejected as outliers.';
const detected = (photo) => (photo && photo.detect && photo.detect.points) || null;

export function openClicker(photo) {
  if (photo && (photo.role || 'face') !== 'face') {
    setStatus(photo.name + ' is ' + (photo.role === 'eye' ? 'an eye' : 'a smile') + ' photo: it needs no landmarks ' +
              '(set its role to "Face (skin)" to texture the skin with it).');
    return;
  }
  const fitted = app.fit && app.fit.landmarks && app.fit.landmarks.length;
  if (!fitted && !detected(photo)) {
    const state = photo && photo.detect ? photo.detect.state : '';
    setStatus(state === 'running' || state === 'waiting' ? 'Face points are being found on ' + photo.name + '; open it again in a moment.'
      : state === 'none' || state === 'failed' ? 'No face points on ' + photo.name + ': once the head is fitted, click its landmarks on it instead.'
        : 'Fit the head first: the landmarks are placed on the fitted head.');
    return;
  }
  stopAnimation();
  clicker.photo = photo;
  clicker.image = new Image();
  clicker.image.onload = () => drawClicker();
  clicker.image.src = photo.url;
  clicker.current = fitted ? nextLandmark(0) : -1;
  ui.clicker.hidden = false;
  ui.viewerPane.classList.add('clicking');
  reframeSoon();
  renderPhotos();
  updateClicker();
}
app.openClicker = (i) => openClicker(app.photos[i]);

export function closeClicker() {
  if (!clicker.photo) return;
  const corrected = clicker.corrected;
  clicker.photo = null;
  clicker.corrected = false;
  ui.clicker.hidden = true;
  ui.viewerPane.classList.remove('clicking');
  reframeSoon();
  if (app.viewer) app.viewer.set_markers(new Float32Array(0), null);
  renderPhotos();
  // Corrected face points make the head from photos again (with Auto-run on,
  // no scan loaded, the page at rest: photosHeadAfterLandmarks decides).
  if (corrected && app.afterLandmarks) app.afterLandmarks();
}

// The 3D view's width changes with the clicker: frame the head again once
// the viewer has taken the new canvas size (it does so each frame).
function reframeSoon() {
  requestAnimationFrame(() => requestAnimationFrame(() => { if (app.viewer) app.viewer.reset_view(); }));
}

// The first landmark from `from` on that has neither a click nor a skip.
function nextLandmark(from) {
  if (!app.fit || !app.fit.landmarks) return -1;
  const lms = app.fit.landmarks;
  for (let k = 0; k < lms.length; k++) {
    const i = (from + k) % lms.length;
    if (!clicker.photo.clicks.has(lms[i].id)) return i;
  }
  return -1;
}

export function updateClicker() {
  const photo = clicker.photo;
  if (!photo) return;
  const found = detected(photo);
  ui.clickerSavePoints.hidden = !found;
  if (!app.fit || !app.fit.landmarks) {
    // Face points only (no fitted head to click landmarks on yet).
    ui.clickerPrompt.textContent = photo.name + ': ' + photo.detect.message + '. Drag a point to correct it.';
    ui.clickerNote.textContent = 'The yellow dots are the face points found in the photo. Drag one that is off to where it ' +
      'belongs; Save points keeps them as a file. Once the head is fitted, clicking the photo marks the guided landmarks.';
    ui.clickerList.textContent = '';
    ui.clickerUndo.disabled = ui.clickerSkip.disabled = true;
    drawClicker();
    return;
  }
  ui.clickerNote.textContent = CLICK_NOTE +
    (found ? ' The faint yellow dots are the face points found in the photo: drag one to correct it.' : '');
  const lms = app.fit.landmarks;
  const done = lms.filter((l) => photo.clicks.has(l.id) && photo.clicks.get(l.id) !== 'skip').length;
  const lm = clicker.current >= 0 ? lms[clicker.current] : null;
  ui.clickerPrompt.textContent = '';
  if (lm) {
    ui.clickerPrompt.append(photo.name + ': click ');
    const b = document.createElement('strong');
    b.textContent = lm.label;
    ui.clickerPrompt.append(b, ' (' + (clicker.current + 1) + ' of ' + lms.length + '; ' + done + ' clicked)');
  } else {
    ui.clickerPrompt.textContent = photo.name + ': every landmark is clicked or skipped (' + done + ' clicked).' +
      (done < 6 ? ' At least 6 are needed.' : ' Texture when the other photos are done.');
  }
  ui.clickerList.textContent = '';
  const sentIndex = new Map((photo.sent || []).map((s, k) => [s.label, k]));
  for (const [i, l] of lms.entries()) {
    const li = document.createElement('li');
    const c = photo.clicks.get(l.id);
    let text = l.label;
    const k = sentIndex.get(l.label);
    if (c && c !== 'skip' && photo.calib && photo.calib.ok && k !== undefined) {
      const err = photo.calib.errors[k];
      text += ' · ' + (err < 0 ? 'behind the camera' : err.toFixed(1) + ' px');
      if (photo.calib.outlier[k]) { li.classList.add('outlier'); text += ' (outlier)'; }
    }
    li.textContent = text;
    if (c === 'skip') li.classList.add('skipped');
    else if (c) li.classList.add('done');
    if (i === clicker.current) li.classList.add('current');
    li.addEventListener('click', () => { clicker.current = i; updateClicker(); });
    ui.clickerList.append(li);
  }
  ui.clickerUndo.disabled = photo.clicks.size === 0;
  ui.clickerSkip.disabled = !lm;
  // The asked landmark in red on the 3D head; clicked ones green.
  if (app.viewer) {
    const pos = [], col = [];
    for (const [i, l] of lms.entries()) {
      const c = photo.clicks.get(l.id);
      if (i === clicker.current) { pos.push(...l.position); col.push(1, 0.15, 0.1); }
      else if (c && c !== 'skip') { pos.push(...l.position); col.push(0.3, 0.9, 0.5); }
    }
    app.viewer.set_markers(new Float32Array(pos), new Float32Array(col));
  }
  drawClicker();
}

function drawClicker() {
  const photo = clicker.photo, img = clicker.image;
  const canvas = ui.clickerCanvas;
  if (!photo) return;
  ui.clickerSavePoints.hidden = !detected(photo);
  const dpr = window.devicePixelRatio || 1;
  const w = Math.max(1, Math.round(canvas.clientWidth * dpr)), h = Math.max(1, Math.round(canvas.clientHeight * dpr));
  if (canvas.width !== w || canvas.height !== h) { canvas.width = w; canvas.height = h; }
  const g = canvas.getContext('2d');
  g.fillStyle = '#000';
  g.fillRect(0, 0, w, h);
  if (!img || !img.complete || !img.naturalWidth) return;
  const scale = Math.min(w / photo.width, h / photo.height);
  const ox = (w - photo.width * scale) / 2, oy = (h - photo.height * scale) / 2;
  clicker.view = { scale, ox, oy, dpr };
  g.drawImage(img, ox, oy, photo.width * scale, photo.height * scale);
  // The detector's face points: small dots, the dragged one larger. While
  // the guided landmarks are clicked they are faint, so the eye corners and
  // lips they cover stay visible; they can still be dragged.
  const found = detected(photo);
  if (found) {
    const guided = !!(app.fit && app.fit.landmarks);
    g.fillStyle = '#ffd24d';
    for (const [i, p] of found.entries()) {
      if (!p) continue;
      const dragged = i === clicker.drag;
      g.globalAlpha = guided && !dragged ? 0.3 : 1;
      const r = (dragged ? 4 : guided ? 1.2 : 1.6) * dpr;
      g.fillRect(ox + p[0] * scale - r, oy + p[1] * scale - r, 2 * r, 2 * r);
    }
    g.globalAlpha = 1;
  }
  // Points: clicked (or from the file), numbered; after a calibration each
  // shows its reprojection error, outliers in red.
  const pts = photoPoints(photo);
  const sentIndex = new Map((photo.sent || []).map((s, k) => [s.label, k]));
  g.font = Math.round(12 * dpr) + 'px system-ui, sans-serif';
  g.lineWidth = 2 * dpr;
  for (const [n, pt] of pts.list.entries()) {
    const x = ox + pt.u * scale, y = oy + pt.v * scale;
    const k = sentIndex.get(pt.label);
    const calib = photo.calib && photo.calib.ok && k !== undefined ? photo.calib : null;
    const outlier = calib && calib.outlier[k];
    g.strokeStyle = outlier ? '#ff4d4d' : '#7de2c3';
    g.beginPath();
    g.arc(x, y, 6 * dpr, 0, 2 * Math.PI);
    g.stroke();
    g.fillStyle = outlier ? '#ff4d4d' : '#ffffff';
    const label = String(n + 1) + (calib ? ' · ' + (calib.errors[k] < 0 ? '∞' : calib.errors[k].toFixed(1)) + ' px' : '');
    g.fillText(label, x + 8 * dpr, y - 8 * dpr);
  }
}

// Canvas pixel of a pointer event -> photo pixel.
function photoPixel(e) {
  const v = clicker.view, rect = ui.clickerCanvas.getBoundingClientRect();
  return [((e.clientX - rect.left) * v.dpr - v.ox) / v.scale, ((e.clientY - rect.top) * v.dpr - v.oy) / v.scale];
}

// Dragging a detected face point moves it (the user's correction).
function pointerDown(e) {
  const found = detected(clicker.photo), v = clicker.view;
  clicker.moved = false;
  if (!found || !v) return;
  const [u, w] = photoPixel(e);
  const reach = 8 * v.dpr / v.scale;  // 8 CSS pixels
  let best = -1, bestD = reach * reach;
  for (const [i, p] of found.entries()) {
    if (!p) continue;
    const d = (p[0] - u) ** 2 + (p[1] - w) ** 2;
    if (d < bestD) { best = i; bestD = d; }
  }
  if (best < 0) return;
  clicker.drag = best;
  ui.clickerCanvas.setPointerCapture(e.pointerId);
  drawClicker();
}

function pointerMove(e) {
  if (clicker.drag < 0) return;
  const photo = clicker.photo;
  const [u, w] = photoPixel(e);
  detected(photo)[clicker.drag] = [Math.min(Math.max(u, 0), photo.width), Math.min(Math.max(w, 0), photo.height)];
  if (!photo.detect.corrected) photo.detect.corrected = new Set();
  photo.detect.corrected.add(clicker.drag);  // kept with the photo (keep.js)
  clicker.moved = true;
  clicker.corrected = true;
  drawClicker();
}

function pointerUp() {
  if (clicker.drag < 0) return;
  clicker.drag = -1;
  drawClicker();
}

function savePoints() {
  const photo = clicker.photo, found = detected(photo);
  if (!found) return;
  const json = JSON.stringify(landmarksJson(photo.name, photo.width, photo.height, found));
  download(photo.name.replace(/\.[^.]*$/, '') + '.landmarks.json', new TextEncoder().encode(json), 'application/json');
  setStatus('Saved the ' + found.length + ' face points of ' + photo.name + '.');
}

function clickerClick(e) {
  const photo = clicker.photo, v = clicker.view;
  if (clicker.moved) { clicker.moved = false; return; }  // the end of a drag
  if (!photo || !v || clicker.current < 0) return;
  const rect = ui.clickerCanvas.getBoundingClientRect();
  const u = ((e.clientX - rect.left) * v.dpr - v.ox) / v.scale;
  const w = ((e.clientY - rect.top) * v.dpr - v.oy) / v.scale;
  if (u < 0 || w < 0 || u > photo.width || w > photo.height) return;  // outside the photo
  const lm = app.fit.landmarks[clicker.current];
  photo.clicks.delete(lm.id);  // re-clicking a landmark moves it (and puts it last for Undo)
  photo.clicks.set(lm.id, { u, v: w });
  photo.calib = null;
  clicker.current = nextLandmark(clicker.current + 1);
  updateClicker();
  renderPhotos();
}

function clickerUndo() {
  const photo = clicker.photo;
  if (!photo || !photo.clicks.size) return;
  const last = Array.from(photo.clicks.keys()).pop();
  photo.clicks.delete(last);
  photo.calib = null;
  clicker.current = app.fit.landmarks.findIndex((l) => l.id === last);
  updateClicker();
  renderPhotos();
}

function clickerSkip() {
  const photo = clicker.photo;
  if (!photo || clicker.current < 0) return;
  const lm = app.fit.landmarks[clicker.current];
  photo.clicks.delete(lm.id);
  photo.clicks.set(lm.id, 'skip');
  clicker.current = nextLandmark(clicker.current + 1);
  updateClicker();
}

function clickerClear() {
  const photo = clicker.photo;
  if (!photo) return;
  photo.clicks = new Map();
  photo.calib = null;
  clicker.current = nextLandmark(0);
  updateClicker();
  renderPhotos();
}

export function wireClicker() {
  ui.clickerCanvas.addEventListener('click', clickerClick);
  ui.clickerCanvas.addEventListener('pointerdown', pointerDown);
  ui.clickerCanvas.addEventListener('pointermove', pointerMove);
  ui.clickerCanvas.addEventListener('pointerup', pointerUp);
  ui.clickerCanvas.addEventListener('pointercancel', pointerUp);
  ui.clickerSavePoints.addEventListener('click', savePoints);
  ui.clickerUndo.addEventListener('click', clickerUndo);
  ui.clickerSkip.addEventListener('click', clickerSkip);
  ui.clickerClear.addEventListener('click', clickerClear);
  ui.clickerClose.addEventListener('click', closeClicker);
  window.addEventListener('resize', () => drawClicker());
  ui.clicker.addEventListener('keydown', (e) => {
    if (e.key === 'Escape') closeClicker();
    else if ((e.ctrlKey || e.metaKey) && e.key === 'z') { e.preventDefault(); clickerUndo(); }
  });
}
