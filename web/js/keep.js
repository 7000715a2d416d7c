// Nothing lost (issue 39): the head on the page is kept in the browser's
// IndexedDB (keep_store.js) as it changes, and offered back after a reload
// or a crash, restored in one click without fitting (load_project_job).
//   - What is kept: the project file's bytes from save_project_job (the
//     fitted, and textured, head with its scan), and what that file does not
//     hold: the options, the photos (their files, roles, clicks, points
//     files, the detector's face points with the user's corrections) and a
//     thumbnail of the viewer. A scan and photos dropped before there is a
//     head are kept too, as an entry without a head (the scan file itself
//     while no head was fitted from it: a reload in the middle of its fit
//     gets it back), which the head made from them later takes over.
//   - When: right after a fit, a texture or an opened project (a new head is
//     saved at once, so a worker lost to Cancel can get it back), and a
//     moment after an option, a photo or a landmark click changed.
//   - Each fitted or opened head is one entry; texturing and options update
//     it; the newest MAX_HEADS are kept, each listed with Restore and Delete.
//   - A full storage says so in the card and never breaks the page.
// The worker loses its head when it is stopped (Cancel, out of memory):
// reviveHead() puts the kept bytes into the fresh worker, so the head shown
// stays exportable.
import { app, params, ui, onPageChange, setStatus } from './state.js';
import { forgetFit } from './fit.js';
import { runJob } from './worker_client.js';
import { openProject, projectParts } from './project.js';
import { loadScan } from './scan.js';
import { renderPhotos } from './photos.js';
import { setPhotoRole } from './photo_roles.js';
import { forgetTexture } from './texture.js';
import { deleteHead, getFile, hasFile, listHeads, putHead } from './keep_store.js';
import { photoCount } from './wording.js';
import { applyOptions, pageOptions, photoState, restorePhotos } from './project_inputs.js';

export const MAX_HEADS = 5;
const SAVE_DELAY_MS = Number(params.get('keep_delay_ms')) >= 0 && params.has('keep_delay_ms') ? Number(params.get('keep_delay_ms')) : 1500;
const OFF = params.get('keep') === '0';  // ?keep=0: neither saved nor offered

// The head kept now: {id, fit, texture (the app objects its bytes hold), bytes, photosKey}.
let current = null;
let timer = 0, saving = null, again = false;
const keep = app.keep = { saves: 0, lastSave: null, error: null, heads: [] };

const $ = (id) => document.getElementById(id);
const el = { card: $('keep-card'), offer: $('restore-offer'), offerText: $('restore-text'), restore: $('btn-restore'),
             later: $('btn-restore-later'), list: $('keep-list'), note: $('keep-note') };

function when(t) {
  const d = new Date(t), now = new Date();
  const time = d.toLocaleTimeString([], { hour: '2-digit', minute: '2-digit' });
  return d.toDateString() === now.toDateString() ? 'today at ' + time : d.toLocaleDateString([], { day: 'numeric', month: 'short' }) + ', ' + time;
}

const baseName = (name) => String(name || 'head').replace(/\.likeness\.glb$/i, '').replace(/\.[^.]*$/, '');

// A small PNG of the viewer's centre. The viewer draws only when something
// changed and its canvas keeps no drawing buffer after a frame is shown, so
// a redraw is asked for and the canvas read in the frame that draws it.
function thumbnail() {
  return new Promise((resolve) => {
    const v = app.viewer;
    if (!v) { resolve(''); return; }
    const n0 = v.frames_drawn();
    v.set_point_size(Number(ui.pointSize.value));  // marks the scene changed: one more frame
    let tries = 0;
    const look = () => {
      if (v.frames_drawn() === n0 && ++tries < 30) { requestAnimationFrame(look); return; }
      try {
        const c = ui.canvas, side = Math.min(c.width, c.height);
        const t = document.createElement('canvas');
        t.width = t.height = 96;
        t.getContext('2d').drawImage(c, (c.width - side) / 2, (c.height - side) / 2, side, side, 0, 0, 96, 96);
        resolve(t.toDataURL('image/png'));
      } catch (e) {
        resolve('');
      }
    };
    requestAnimationFrame(look);
  });
}

