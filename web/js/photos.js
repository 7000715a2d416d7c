// Photos for the texture (tarini2002 Sec. 3) and their correspondences:
// each dropped photo is decoded once in the worker (a broken file is caught
// now, not at the Texture stage), listed with a thumbnail, and gets its
// points from a points file of the same name or from landmark clicks.
import { app, ui, beginJob, endJob, live, refreshControls, setStatus, showError } from './state.js';
import { formatBytes, listFile, MAX_SCAN_BYTES, refuseFile } from './files.js';
import { runJob } from './worker_client.js';
import { clicker, closeClicker, openClicker } from './clicker.js';
import { dropRoleTexture, PHOTO_ROLES, setPhotoRole } from './photo_roles.js';
import { detectLandmarks, detectorInference, preloadDetector } from './landmarks.js';
import { photoCount } from './wording.js';

// Photos are decoded once in the worker to catch broken files now rather
// than at the Texture stage; the File objects are kept for that stage.
export async function checkPhotos(photos, alone) {
  const job = beginJob('photos');
  if (!job) return;
  // The detector loads while the first photo is checked (landmarks.js).
  if (photos.length) preloadDetector();
  const failures = [];
  for (const file of photos) {
    if (!live(job)) break;
    const meta = listFile(file, 'checking…');
    if (file.size > MAX_SCAN_BYTES) {
      const tooLarge = file.name + ' is ' + formatBytes(file.size) + '; photos up to ' + formatBytes(MAX_SCAN_BYTES) + ' are accepted.';
      refuseFile(meta, file, 'too large', tooLarge);
      failures.push(tooLarge);
      continue;
    }
    let result;
    const t0 = performance.now();
    try {
      const buffer = await file.arrayBuffer();
      result = await runJob({ type: 'image', name: file.name, buffer, smallPx: DETECT_PX }, [buffer]);
    } catch (e) {
      if (e && e.cancelled) {
        meta.textContent = formatBytes(file.size) + ' · cancelled';
        break;
      }
      result = { ok: false, message: file.name + ': ' + (e && e.message ? e.message : e) };
    }
    if (!result.ok) {
      // Beside the file: why it was refused (the worker's message).
      refuseFile(meta, file, 'refused', result.message || result.code);
      failures.push(result.message);
      continue;
    }
    meta.textContent = formatBytes(file.size) + ' · ' + result.width + '×' + result.height + ' photo';
    meta.parentElement.title = file.name + ': ' + result.width + '×' + result.height +
                               ' photo, kept for the Texture stage';
    // checked: the worker checked these bytes (the texture job need not probe them again).
    const photo = addPhoto({ name: file.name, file, width: result.width, height: result.height, decoder: result.decoder, checked: true,
                             exifFocalPx: result.focalPx || 0, checkMs: performance.now() - t0, small: result.small || null,
                             outline: result.outline || null });
    // Its face points are found now, while the worker checks the next photo
    // (the detector takes one photo at a time, landmarks.js).
    findLandmarks([photo]);
  }
  renderPhotos();
  if (!endJob(job)) return;
  if (failures.length) {
    showError(failures.join(' '));
  } else if (alone) {
    setStatus(photoCount(app.photos.length) + ' kept for the Texture stage. ' +
              (app.fit ? 'Give each its points (a .txt of the same name, or click the photo), then Texture.'
                : app.model ? 'Fit the head, then texture it.' : 'Drop a head scan (PLY, OBJ, XYZ or VTK) to start.'));
  }
  // Every photo's points may already be in (the detection ran beside the checks).
  if (app.afterLandmarks) app.afterLandmarks();
}

const baseName = (name) => name.replace(/\.[^.]*$/, '').toLowerCase();

