// The page's shared state: the URL parameters, the elements, window.likeness
// (the app's data, exposed for the browser tests and the console), the
// page's states (owned by page_state.js's PageState, applied here to
// document.body.dataset.state, the banner and the controls), the status
// line and the Pipeline rows. It imports only page_state.js, so every other
// module can use it while they are evaluated. The states are described in
// page_state.js: loading, ready, working, done, error.
import { controlsFor, PageState } from './page_state.js';

export const params = new URLSearchParams(location.search);

const $ = (id) => document.getElementById(id);
export const ui = {
  canvas: $('canvas'), overlay: $('viewer-overlay'), overlayText: $('overlay-text'),
  status: $('status'), banner: $('error-banner'), bannerText: $('error-text'),
  dismiss: $('error-dismiss'), dropZone: $('drop-zone'), fileInput: $('file-input'),
  fileList: $('file-list'), reset: $('btn-reset'), generic: $('btn-generic'),
  pointSize: $('point-size'), maxSize: $('max-size'), sample: $('btn-sample'), samplePhotos: $('btn-sample-photos'), cancel: $('btn-cancel'), wireframe: $('wireframe'),
  fit: $('btn-fit'), autoFit: $('auto-fit'), scanUp: $('scan-up'), scanFacing: $('scan-facing'), fitTotal: $('fit-total'), fitView: $('fit-view'),
  level: $('level'), showPoints: $('show-points'), showDistance: $('show-distance'), animate: $('animate'), animStats: $('anim-stats'),
  fullDetail: $('full-detail'),
  expressions: $('expressions'), exprControls: $('expr-controls'), exprGroup: $('expr-group'), exprSliders: $('expr-sliders'),
  exprStats: $('expr-stats'), talk: $('btn-talk'), sayText: $('say-text'), sayLang: $('say-lang'),
  follow: $('follow-face'), followStatus: $('follow-status'), followVideo: $('follow-video'), cameraOn: $('camera-on'),
  fitNotes: $('fit-notes'), fitQuality: $('fit-quality'), qualityTitle: $('quality-title'), qualitySummary: $('quality-summary'),
  qualityList: $('quality-list'),
  showComponents: $('show-components'),
  exportObj: $('btn-export-obj'), exportPly: $('btn-export-ply'), exportGlb: $('btn-export-glb'), exportTextured: $('btn-export-textured'),
  exportMap: $('btn-export-map'), distanceLegend: $('distance-legend'),
  saveProject: $('btn-save-project'), projectInput: $('project-input'),
  photoList: $('photo-list'), photoCount: $('photo-count'), texture: $('btn-texture'),
  photosHead: $('btn-photos-head'), photosHeadTotal: $('photos-head-total'), textureTotal: $('texture-total'),
  viewerPane: document.querySelector('.viewer-pane'), clicker: $('clicker'), clickerPrompt: $('clicker-prompt'),
  clickerCanvas: $('clicker-canvas'), clickerList: $('clicker-list'), clickerUndo: $('clicker-undo'),
  clickerSkip: $('clicker-skip'), clickerClear: $('clicker-clear'), clickerClose: $('clicker-close'),
  clickerSavePoints: $('clicker-save-points'), clickerNote: $('clicker-note'),
};

// Exposed for the browser test and for debugging from the console.
export const app = window.likeness = {
  startedAt: performance.now(),
  loadMs: null,          // page start -> viewer and worker up, head drawn
  timings: {},           // ms since page start: viewerRuntime (its wasm compiled, before its main), viewerModule, firstFrame, worker
  viewer: null,
  worker: null,
  workerThreads: null,   // {variant: 'threads'|'single', threads}: which core the worker runs
                         // (threads when the page is cross-origin isolated, see worker.js)
  model: null,           // {name, kind, vertexCount, triangleCount} shown now
  photos: [],            // checked photos, for texturing: [{name, file, width, height, url (thumbnail),
                         //   filePoints (Float64Array u v X Y Z from a points file, or null), pointsName,
                         //   clicks (landmark id -> {u, v} or 'skip'), calib (the last calibration), sent}]
  texture: null,         // the last texture: {uvs, skin {width, height, channels, pixels}, steps, textureMs, wallMs}
  lastError: null,
  warmup: null,          // the start-up warm-up worker: {state: running|done|failed|gave up, variant, ms, fitMs}
  startupFailed: false,  // the viewer or the core could not start
  scan: null,            // {file, display}: the loaded scan, kept to fit it and draw it under the fit
  project: null,         // {name, loadMs, wallMs} when the head shown came from a project file
  photosHead: null,      // the last head from photos: {trigger: 'auto'|'button', ok, photos, focalPx, wallMs, message}
  fit: null,             // the last fit: {name, stages, meshes, fitMs, parseMs, wallMs, quality}; its
                         // multiresolution head lives in the worker (animation, export)
  shownStage: null,      // which fit mesh is drawn: align|local_fit|global_fit|subdivide
  animation: { running: false, frames: 0, fps: 0, updateMs: 0 },
  expressions: null,     // expressions.js: the shape weights, the baked shapes' level, blend timings, talking
  downloads: [],         // [{name, size}] files handed to the browser (tests)
  componentsData: null,  // the worker's last components (meshes, generic eye and teeth textures)
  eyePhoto: null,        // {name, texture, circle, ms}: the iris from a photo of role "eye", on both eyeballs
  smilePhoto: null,      // {name, texture, ms}: the teeth texture from a photo of role "smile"
  // What the shown components wear: eyes/teeth 'generic', 'photo:<name>' or
  // 'none' (untextured), teethTextured true once the teeth have a texture.
  componentTextures: { eyes: 'none', teeth: 'none', teethTextured: false },
};