// A photo's first frame as a 96-px square thumbnail (an entry without a head).
async function photoThumbnail(photo) {
  try {
    const b = await createImageBitmap(photo.file);
    const t = document.createElement('canvas'), side = Math.min(b.width, b.height);
    t.width = t.height = 96;
    t.getContext('2d').drawImage(b, (b.width - side) / 2, (b.height - side) / 2, side, side, 0, 0, 96, 96);
    b.close();
    return t.toDataURL('image/png');
  } catch (e) {
    return '';
  }
}

// What the project file does not hold: options and photos (project_inputs.js).
function pageState() {
  return { options: pageOptions(), photos: app.photos.map(photoState) };
}
const fileKey = (f) => f.name + ':' + f.size + ':' + f.lastModified;
const photosKey = () => app.photos.map((p) => fileKey(p.file)).join('|');
// The dropped scan file while no head is fitted from it (a project's scan is
// in its bytes); the key of an entry without a head.
const scanFile = () => (app.scan && app.scan.file) || null;
const inputsKey = (scan = scanFile()) => photosKey() + '#' + (scan ? fileKey(scan) : '');
// "scan and 2 photos" (an entry without a head)
function inputsText(h) {
  const n = (h.page.photos || []).length;
  return [h.scanName ? 'scan' : '', n ? photoCount(n) : ''].filter(Boolean).join(' and ');
}

export function scheduleSave(delay = SAVE_DELAY_MS) {
  if (OFF || (!app.fit && !app.photos.length && !scanFile())) return;
  clearTimeout(timer);
  timer = setTimeout(() => { timer = 0; saveNow(); }, delay);
}

// Saves the head shown; a call while one runs makes one more afterwards.
export function saveNow() {
  if (saving) { again = true; return saving; }
  saving = save().catch((e) => say(e)).finally(() => {
    saving = null;
    if (again) { again = false; scheduleSave(0); }
  });
  return saving;
}

function say(e) {
  keep.error = e && e.message ? e.message : String(e);
  el.note.classList.add('bad');
  el.note.textContent = e && e.quota
    ? 'This browser\'s storage for the page is full, so the head is not kept: delete earlier heads below, free space in ' +
      'the browser\'s site settings, or use Save project to keep it in a file.'
    : 'The head could not be kept in this browser (' + keep.error + '); use Save project to keep it in a file.';
}

// A scan and photos without a head: one entry of their files and points,
// no project (photosOnly: its historical name; scanName when it has a scan).
async function saveInputs() {
  const scan = scanFile();
  if (!app.photos.length && !scan) return;
  if (current && current.fit) current = null;  // the head is gone (Reset, a new scan): the inputs start an entry of their own
  if (!current) current = { id: newId(), fit: null, texture: null, bytes: null, photosKey: null };
  const key = inputsKey();
  const whole = key !== current.photosKey || !(await hasFile(current.id));
  const file = whole ? { bytes: null, photos: app.photos.map((p) => p.file), scan } : null;
  const first = app.photos[0];
  const head = { id: current.id, name: baseName(scan ? scan.name : first.name), photosOnly: true, scanName: scan ? scan.name : '',
                 savedAt: Date.now(), thumb: scan ? await thumbnail() : await photoThumbnail(first),
                 size: app.photos.reduce((n, p) => n + p.file.size, 0) + (scan ? scan.size : 0),
                 textured: false, vertices: 0, page: pageState() };
  await putHead(head, file);
  current.photosKey = key;
  await saved(head, !!file);
}
const newId = () => 'h' + Date.now().toString(36) + Math.random().toString(36).slice(2, 6);