// A photo dropped again under the same name replaces the old one but keeps
// its points and clicks (they are the user's work).
function addPhoto(entry) {
  const old = app.photos.findIndex((p) => p.name === entry.name);
  entry.url = URL.createObjectURL(entry.file);
  entry.filePoints = null;
  entry.pointsName = '';
  entry.clicks = new Map();
  entry.calib = null;
  entry.sent = null;
  entry.role = 'face';
  entry.detect = null;
  entry.photosHead = null;  // {used, refusal, rmsPx, leftOut} from the last head from photos
  if (old >= 0) {
    const prev = app.photos[old];
    URL.revokeObjectURL(prev.url);
    Object.assign(entry, { filePoints: prev.filePoints, pointsName: prev.pointsName, clicks: prev.clicks, role: prev.role || 'face' });
    app.photos[old] = entry;
  } else {
    app.photos.push(entry);
  }
  return entry;
}

// The photo as the detector sees it: at most DETECT_PX on its longer side.
// The detector finds the face on its own 192-256 px crops, so a smaller
// image costs it less and loses little (docs/design/photos.md, "Ten
// 12-megapixel photos": 1280 px halves the time of 1920 px, its points
// 2.8 px of a 4000 px photo from the full size's); its points are fractions
// of the image, so they come out in the photo's own pixels. The texture
// still reads the original file. The worker's check made it from its own
// decode of the photo (photo.small), so the photo is decoded here only where
// it did not (a photo smaller than that, or the stb decoder).
export const DETECT_PX = 1280;  // = the core's kPlainOutlineMaxSide (photos/outline.h)
async function detectionImage(photo) {
  const small = photo.small;
  photo.small = null;
  if (small) return small;
  const full = await createImageBitmap(photo.file);  // EXIF orientation applied
  const scale = DETECT_PX / Math.max(full.width, full.height);
  if (scale >= 1) return full;
  try {
    return await createImageBitmap(full, { resizeWidth: Math.round(full.width * scale), resizeHeight: Math.round(full.height * scale),
                                           resizeQuality: 'high' });
  } finally {
    full.close();
  }
}

// Face landmarks found by the detector (landmarks.js), one photo after the
// other, beside the page's jobs (they need no worker): photo.detect is
// {state: 'running' | 'found' | 'none' | 'many' | 'failed', points, faces,
// message, ms}. Where no face is found the guided clicks remain the way in.
async function findLandmarks(photos) {
  app.detectorInference = detectorInference();
  for (const photo of photos) photo.detect = { state: 'waiting' };
  for (const photo of photos) {
    if (!app.photos.includes(photo)) {  // removed meanwhile
      if (photo.small) photo.small.close();
      continue;
    }
    photo.detect = { state: 'running' };
    renderPhotos();
    const t0 = performance.now();
    let bitmap = null;
    try {
      bitmap = await detectionImage(photo);
      const t1 = performance.now();
      const r = await detectLandmarks(bitmap, photo.width, photo.height);
      const doneAt = performance.now();
      // ms: from its turn to its points; decodeMs: its detection image;
      // detectMs: the detector (its loading, for the first photo, included).
      const ms = Math.round(doneAt - t0), times = { ms, decodeMs: t1 - t0, detectMs: doneAt - t1, doneAt };
      if (!r.points) {
        photo.detect = { state: 'none', faces: 0, points: null, ...times,
                         message: 'no face found: mark its landmarks by clicking instead' };
      } else {
        photo.detect = { state: r.faces > 1 ? 'many' : 'found', faces: r.faces, points: r.points, ...times,
                         message: r.faces > 1 ? r.faces + ' faces found: points shown for one of them, check it is the right person'
                           : r.points.length + ' face points found' };
      }
    } catch (e) {
      photo.detect = { state: 'failed', points: null, message: 'face points not found: ' + (e && e.message ? e.message : e) };
    } finally {
      if (bitmap) bitmap.close();
    }
    renderPhotos();
    if (clicker.photo === photo) openClicker(photo);
  }
  // Every photo's points are in: a head from them (photos_head.js) when
  // Auto-run is on and no scan is loaded.
  if (app.afterLandmarks) app.afterLandmarks();
}

function removePhoto(photo) {
  if (document.body.dataset.state === 'working') return;
  if (clicker.photo === photo) closeClicker();
  app.photos = app.photos.filter((p) => p !== photo);
  URL.revokeObjectURL(photo.url);
  dropRoleTexture(photo);
  renderPhotos();
  setStatus('Removed ' + photo.name + ' from the photos.');
}

