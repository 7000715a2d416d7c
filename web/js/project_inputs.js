// What a kept head keeps of the page besides the head (issue 39): the
// options and the photos (files, roles, clicks, points files, the
// detector's face points with the user's drags). keep.js stores them in
// IndexedDB beside the project bytes; Save project puts them in the project
// file itself (version 3: core/project/project_file.h), so Open project,
// here or in another browser, gives the photo rows back without detecting
// or fitting again.
import { app, params, ui } from './state.js';
import { DETECTOR } from './landmarks.js';
import { AXES, showAxes } from './axes.js';

// A fit's thinning (?thin) and a texture's size (?texture_size) come from
// the address; a restored project brings its own where the address gives none.
export function pageOption(name) {
  const fromUrl = Number(params.get(name === 'thin' ? 'thin' : 'texture_size'));
  if (fromUrl > 0) return fromUrl;
  const kept = app.keptOptions && Number(app.keptOptions[name]);
  return kept > 0 ? kept : 0;
}

export function pageOptions() {
  return { level: ui.level.value, autoFit: ui.autoFit.checked, showComponents: ui.showComponents.checked,
           fullDetail: ui.fullDetail.checked, thin: pageOption('thin'), textureSize: pageOption('textureSize'),
           scanUp: ui.scanUp.value, scanFacing: ui.scanFacing.value };
}

export function applyOptions(o) {
  o = o || {};
  if (o.level !== undefined) ui.level.value = o.level;
  ui.autoFit.checked = o.autoFit !== false;
  ui.showComponents.checked = o.showComponents !== false;
  ui.fullDetail.checked = !!o.fullDetail;
  showAxes(ui.scanUp, ui.scanFacing, AXES.includes(o.scanUp) ? o.scanUp : '+y', AXES.includes(o.scanFacing) ? o.scanFacing : '+z');
  app.keptOptions = { thin: Number(o.thin) || 0, textureSize: Number(o.textureSize) || 0 };
}

// The detector's face points of a photo as kept: what it found, with the
// user's drags (corrected: the indices moved), or null while none are known.
export function keptDetect(p) {
  const d = p.detect;
  if (!d || !d.points || !['found', 'many'].includes(d.state)) return null;
  return { state: d.state, faces: d.faces, points: d.points.map((q) => (q ? [q[0], q[1]] : null)),
           corrected: d.corrected ? [...d.corrected] : [] };
}

// Kept face points as the page holds them again (no detection needed).
export function restoredDetect(k) {
  if (!k || !Array.isArray(k.points)) return null;
  const n = k.corrected && k.corrected.length;
  return { state: k.state, faces: k.faces, points: k.points, ms: 0, corrected: new Set(k.corrected || []),
           message: k.points.length + ' face points (kept' + (n ? ', ' + n + ' moved by hand' : '') + ')' };
}

// A photo's row without its file (IndexedDB keeps the file beside it).
export function photoState(p) {
  return { name: p.name, width: p.width, height: p.height, role: p.role || 'face', eyeFromViews: !!p.eyeFromViews, clicks: [...p.clicks.entries()],
           pointsName: p.pointsName || '', filePoints: p.filePoints ? Array.from(p.filePoints) : null, detect: keptDetect(p) };
}

// The photo rows again from kept states and their files; roles are set by
// the caller (an eye or smile photo's texture is a job of its own).
export function restorePhotos(states, files) {
  for (const p of app.photos) URL.revokeObjectURL(p.url);
  app.photos = states.map((p, i) => {
    const blob = files[i];
    if (!blob) return null;
    const f = blob instanceof File ? blob : new File([blob], p.name);
    return { name: p.name, file: f, width: p.width, height: p.height, url: URL.createObjectURL(f), role: 'face', eyeFromViews: !!p.eyeFromViews,
             filePoints: p.filePoints ? new Float64Array(p.filePoints) : null, pointsName: p.pointsName,
             clicks: new Map(p.clicks || []), calib: null, sent: null, detect: restoredDetect(p.detect) };
  }).filter(Boolean);
}

const MIME = (name) => (/\.png$/i.test(name) ? 'image/png' : 'image/jpeg');

// For Save project: {photos: [{name, role, bytes, points}], pageOptions}.
// points: the photo's likeness-landmarks JSON (the CLI's points file, as
// landmarks.js exports it, but unrounded so a restore gives the same
// numbers) with "corrected" (the indices dragged) and "faces"; '' without
// detected points. pageOptions: the options and each photo's other state.
export async function projectInputs() {
  const photos = [];
  for (const p of app.photos) {
    const d = keptDetect(p);
    const points = d ? JSON.stringify({ format: 'likeness-landmarks', version: 1, image: { name: p.name, width: p.width, height: p.height },
                                        detector: DETECTOR, points: d.points, corrected: d.corrected, faces: d.faces }) : '';
    photos.push({ name: p.name, role: p.role || 'face', bytes: new Uint8Array(await p.file.arrayBuffer()), points });
  }
  const rows = app.photos.map((p) => { const s = photoState(p); delete s.detect; return s; });
  return { photos, pageOptions: JSON.stringify({ options: pageOptions(), photos: rows }) };
}

// An opened project's inputs back on the page: its options and photo rows,
// the face points from the file (no detection). The eye and smile photos'
// textures came with the project's parts, so their roles are set as they
// are, without making the textures again. Returns the number of photos.
export function takeInputs(inputs) {
  if (!inputs || !inputs.photos || (!inputs.photos.length && !inputs.pageOptions)) return 0;
  let page = {};
  try { page = inputs.pageOptions ? JSON.parse(inputs.pageOptions) : {}; } catch (e) { page = {}; }
  if (page.options) applyOptions(page.options);  // a file made by `likeness photos` has none
  const rows = Array.isArray(page.photos) ? page.photos : [];
  const states = inputs.photos.map((ph, i) => {
    const row = rows.find((r) => r && r.name === ph.name) || rows[i] || {};
    let detect = null, doc = null;
    try { doc = ph.points ? JSON.parse(ph.points) : null; } catch (e) { doc = null; }
    if (doc && Array.isArray(doc.points)) {
      const faces = Number(doc.faces) || 1;
      detect = { state: faces > 1 ? 'many' : 'found', faces, points: doc.points, corrected: doc.corrected || [] };
    }
    const image = (doc && doc.image) || {};
    return { name: ph.name, width: row.width || image.width, height: row.height || image.height, clicks: row.clicks,
             eyeFromViews: !!row.eyeFromViews && ph.role === 'eye',
             pointsName: row.pointsName || '', filePoints: row.filePoints || null, detect };
  });
  restorePhotos(states, inputs.photos.map((ph) => new File([ph.bytes], ph.name, { type: MIME(ph.name) })));
  for (const p of app.photos) {
    const ph = inputs.photos.find((x) => x.name === p.name);
    p.role = ph && ph.role ? ph.role : 'face';
  }
  return app.photos.length;
}