async function save() {
  const fit = app.fit, texture = app.texture;
  // Inputs need no worker: kept even while their fit runs.
  if (!fit) {
    await saveInputs();
    return;
  }
  // A job may change the worker's head under us; the animation poses it.
  if (document.body.dataset.state === 'working' || (app.animation && app.animation.running)) { scheduleSave(); return; }
  const fresh = !current || current.fit !== fit;
  let bytes = null;
  const eye = app.eyePhoto, smile = app.smilePhoto;
  if (fresh || current.texture !== texture || current.eyePhoto !== eye || current.smilePhoto !== smile) {
    // With the eyes' and teeth's textures shown (a head opened from a file
    // keeps them without their photos).
    const r = await runJob({ type: 'saveProject', parts: projectParts() }, []);
    if (app.fit !== fit || app.texture !== texture || app.eyePhoto !== eye || app.smilePhoto !== smile) { scheduleSave(0); return; }  // changed meanwhile
    if (!r.ok) throw new Error(r.message || r.code);
    bytes = r.bytes;
  }
  // A head made from kept photos takes their entry over.
  if (fresh) current = current && !current.fit ? Object.assign(current, { fit, photosKey: null }) : { id: newId(), fit, photosKey: null };
  if (bytes) Object.assign(current, { bytes, texture, eyePhoto: eye, smilePhoto: smile });
  const key = photosKey();
  const whole = bytes || key !== current.photosKey || !(await hasFile(current.id));
  const file = whole ? { bytes: current.bytes, photos: app.photos.map((p) => p.file) } : null;
  const head = { id: current.id, name: baseName(fit.name), savedAt: Date.now(), thumb: await thumbnail(),
                 size: current.bytes.byteLength, textured: !!current.texture,
                 vertices: fit.meshes.levels.length ? fit.meshes.levels[fit.meshes.levels.length - 1].vertexCount : 0,
                 page: pageState() };
  await putHead(head, file);
  current.photosKey = key;
  await saved(head, !!file);
}

// Other tabs of the page list the same store: each write or delete here
// tells them to list it again (a head deleted in one tab is gone in all).
const others = self.BroadcastChannel ? new BroadcastChannel('likeness-keep') : null;
const tellOthers = () => { if (others) others.postMessage('changed'); };

async function saved(head, wroteFile) {
  keep.saves++;
  keep.lastSave = { id: head.id, savedAt: head.savedAt, size: head.size, wroteFile, photosOnly: !!head.photosOnly };
  keep.error = null;
  el.note.classList.remove('bad');
  el.note.textContent = 'Kept in this browser ' + when(head.savedAt) + ': a reload or a crash loses nothing.';
  await prune();
  tellOthers();
}

// The newest MAX_HEADS stay; older ones go.
async function prune() {
  const heads = await listHeads();
  for (const h of heads.slice(MAX_HEADS)) if (!current || h.id !== current.id) await deleteHead(h.id);
  await renderList();
}