// Points files (u v X Y Z per line, read by the core's parser) go to the
// photo of the same base name.
export async function readPointFiles(files) {
  const failures = [];
  const job = beginJob('points');
  if (!job) return;
  for (const file of files) {
    if (!live(job)) break;
    const photo = app.photos.find((p) => baseName(p.name) === baseName(file.name));
    const meta = listFile(file, 'reading…');
    if (!photo) {
      const why = file.name + ' is not a scan, and no photo is named ' + baseName(file.name) + '.jpg or .png: a .txt of ' +
                  'matching points goes with the photo of the same name; drop both together.';
      refuseFile(meta, file, 'no photo named ' + baseName(file.name) + '.jpg/.png', why);
      failures.push(why);
      continue;
    }
    let result;
    try {
      result = file.size > 4 * 1024 * 1024 ? { ok: false, message: 'larger than 4 MB: not a list of matching points' }
        : await runJob({ type: 'points', text: await file.text() }, []);
    } catch (e) {
      result = { ok: false, message: e && e.message ? e.message : String(e) };
    }
    if (!result.ok) {
      const why = file.name + ': ' + result.message + ' (each line should hold five numbers: a point\'s pixel in the ' +
                  'photo, u v, then its place on the scan, X Y Z)';
      refuseFile(meta, file, 'not matching points', why);
      failures.push(why);
      continue;
    }
    photo.filePoints = result.points;
    photo.pointsName = file.name;
    photo.calib = null;
    meta.textContent = formatBytes(file.size) + ' · ' + result.points.length / 5 + ' points for ' + photo.name;
  }
  renderPhotos();
  if (!endJob(job)) return;
  if (failures.length) showError(failures.join(' '));
}

// The correspondences a photo contributes: its clicks when it has any
// (landmarks placed on the fitted head), else its points file.
export function photoPoints(photo) {
  const clicked = [];
  if (app.fit && app.fit.landmarks) {
    for (const lm of app.fit.landmarks) {
      const c = photo.clicks.get(lm.id);
      if (c && c !== 'skip') clicked.push({ u: c.u, v: c.v, p: lm.position, label: lm.label });
    }
  }
  if (clicked.length || !photo.filePoints) return { source: clicked.length ? 'clicks' : 'none', list: clicked };
  const list = [];
  const f = photo.filePoints;
  for (let k = 0; k + 4 < f.length; k += 5) list.push({ u: f[k], v: f[k + 1], p: [f[k + 2], f[k + 3], f[k + 4]], label: 'point ' + (k / 5 + 1) });
  return { source: 'file', list };
}

// Photos that take part in texturing: those with any correspondence.
export function texturable() { return facePhotos().filter((p) => photoPoints(p).list.length > 0); }
// Photos of role "face" (the default) texture the skin; "eye" and "smile"
// photos only make the iris and teeth textures.
export function facePhotos() { return app.photos.filter((p) => (p.role || 'face') === 'face'); }
// The detector has the photo queued or running (photo.detect, findLandmarks);
// a photo never sent to it (one restored from a kept head) is not waiting.
export const findingFacePoints = (p) => !!p.detect && ['waiting', 'running'].includes(p.detect.state);

