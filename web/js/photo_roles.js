// Photo roles (tarini2002 Sec. 4): a photo set to "Eye (iris)" makes the
// eyeballs' iris texture, one set to "Smile (teeth)" the teeth texture; both
// run in the worker. Face photos (the default) texture the skin.
import { app, beginJob, clearError, endJob, live, setStatus, showError } from './state.js';
import { runJob } from './worker_client.js';
import { renderPhotos } from './photos.js';
import { clicker, closeClicker } from './clicker.js';
import { showComponents } from './head_view.js';
import { runTexture } from './texture.js';

export const PHOTO_ROLES = [['face', 'Face (skin)'], ['eye', 'Eye (iris)'], ['smile', 'Smile (teeth)']];

// Forgets the iris / teeth texture this photo made (role changed, photo
// removed); the components go back to the generic textures.
export function dropRoleTexture(photo) {
  let changed = false;
  if (app.eyePhoto && app.eyePhoto.name === photo.name) { app.eyePhoto = null; changed = true; }
  if (app.smilePhoto && app.smilePhoto.name === photo.name) { app.smilePhoto = null; changed = true; }
  if (changed && app.viewer && app.componentsData) showComponents(app.componentsData);
}

// MediaPipe Face Mesh landmarks (landmarks.js numbering): each eye's
// corners, the mouth's corners and the lips' middles.
const EYE_CORNERS = [[33, 133], [362, 263]];
const MOUTH = { corners: [61, 291], lips: [0, 17] };

// A photo whose face points were found (a whole face, not a close-up): the
// close-up the eye or smile job needs, cut around the wider eye (the one
// turned most to the camera) or the mouth, as PNG bytes; null when the
// points are missing or the cut would be under 32 px. {buffer, box}.
async function closeUpFromFace(photo, eye) {
  const pts = photo.detect && photo.detect.points;
  if (!pts) return null;
  const span = (a, b) => (pts[a] && pts[b] ? Math.hypot(pts[a][0] - pts[b][0], pts[a][1] - pts[b][1]) : 0);
  let c, width;
  if (eye) {
    const [a, b] = EYE_CORNERS.reduce((best, e) => (span(...e) > span(...best) ? e : best));
    if (!span(a, b)) return null;
    c = [(pts[a][0] + pts[b][0]) / 2, (pts[a][1] + pts[b][1]) / 2];
    width = 1.5 * span(a, b);   // the eye and a little lid around it
  } else {
    const [a, b] = MOUTH.corners, [u, l] = MOUTH.lips;
    if (!span(a, b) || !pts[u] || !pts[l]) return null;
    c = [(pts[a][0] + pts[b][0]) / 2, (pts[u][1] + pts[l][1]) / 2];
    width = 1.6 * span(a, b);   // the lips and a little cheek
  }
  const w = Math.round(Math.min(width, photo.width)), h = Math.round(Math.min(0.75 * width, photo.height));
  if (w < 32 || h < 24) return null;
  const x = Math.round(Math.min(Math.max(c[0] - w / 2, 0), photo.width - w));
  const y = Math.round(Math.min(Math.max(c[1] - h / 2, 0), photo.height - h));
  const bitmap = await createImageBitmap(photo.file);
  try {
    // Brought up to a close-up's size (the jobs' thresholds are set on
    // close-ups, ~600 px and more across); never down.
    const scale = Math.max(1, 640 / w);
    const canvas = new OffscreenCanvas(Math.round(w * scale), Math.round(h * scale));
    const g = canvas.getContext('2d');
    g.imageSmoothingQuality = 'high';
    g.drawImage(bitmap, x, y, w, h, 0, 0, canvas.width, canvas.height);
    const blob = await canvas.convertToBlob({ type: 'image/png' });
    return { buffer: await blob.arrayBuffer(), box: { x, y, w, h } };
  } finally {
    bitmap.close();
  }
}