// Lists the kept heads. Calls overlap (a save's prune, a Delete, another
// tab's change): a read begun before a Delete committed would list the
// deleted head again after the Delete's own refresh, so only the newest
// call's answer is shown.
let listing = 0;
export async function renderList() {
  const mine = ++listing;
  let heads = [];
  try { heads = await listHeads(); } catch (e) { say(e); }
  if (mine !== listing) return heads;
  keep.heads = heads.map((h) => ({ id: h.id, name: h.name, savedAt: h.savedAt, size: h.size, textured: h.textured }));
  el.list.textContent = '';
  for (const h of heads) {
    const li = document.createElement('li');
    li.dataset.id = h.id;
    li.classList.toggle('current', !!current && current.id === h.id);
    const img = document.createElement('img');
    img.alt = '';
    if (h.thumb) img.src = h.thumb;
    const text = document.createElement('div');
    text.className = 'keep-text';
    // Inputs whose head was just made are kept as that head once its
    // project file is written (a second or two): say so meanwhile.
    const keeping = h.photosOnly && !!app.fit && !!current && current.id === h.id && !current.fit;
    text.textContent = h.name + (keeping ? ' (keeping the head made from them\u2026)'
      : h.photosOnly ? ' (' + inputsText(h) + ', no head yet)' : h.textured ? ' (textured)' : '');
    const meta = document.createElement('div');
    meta.className = 'keep-meta';
    meta.textContent = when(h.savedAt) + ' · ' + (h.size / 1048576).toFixed(1) + ' MB';
    text.append(meta);
    const restore = document.createElement('button');
    restore.type = 'button';
    restore.className = 'small needs-idle keep-restore';
    restore.textContent = 'Restore';
    restore.setAttribute('aria-label', 'Restore ' + h.name + ' from ' + when(h.savedAt));
    restore.addEventListener('click', () => restoreHead(h.id));
    const del = document.createElement('button');
    del.type = 'button';
    del.className = 'small keep-delete';
    del.textContent = 'Delete';
    del.setAttribute('aria-label', 'Delete ' + h.name + ' from ' + when(h.savedAt) + ' from this browser');
    del.addEventListener('click', () => removeHead(h.id));
    li.append(img, text, restore, del);
    el.list.append(li);
  }
  el.card.hidden = heads.length === 0 && !keep.error;
  const busy = document.body.dataset.state === 'working' || document.body.dataset.state === 'loading';
  for (const b of el.list.querySelectorAll('.needs-idle')) b.disabled = busy;
  return heads;
}

async function removeHead(id) {
  try {
    await deleteHead(id);
    if (current && current.id === id) current = null;  // the next change keeps the head again, as a new entry
    tellOthers();
  } catch (e) { say(e); }
  if (keep.offered === id) el.offer.hidden = true;
  await renderList();
}

// Shows the kept head `id` again: its project file through Open project
// (no fit), then its options and photos.
export async function restoreHead(id) {
  const state = document.body.dataset.state;
  if (state === 'working' || state === 'loading' || app.startupFailed) return;
  el.offer.hidden = true;
  const t0 = performance.now();
  let head, stored;
  try {
    head = (await listHeads()).find((h) => h.id === id);
    stored = head && await getFile(id);
  } catch (e) { say(e); return; }
  if (!head || !stored) { setStatus('That head is no longer kept in this browser.'); await renderList(); return; }
  if (head.photosOnly) {
    if (app.fit) forgetFit();
    current = { id, fit: null, texture: null, bytes: null, photosKey: null };
  } else {
    const file = new File([stored.bytes], head.name + '.likeness.glb', { type: 'model/gltf-binary' });
    await openProject(file);
    if (!app.project || app.project.name !== file.name || !app.fit) return;  // refused: openProject said why
    current = { id, fit: app.fit, texture: app.texture, eyePhoto: app.eyePhoto, smilePhoto: app.smilePhoto,
               bytes: stored.bytes, photosKey: null };
  }
  applyOptions(head.page.options);
  restorePhotos(head.page.photos || [], stored.photos || []);
  current.photosKey = head.photosOnly ? inputsKey() : photosKey();
  renderPhotos();
  app.restored = { id, savedAt: head.savedAt, ms: performance.now() - t0 };
  // Eye and smile photos make their textures again (small jobs, no fit); a
  // face photo set to "Eye (iris)" gave the iris with the head's cameras,
  // which the kept head brings back without them (its eyes are the project's).
  for (const p of head.page.photos || []) {
    const photo = app.photos.find((x) => x.name === p.name);
    if (photo && photo.eyeFromViews) { photo.role = 'eye'; photo.roleNote = 'the eyes\' colour came from the head\'s photos'; continue; }
    if (photo && p.role && p.role !== 'face') await setPhotoRole(photo, p.role);
  }
  if (!(head.photosOnly && stored.scan)) setStatus(head.photosOnly
    ? 'Restored ' + photoCount(app.photos.length) + ' as kept ' + when(head.savedAt) + (app.photos.length === 1 ? ', with its face points: add more photos, or make the head from it.' : ', with their face points: add more, or make the head from them.')
    : 'Restored ' + head.name + ' as kept ' + when(head.savedAt) + ', in ' + Math.round(performance.now() - t0) +
      ' ms without fitting: animate it, texture it or export it.');
  await renderList();
  // A kept scan is loaded as if dropped again (Auto-run fits it, as it did
  // before the reload); the entry goes on with it.
  if (head.photosOnly && stored.scan) {
    const f = stored.scan instanceof File ? stored.scan : new File([stored.scan], head.scanName || 'scan.ply');
    current.photosKey = inputsKey(f);  // what inputsKey() gives once it is loaded
    await loadScan(f);
  }
}

