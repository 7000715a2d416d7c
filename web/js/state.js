// The page's shared state: the URL parameters, the elements, window.likeness
// (the app's data, exposed for the browser tests and the console), the
// state machine on document.body.dataset.state, the status line, the error
// banner and the Pipeline rows. It imports nothing, so every other module
// can use it while they are evaluated.
//
// document.body.dataset.state is always one of:
//   loading  the modules start and the generic head is not drawn yet
//   ready    viewer and worker are up, nothing loaded yet
//   working  a job runs in the worker
//   done     the last job's result is shown
//   error    the last action failed; the message is in #error-banner and the
//            previous model is still shown

export const params = new URLSearchParams(location.search);

const $ = (id) => document.getElementById(id);
export const ui = {
  canvas: $('canvas'), overlay: $('viewer-overlay'), overlayText: $('overlay-text'),
  status: $('status'), banner: $('error-banner'), bannerText: $('error-text'),
  dismiss: $('error-dismiss'), dropZone: $('drop-zone'), fileInput: $('file-input'),
  fileList: $('file-list'), reset: $('btn-reset'), generic: $('btn-generic'),
  pointSize: $('point-size'), maxSize: $('max-size'), sample: $('btn-sample'), cancel: $('btn-cancel'), wireframe: $('wireframe'),
  fit: $('btn-fit'), autoFit: $('auto-fit'), fitTotal: $('fit-total'), fitView: $('fit-view'),
  level: $('level'), showPoints: $('show-points'), showDistance: $('show-distance'), animate: $('animate'), animStats: $('anim-stats'),
  fullDetail: $('full-detail'),
  fitNotes: $('fit-notes'), fitQuality: $('fit-quality'), qualityTitle: $('quality-title'), qualitySummary: $('quality-summary'),
  qualityList: $('quality-list'),
  showComponents: $('show-components'),
  exportObj: $('btn-export-obj'), exportPly: $('btn-export-ply'), exportTextured: $('btn-export-textured'),
  exportMap: $('btn-export-map'), distanceLegend: $('distance-legend'),
  saveProject: $('btn-save-project'), projectInput: $('project-input'),
  photoList: $('photo-list'), photoCount: $('photo-count'), texture: $('btn-texture'), textureTotal: $('texture-total'),
  viewerPane: document.querySelector('.viewer-pane'), clicker: $('clicker'), clickerPrompt: $('clicker-prompt'),
  clickerCanvas: $('clicker-canvas'), clickerList: $('clicker-list'), clickerUndo: $('clicker-undo'),
  clickerSkip: $('clicker-skip'), clickerClear: $('clicker-clear'), clickerClose: $('clicker-close'),
};

// Exposed for the browser test and for debugging from the console.
export const app = window.likeness = {
  startedAt: performance.now(),
  loadMs: null,          // page start -> viewer and worker up, head drawn
  timings: {},           // ms since page start: viewerModule, firstFrame, worker
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
  fit: null,             // the last fit: {name, stages, meshes, fitMs, parseMs, wallMs, quality}; its
                         // multiresolution head lives in the worker (animation, export)
  shownStage: null,      // which fit mesh is drawn: align|local_fit|global_fit|subdivide
  animation: { running: false, frames: 0, fps: 0, updateMs: 0 },
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
  const q = app.fit && app.fit.quality;
  const colors = q && q.ok && q.faceToScan && q.faceToScan.colors;
  return colors && colors.length ? colors : null;
}

let stateBeforeError = 'ready';
// The state an error replaced (what clearing it goes back to).
export function stateUnderError() { return stateBeforeError; }

export function setState(state) {
  if (state !== 'error') stateBeforeError = state;
  document.body.dataset.state = state;
  const interactive = state !== 'loading' && !app.startupFailed;
  ui.fileInput.disabled = !interactive || state === 'working';
  ui.reset.disabled = !interactive;
  ui.generic.disabled = !interactive || state === 'working';
  ui.sample.disabled = !interactive || state === 'working';
  ui.pointSize.disabled = !interactive;
  ui.wireframe.disabled = !interactive;
  ui.dropZone.classList.toggle('busy', state === 'working');
  ui.cancel.hidden = state !== 'working';
  const fitting = state === 'working';
  ui.fit.disabled = !interactive || fitting || !app.scan || !app.scan.file;
  const haveFit = interactive && !fitting && !!app.fit;
  ui.exportObj.disabled = !haveFit;
  ui.exportPly.disabled = !haveFit;
  ui.animate.disabled = !haveFit;
  ui.fullDetail.disabled = !haveFit;
  ui.level.disabled = !haveFit;
  ui.showPoints.disabled = !haveFit;
  ui.showComponents.disabled = !haveFit;
  ui.texture.disabled = !haveFit || !app.photos.length;
  ui.exportTextured.disabled = !haveFit || !app.texture;
  ui.exportMap.disabled = !haveFit || !distanceColors();
  ui.saveProject.disabled = !haveFit;
  ui.projectInput.disabled = !interactive || state === 'working';
  for (const role of ui.photoList.querySelectorAll('select.photo-role')) role.disabled = !interactive || state === 'working';
}

export function setStatus(text) { ui.status.textContent = text; }

export function showError(message) {
  app.lastError = message;
  ui.bannerText.textContent = message;
  ui.banner.hidden = false;
  setState('error');
}

export function clearError() {
  ui.banner.hidden = true;
  if (document.body.dataset.state === 'error' && !app.startupFailed) setState(stateBeforeError);
}

// Without the viewer or the core nothing works: every control stays off.
export function fatalStartup(message) {
  app.startupFailed = true;
  ui.overlay.hidden = false;
  ui.overlayText.textContent = 'The app could not start.';
  setStatus('Likeness could not start in this browser.');
  ui.overlay.classList.add('failed');
  showError(message);
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