// An eye photo runs the iris synthesis in the worker and dresses both
// eyeballs; a smile photo makes the teeth texture. Errors go to the banner;
// the photo keeps its role (and its clicks), the textures stay as they were.
export async function setPhotoRole(photo, role) {
  const state = document.body.dataset.state;
  if (state === 'working' || state === 'loading' || app.startupFailed) { renderPhotos(); return; }
  clearError();
  // (Before the photo's own iris is dropped: the head's may come from it.)
  const viaViews = role === 'eye' && eyeFromViews(photo);
  if (!viaViews) dropRoleTexture(photo);
  photo.role = role;
  photo.roleNote = '';
  photo.roleFailed = false;
  photo.eyeFromViews = false;
  if (viaViews) return findEyeInViews(photo);
  if (role === 'face') {
    renderPhotos();
    setStatus(photo.name + ' is a face photo again: it textures the skin.');
    return;
  }
  if (clicker.photo === photo) closeClicker();
  const eye = role === 'eye';
  const job = beginJob(eye ? 'eye photo' : 'smile photo');
  if (!job) { renderPhotos(); return; }
  photo.roleNote = eye ? 'finding the iris…' : 'making the teeth texture…';
  renderPhotos();
  setStatus((eye ? 'Synthesizing the iris from ' : 'Making the teeth texture from ') + photo.name + '…');
  const t0 = performance.now();
  let result;
  try {
    // A whole face (its points found): the eye or mouth is cut out of it;
    // a close-up (no face found in it) goes as it is.
    const cut = await closeUpFromFace(photo, eye).catch(() => null);
    photo.roleCrop = cut ? cut.box : null;
    const buffer = cut ? cut.buffer : await photo.file.arrayBuffer();
    result = await runJob({ type: eye ? 'eye' : 'smile', name: photo.name, buffer }, [buffer]);
  } catch (e) {
    result = { ok: false, message: photo.name + ': ' + (e && e.cancelled ? 'cancelled' : e && e.message ? e.message : e) };
  }
  const wallMs = performance.now() - t0;
  if (!live(job)) { photo.roleNote = 'cancelled'; renderPhotos(); return; }
  endJob(job);
  if (photo.role !== role || !app.photos.includes(photo)) { renderPhotos(); return; }
  if (!result.ok) {
    photo.roleFailed = true;
    photo.roleNote = eye ? 'no iris found' : 'no teeth found';
    renderPhotos();
    setStatus(photo.name + ': ' + photo.roleNote + '; the ' + (eye ? 'eyes' : 'teeth') + ' keep their texture.');
    // The worker's message starts with the photo's name.
    // The core's refusals of a photo that is no close-up say what one is.
    const message = result.message || photo.name + ': ' + result.code;
    const cutNote = photo.roleCrop ? ' (looked for in the ' + (eye ? 'eye' : 'mouth') + ' found in the face, ' +
                                     photo.roleCrop.w + '×' + photo.roleCrop.h + ' px)' : '';
    const hint = cutNote + (/close-up/.test(message) && !photo.roleCrop ? '.'
      : eye ? '. An eye photo is a close-up of one open eye, the iris near the middle.'
        : '. A smile photo shows the front teeth, lips apart, filling most of the picture.');
    showError((eye ? 'Eye photo ' : 'Smile photo ') + message + hint);
    return;
  }
  // Only one eye photo and one smile photo at a time: the newest wins.
  for (const other of app.photos) {
    if (other !== photo && other.role === role) { other.role = 'face'; other.roleNote = ''; other.roleFailed = false; }
  }
  const entry = { name: photo.name, texture: result.texture, ms: result.ms, wallMs };
  if (eye) { entry.circle = result.circle; app.eyePhoto = entry; } else { app.smilePhoto = entry; }
  const from = photo.roleCrop ? ' from the ' + (eye ? 'eye' : 'mouth') + ' found in the face' : '';
  photo.roleNote = eye ? 'iris r ' + result.circle.radius.toFixed(0) + ' px' + from + ', on both eyes (' + Math.round(result.ms) + ' ms)'
    : 'teeth texture' + from + ' (' + Math.round(result.ms) + ' ms)';
  if (app.viewer && app.componentsData) showComponents(app.componentsData);
  renderPhotos();
  setStatus((eye ? 'Iris from ' : 'Teeth from ') + photo.name + ' in ' + (result.ms / 1000).toFixed(2) + ' s' +
            (app.componentsData ? '; shown with the subdivided head (Show eyes, teeth).' : '; shown once the head is fitted.'));
}
app.setPhotoRole = (index, role) => setPhotoRole(app.photos[index], role);

// A face photo (its face points found) that made the head shown from
// photos: its camera is known, so the iris is looked for where the head's
// eyeball projects into it (the texture job's finder,
// core/project/eye_from_views.h, restricted to this photo), which finds
// light irises the close-up finder misses.
function eyeFromViews(photo) {
  return !!(photo.detect && photo.detect.points && app.fit && app.fit.fromPhotos && photo.photosHead && photo.photosHead.used);
}

async function findEyeInViews(photo) {
  if (clicker.photo === photo) closeClicker();
  // The newest eye photo wins: an earlier one goes back to the face, and
  // the iris it gave (or one a project brought) gives way.
  for (const other of app.photos) {
    if (other !== photo && other.role === 'eye') { dropRoleTexture(other); other.role = 'face'; other.roleNote = ''; other.eyeFromViews = false; }
  }
  photo.eyeFromViews = true;
  // Looked for again, in this photo alone, whatever iris is shown now (one
  // found in another photo, or a close-up's given up above): the texture
  // job sends it as the photo to search (texture.js).
  if (app.eyePhoto) { app.eyePhoto = null; if (app.viewer && app.componentsData) showComponents(app.componentsData); }
  photo.roleNote = 'finding the iris in this photo with the head\'s cameras…';
  renderPhotos();
  await runTexture();
  if (photo.role !== 'eye' || !photo.eyeFromViews) { renderPhotos(); return; }
  const e = app.eyePhoto && app.eyePhoto.name === photo.name ? app.eyePhoto : null;
  photo.roleFailed = !e;
  photo.roleNote = e ? 'iris found in ' + photo.name + ' with the head\'s cameras, on both eyes'
    : 'no iris found in ' + photo.name + ' with the head\'s cameras: the eyes keep the generic iris';
  renderPhotos();
  if (!e && app.eyeNote) setStatus('The eyes keep the generic iris: ' + app.eyeNote);
  if (e) setStatus('The eyes\' colour is from ' + e.name + ', found with the head\'s cameras; ' + photo.name + ' stays one of the head\'s photos.');
}