// The checks' distance map of the finest level (fit.quality.faceToScan.colors),
// or null when the last checks gave none.
export function distanceColors() {
  const q = app.fit && !app.fit.fromPhotos && app.fit.quality;  // a head from photos: no scan, no map
  const colors = q && q.ok && q.faceToScan && q.faceToScan.colors;
  return colors && colors.length ? colors : null;
}

// The page's states have one owner (page_state.js); this applies them to
// the page: data-state, the banner, and what each control allows.
const pageListeners = [];
// f(snapshot) after every change of the page's state (keep.js saves then).
export function onPageChange(f) { pageListeners.push(f); }
export const page = new PageState({
  rest: () => (app.model ? 'done' : 'ready'),
  onChange: (snap) => { applyState(snap); for (const f of pageListeners) f(snap); },
  onCancel: () => { if (app.cancelJobs) app.cancelJobs(); },
});
app.page = page;

function applyState(snap) {
  document.body.dataset.state = snap.state;
  ui.banner.hidden = !snap.banner;
  if (snap.banner) ui.bannerText.textContent = snap.message;
  const c = controlsFor({ state: snap.state, fatal: snap.fatal || app.startupFailed, scanFile: !!(app.scan && (app.scan.file || app.scan.kept)),
                          fit: !!app.fit, texture: !!app.texture, photos: app.photos.length,
                          distance: !!distanceColors(), scan: !!app.scan,
                          facePoints: app.photos.filter((p) => (p.role || 'face') === 'face' && p.detect && p.detect.points).length });
  ui.fileInput.disabled = !c.files;
  ui.reset.disabled = !c.reset;
  ui.generic.disabled = !c.generic;
  ui.sample.disabled = !c.sample;
  ui.samplePhotos.disabled = !c.sample;
  ui.pointSize.disabled = !c.pointSize;
  ui.wireframe.disabled = !c.wireframe;
  ui.dropZone.classList.toggle('busy', snap.state === 'working');
  ui.cancel.hidden = !c.cancel;
  ui.fit.disabled = !c.fit;
  ui.scanUp.disabled = ui.scanFacing.disabled = !c.scanAxes;
  ui.photosHead.disabled = !c.photosHead;
  ui.exportObj.disabled = !c.exportObj;
  ui.exportPly.disabled = !c.exportPly;
  ui.exportGlb.disabled = !c.exportGlb;
  ui.animate.disabled = !c.animate;
  ui.fullDetail.disabled = !c.fullDetail;
  ui.exprControls.disabled = !c.expressions;
  ui.level.disabled = !c.level;
  ui.showPoints.disabled = !c.showPoints;
  ui.showComponents.disabled = !c.showComponents;
  ui.texture.disabled = !c.texture;
  ui.exportTextured.disabled = !c.exportTextured;
  ui.exportMap.disabled = !c.exportMap;
  ui.saveProject.disabled = !c.saveProject;
  ui.projectInput.disabled = !c.openProject;
  for (const role of ui.photoList.querySelectorAll('select.photo-role')) role.disabled = !c.photoRoles;
  for (const b of document.querySelectorAll('.needs-idle')) b.disabled = !c.restore;
}
// A job starts (null: another runs, or the page cannot be used now); end it
// with endJob(job); live(job): not cancelled or replaced meanwhile.
export function beginJob(name) { return page.begin(name); }
export function endJob(job) { return page.end(job); }
export function live(job) { return page.isLive(job); }
// What the page holds changed: the controls follow.
export function refreshControls() { page.refresh(); }

export function setStatus(text) { ui.status.textContent = text; }

// An error ends the running job, if any; what was shown stays shown.
export function showError(message) {
  app.lastError = message;
  page.fail(message);
}

export function clearError() { page.dismiss(); }

// Without the viewer or the core nothing works: every control stays off.
export function fatalStartup(message) {
  app.startupFailed = true;
  ui.overlay.hidden = false;
  ui.overlayText.textContent = 'The app could not start.';
  setStatus('Likeness could not start in this browser.');
  ui.overlay.classList.add('failed');
  app.lastError = message;
  page.startFailed(message);
}

// ---- the Pipeline rows (index.html's #stages li[data-stage]) ----------------
export function stageItem(stage) { return document.querySelector('#stages li[data-stage="' + stage + '"]'); }

export function setStage(stage, tag, fraction, cls) {
  const li = stageItem(stage);
  if (!li) return;
  li.querySelector('.stage-tag').textContent = tag;
  if (fraction !== undefined) li.querySelector('progress').value = fraction;
  li.classList.remove('active', 'complete', 'failed');
  if (cls) li.classList.add(cls);
}