export function renderPhotos() {
  ui.photoList.textContent = '';
  for (const [index, photo] of app.photos.entries()) {
    const li = document.createElement('li');
    li.dataset.index = String(index);
    li.classList.toggle('open', clicker.photo === photo);
    // The thumbnail is the row's button (keyboard, screen readers); the whole
    // row takes clicks. Not the row itself: it holds the role menu and ×.
    const open = document.createElement('button');
    open.type = 'button';
    open.className = 'photo-open';
    open.setAttribute('aria-label', 'Open ' + photo.name + ' to mark landmarks');
    const img = document.createElement('img');
    img.src = photo.url;
    img.alt = '';
    open.append(img);
    const text = document.createElement('div');
    const name = document.createElement('div');
    name.className = 'photo-name';
    name.textContent = photo.name;
    const meta = document.createElement('div');
    meta.className = 'photo-meta';
    const pts = photoPoints(photo);
    let note = photo.width + '×' + photo.height;
    // "no points yet" only while the detector has not given the photo its own.
    // Nor when the detector found none: its own message says what to do.
    const detected = photo.detect && ['found', 'many', 'none', 'failed'].includes(photo.detect.state);
    if (pts.source === 'clicks') note += ' · ' + pts.list.length + ' of ' + app.fit.landmarks.length + ' landmarks clicked';
    else if (pts.source === 'file') note += ' · ' + pts.list.length + ' points from ' + photo.pointsName;
    else if (!detected) note += ' · ' + (app.fit ? 'no points yet: click to mark landmarks' : 'no points yet');
    if (pts.list.length > 0 && pts.list.length < 6) { note += ' (6 needed)'; meta.classList.add('bad'); }
    if (photo.detect && photo.detect.state !== 'waiting' && (photo.role || 'face') === 'face') {
      note += ' · ' + (photo.detect.state === 'running' ? 'finding face points…' : photo.detect.message);
      if (photo.detect.state !== 'found' && photo.detect.state !== 'running') meta.classList.add('bad');
    }
    // The last head from photos: used, or why not.
    const ph = (photo.role || 'face') === 'face' ? photo.photosHead : null;
    if (ph) {
      if (ph.used) note += ' · used for the head (' + ph.rmsPx.toFixed(1) + ' px' + (ph.outlinePoints ? ', and its outline' : '') + ')';
      else { note += ' · not used for the head' + (ph.leftOut ? ' (no face points)' : ph.refusal ? ': ' + ph.refusal : ''); meta.classList.add('bad'); }
    }
    if (photo.calib) {
      if (photo.calib.ok) {
        const outliers = photo.calib.outlier.filter(Boolean).length;
        note += ' · calibrated, rms ' + photo.calib.rms.toFixed(2) + ' px' + (outliers ? ', ' + outliers + ' outlier(s)' : '');
      } else {
        note += ' · calibration failed';
        meta.classList.add('bad');
      }
    }
    meta.textContent = note;
    const role = document.createElement('select');
    role.className = 'photo-role small';
    role.setAttribute('aria-label', 'Role of ' + photo.name);
    for (const [value, label] of PHOTO_ROLES) role.append(new Option(label, value, false, value === (photo.role || 'face')));
    role.addEventListener('click', (e) => e.stopPropagation());
    role.addEventListener('keydown', (e) => e.stopPropagation());
    role.addEventListener('change', () => setPhotoRole(photo, role.value));
    if ((photo.role || 'face') !== 'face') {
      meta.classList.remove('bad');
      meta.textContent = photo.width + '×' + photo.height + ' · ' + (photo.roleNote || '');
      if (photo.roleFailed) meta.classList.add('bad');
    }
    text.append(name, meta, role);
    const remove = document.createElement('button');
    remove.type = 'button';
    remove.className = 'photo-remove small';
    remove.textContent = '×';
    remove.title = 'Remove ' + photo.name + ' (and its points) from the texture';
    remove.setAttribute('aria-label', 'Remove ' + photo.name);
    remove.addEventListener('click', (e) => { e.stopPropagation(); removePhoto(photo); });
    li.append(open, text, remove);
    li.title = photo.name + ': click to mark landmarks on it' + (photo.calib && !photo.calib.ok ? ' (' + photo.calib.message + ')' : '');
    li.addEventListener('click', () => openClicker(photo));
    ui.photoList.append(li);
  }
  const faces = app.photos.filter((p) => p.detect && p.detect.points).length, points = texturable().length;
  ui.photoCount.textContent = !app.photos.length ? '' : photoCount(app.photos.length) +
    (faces ? ', ' + faces + ' with face points' : '') + (points || !faces ? ', ' + points + ' with points for the texture' : '');
  refreshControls();
}