// After a reload: the newest kept head is offered back.
export async function offerRestore() {
  if (OFF) return;
  const heads = await renderList();
  if (!heads.length || app.fit || app.photos.length || scanFile()) return;
  const h = heads[0];
  keep.offered = h.id;
  el.offerText.textContent = h.photosOnly
    ? 'Restore your ' + inputsText(h) + ' from ' + when(h.savedAt) + '? (no head was made from ' +
      ((h.page.photos || []).length + (h.scanName ? 1 : 0) === 1 ? 'it' : 'them') + ' yet)'
    : 'Restore your head from ' + when(h.savedAt) + '? (' + h.name + (h.textured ? ', textured' : '') + ')';
  el.offer.hidden = false;
}

// The worker was stopped with the head in it: the kept bytes go into the
// fresh one. True when it is on its way (exports queue behind it).
function reviveHead() {
  if (!current || current.fit !== app.fit || !current.bytes) return false;
  if (current.texture !== app.texture) forgetTexture();  // the bytes have the older (or no) texture
  const fit = app.fit, bytes = current.bytes.slice();
  setTimeout(() => {  // after the worker is replaced
    runJob({ type: 'openProject', name: fit.name, buffer: bytes.buffer }, [bytes.buffer]).then((r) => {
      if (!r.ok && app.fit === fit) forgetFit('The head could not be put back into the restarted core: fit again.');
      // The checks' distance map (exported from the worker) is measured again.
      else if (r.ok && fit.quality && fit.quality.ok) runJob({ type: 'quality' }, []).catch(() => {});
    }, () => {});
  }, 0);
  return true;
}

export function wireKeep() {
  if (OFF) return;
  app.reviveHead = reviveHead;
  keep.refresh = renderList;
  if (others) others.onmessage = () => { renderList(); };
  el.restore.addEventListener('click', () => restoreHead(keep.offered));
  el.later.addEventListener('click', () => { el.offer.hidden = true; });
  // A head that became the shown one (fit, texture, opened) is kept at once;
  // anything else a moment later.
  onPageChange((snap) => {
    if (app.fit || app.photos.length || scanFile()) el.offer.hidden = true;  // a head or inputs are on the page: nothing to offer
    if (snap.state === 'working' || snap.state === 'loading') return;
    if (app.fit && current && !current.fit) renderList();  // its inputs' entry: "keeping the head"
    if (app.fit && (!current || current.fit !== app.fit || current.texture !== app.texture ||
                    current.eyePhoto !== app.eyePhoto || current.smilePhoto !== app.smilePhoto)) scheduleSave(0);
    else if (!app.fit && scanFile() && (!current || current.photosKey !== inputsKey())) scheduleSave(0);  // before its fit starts
    else if (app.fit || app.photos.length) scheduleSave();
  });
  for (const c of [ui.level, ui.autoFit, ui.showComponents, ui.fullDetail, ui.scanUp, ui.scanFacing]) c.addEventListener('change', () => scheduleSave());
  for (const c of [ui.clickerCanvas, ui.clickerUndo, ui.clickerSkip, ui.clickerClear, ui.photoList]) {
    c.addEventListener('click', () => scheduleSave());
  }
  ui.photoList.addEventListener('change', () => scheduleSave());
}
