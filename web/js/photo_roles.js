// Photo roles (tarini2002 Sec. 4): a photo set to "Eye (iris)" makes the
// eyeballs' iris texture, one set to "Smile (teeth)" the teeth texture; both
// run in the worker. Face photos (the default) texture the skin.
import { app, beginJob, clearError, endJob, live, setStatus, showError } from './state.js';
import { runJob } from './worker_client.js';
import { renderPhotos } from './photos.js';
import { clicker, closeClicker } from './clicker.js';
import { showComponents } from './head_view.js';

export const PHOTO_ROLES = [['face', 'Face (skin)'], ['eye', 'Eye (iris)'], ['smile', 'Smile (teeth)']];

// Forgets the iris / teeth texture this photo made (role changed, photo
// removed); the components go back to the generic textures.
export function dropRoleTexture(photo) {
  let changed = false;
  if (app.eyePhoto && app.eyePhoto.name === photo.name) { app.eyePhoto = null; changed = true; }
  if (app.smilePhoto && app.smilePhoto.name === photo.name) { app.smilePhoto = null; changed = true; }
  if (changed && app.viewer && app.componentsData) showComponents(app.componentsData);
}

// An eye photo runs the iris synthesis in the worker and dresses both
// eyeballs; a smile photo makes the teeth texture. Errors go to the banner;
// the photo keeps its role (and its clicks), the textures stay as they were.
export async function setPhotoRole(photo, role) {
  const state = document.body.dataset.state;
  if (state === 'working' || state === 'loading' || app.startupFailed) { renderPhotos(); return; }
  clearError();
  dropRoleTexture(photo);
  photo.role = role;
  photo.roleNote = '';
  photo.roleFailed = false;
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
    const buffer = await photo.file.arrayBuffer();
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
    const hint = /close-up/.test(message) ? '.'
      : eye ? '. An eye photo is a close-up of one open eye, the iris near the middle.'
        : '. A smile photo shows the front teeth, lips apart, filling most of the picture.';
    showError((eye ? 'Eye photo ' : 'Smile photo ') + message + hint);
    return;
  }
  // Only one eye photo and one smile photo at a time: the newest wins.
  for (const other of app.photos) {
    if (other !== photo && other.role === role) { other.role = 'face'; other.roleNote = ''; other.roleFailed = false; }
  }
  const entry = { name: photo.name, texture: result.texture, ms: result.ms, wallMs };
  if (eye) { entry.circle = result.circle; app.eyePhoto = entry; } else { app.smilePhoto = entry; }
  photo.roleNote = eye ? 'iris r ' + result.circle.radius.toFixed(0) + ' px, on both eyes (' + Math.round(result.ms) + ' ms)'
    : 'teeth texture (' + Math.round(result.ms) + ' ms)';
  if (app.viewer && app.componentsData) showComponents(app.componentsData);
  renderPhotos();
  setStatus((eye ? 'Iris from ' : 'Teeth from ') + photo.name + ' in ' + (result.ms / 1000).toFixed(2) + ' s' +
            (app.componentsData ? '; shown with the subdivided head (Show eyes, teeth).' : '; shown once the head is fitted.'));
}
app.setPhotoRole = (index, role) => setPhotoRole(app.photos[index], role);
