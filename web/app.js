// Likeness web app: wires the page to two WebAssembly modules.
//   likeness_viewer.js  (main thread) draws on #canvas with WebGL2 via SDL2.
//   worker.js -> likeness_worker.js  (Web Worker) runs the core's jobs.
// Files are read locally and transferred to the worker; nothing is fetched
// from anywhere but this page's own origin.
//
// document.body.dataset.state is always one of:
//   loading  the modules start and the generic head is not drawn yet
//   ready    viewer and worker are up, nothing loaded yet
//   working  a job runs in the worker
//   done     the last job's result is shown
//   error    the last action failed; the message is in #error-banner and the
//            previous model is still shown
'use strict';

(function () {
  const params = new URLSearchParams(location.search);
  // Largest scan file accepted. Parsing needs up to ~5x the file's size in
  // wasm memory (the bytes, then double-precision positions and the arrays
  // handed back; 2 GiB heap at most): a 408 MB binary PLY of 34M points ran
  // the worker out of memory, 150 MB (12.5M points) loaded. Refuse early with
  // a clear message instead. ?max_mb=N overrides.
  const DEFAULT_MAX_SCAN_MB = 256;
  const maxScanMb = Number(params.get('max_mb')) > 0 ? Number(params.get('max_mb')) : DEFAULT_MAX_SCAN_MB;
  const MAX_SCAN_BYTES = maxScanMb * 1024 * 1024;
  const PHOTO_EXTENSIONS = ['jpg', 'jpeg', 'png'];
  // What the viewer draws at most (see loadScan); ?max_display_points=N and
  // ?max_display_triangles=N override.
  const MAX_DISPLAY_POINTS = Number(params.get('max_display_points')) > 0 ? Number(params.get('max_display_points')) : 4000000;
  const MAX_DISPLAY_TRIANGLES = Number(params.get('max_display_triangles')) > 0 ? Number(params.get('max_display_triangles')) : 2000000;

  const $ = (id) => document.getElementById(id);
  const ui = {
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
    photoList: $('photo-list'), photoCount: $('photo-count'), texture: $('btn-texture'), textureTotal: $('texture-total'),
    viewerPane: document.querySelector('.viewer-pane'), clicker: $('clicker'), clickerPrompt: $('clicker-prompt'),
    clickerCanvas: $('clicker-canvas'), clickerList: $('clicker-list'), clickerUndo: $('clicker-undo'),
    clickerSkip: $('clicker-skip'), clickerClear: $('clicker-clear'), clickerClose: $('clicker-close'),
  };

  // Exposed for the browser test and for debugging from the console.
  const app = window.likeness = {
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

  let stateBeforeError = 'ready';
  function setState(state) {
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
    ui.fit.disabled = !interactive || fitting || !app.scan;
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
    ui.exportMap.disabled = !haveFit || !distanceMap(true);
    for (const role of ui.photoList.querySelectorAll('select.photo-role')) role.disabled = !interactive || state === 'working';
  }

  function setStatus(text) { ui.status.textContent = text; }

  function showError(message) {
    app.lastError = message;
    ui.bannerText.textContent = message;
    ui.banner.hidden = false;
    setState('error');
  }

  function clearError() {
    ui.banner.hidden = true;
    if (document.body.dataset.state === 'error' && !app.startupFailed) setState(stateBeforeError);
  }

  // Without the viewer or the core nothing works: every control stays off.
  function fatalStartup(message) {
    app.startupFailed = true;
    ui.overlay.hidden = false;
    ui.overlayText.textContent = 'The app could not start.';
    setStatus('Likeness could not start in this browser.');
    ui.overlay.classList.add('failed');
    showError(message);
  }

  // ---- pipeline stage display ---------------------------------------------
  function stageItem(stage) { return document.querySelector('#stages li[data-stage="' + stage + '"]'); }
  function setStage(stage, tag, fraction, cls) {
    const li = stageItem(stage);
    if (!li) return;
    li.querySelector('.stage-tag').textContent = tag;
    if (fraction !== undefined) li.querySelector('progress').value = fraction;
    li.classList.remove('active', 'complete', 'failed');
    if (cls) li.classList.add(cls);
  }

  // ---- the worker -----------------------------------------------------------
  let nextJobId = 1;
  const jobs = new Map();  // id -> {resolve, reject, onProgress}
  let workerReady = null;  // promise resolved when the worker's core is up

  // The worker's start-up is watched here too: worker.js watches its own
  // downloads, compiles and thread pool, but a worker script that never
  // arrives, or an importScripts that never returns, leaves it unable to say
  // anything. No start-up message for WORKER_START_MS (each one restarts the
  // clock; ?worker_start_ms=N) ends that worker: a threaded attempt is
  // retried on one thread, a single-threaded one fails with a message.
  const WORKER_START_MS = Number(params.get('worker_start_ms')) > 0 ? Number(params.get('worker_start_ms')) : 60000;
  let workerStartFailed = null;  // why the last start failed (the next job tries again)

  function startWorker() {
    workerStartFailed = null;
    workerReady = startWorkerOnce().catch((e) => {
      workerStartFailed = e && e.message ? e.message : String(e);
      throw e;
    });
    return workerReady;
  }

  function startWorkerOnce() {
    // ?threads=1 keeps the single-threaded core even where threads are possible;
    // so does a threaded core that could not start before (a restarted worker
    // goes straight to one thread). ?thread_start_ms=N etc.: see worker.js.
    const workerParams = new URLSearchParams();
    const single = params.get('threads') === '1' || (app.workerThreads && app.workerThreads.fallback) || !window.crossOriginIsolated;
    if (single) workerParams.set('threads', '1');
    for (const p of ['thread_start_ms', 'core_stall_ms', 'core_compile_ms']) if (params.get(p)) workerParams.set(p, params.get(p));
    const worker = new Worker('worker.js' + (workerParams.toString() ? '?' + workerParams : ''));
    app.worker = worker;
    app.workerStart = { step: 'script worker.js', steps: ['script worker.js'] };
    return new Promise((resolve, reject) => {
      let up = false, watch = 0;
      const rewatch = () => {
        clearTimeout(watch);
        watch = setTimeout(() => {
          if (up || app.worker !== worker) return;
          const why = 'the core did not answer for ' + WORKER_START_MS / 1000 + ' s while starting (' + app.workerStart.step + ')';
          worker.terminate();
          if (!single) {  // try once more on one thread
            app.workerThreads = { variant: 'single', threads: 1, fallback: why };
            startWorkerOnce().then(resolve, reject);
          } else {
            reject(new Error(why));
          }
        }, WORKER_START_MS);
      };
      rewatch();
      worker.onmessage = (e) => {
        const msg = e.data;
        if (msg.type === 'starting') {
          app.workerStart.step = String(msg.step);
          app.workerStart.steps.push(app.workerStart.step);
          rewatch();
        } else if (msg.type === 'startFailed') {
          clearTimeout(watch);
          worker.terminate();
          if (app.worker === worker) reject(new Error(msg.message));
        } else if (msg.type === 'ready') {
          up = true;
          clearTimeout(watch);
          if (app.timings.worker === undefined) app.timings.worker = performance.now() - app.startedAt;
          // fallback: why the threaded core did not start (kept across restarts).
          app.workerThreads = { variant: msg.variant || 'single', threads: msg.threads || 1,
                                fallback: msg.fallback || (app.workerThreads && app.workerThreads.fallback) || null };
          resolve();
        } else if (msg.type === 'progress') {
          const job = jobs.get(msg.id);
          if (job && job.onProgress) job.onProgress(msg.stage, msg.fraction);
        } else if (msg.type === 'result') {
          const job = jobs.get(msg.id);
          jobs.delete(msg.id);
          if (job) job.resolve(msg.result);
        } else if (msg.type === 'fatal') {
          clearTimeout(watch);
          if (up) workerDied(worker, msg.message);
          else worker.terminate();
          reject(new Error(msg.message));
        }
      };
      worker.onerror = (e) => {
        e.preventDefault();
        clearTimeout(watch);
        const why = e.message || 'worker.js did not load';
        if (up) workerDied(worker, why);
        else worker.terminate();
        reject(new Error(why));
      };
    });
  }

  // The first fit in a page ran its hot loops on V8's baseline tier (+0.6-1.5 s;
  // docs/web.md, "The first fit"). A throw-away worker running one small fit
  // of the same module right after start-up gets them compiled by the
  // optimizing tier, and that code is shared with the core's worker. It runs
  // on its own thread (never delays a job) and ends itself; ?warmup=0 skips it.
  async function warmUp(variant) {
    if (params.get('warmup') === '0' || app.warmup) return;
    app.warmup = { state: 'running', variant };
    let compiled;
    try {
      compiled = await runJob({ type: 'module' }, []);
    } catch (e) {
      compiled = { ok: false, message: e && e.message ? e.message : String(e) };
    }
    if (!compiled.ok) {
      Object.assign(app.warmup, { state: 'failed', message: compiled.message });
      return;
    }
    const workerParams = new URLSearchParams({ warmup: '1' });
    if (variant !== 'threads') workerParams.set('threads', '1');
    for (const p of ['thread_start_ms', 'core_stall_ms', 'core_compile_ms']) if (params.get(p)) workerParams.set(p, params.get(p));
    const t0 = performance.now();
    const worker = new Worker('worker.js?' + workerParams);
    worker.postMessage({ type: 'module', module: compiled.module });
    const end = (state, extra) => {
      clearTimeout(limit);
      worker.terminate();
      if (app.warmup.state === 'running') Object.assign(app.warmup, { state, ms: performance.now() - t0 }, extra);
    };
    const limit = setTimeout(() => end('gave up'), 120000);
    worker.onmessage = (e) => {
      const msg = e.data;
      if (msg.type === 'warm') end(msg.ok ? 'done' : 'failed', { fitMs: msg.fitMs, message: msg.message });
      else if (msg.type === 'startFailed' || msg.type === 'fatal') end('failed', { message: msg.message });
    };
    worker.onerror = (e) => { e.preventDefault(); end('failed', { message: e.message || 'error' }); };
  }

  // The core aborted (out of memory or a bug), or the user cancelled: fail
  // the running jobs with the reason and start a fresh worker so the page
  // keeps working. Terminating is the one cancel that always works, whatever
  // the job is doing.
  function workerDied(worker, why, cancelled = false) {
    if (app.worker !== worker) return;
    worker.terminate();
    for (const [, job] of jobs) {
      const err = new Error(cancelled ? 'cancelled' : 'the worker stopped (' + why + ') and was restarted');
      err.cancelled = cancelled;
      job.reject(err);
    }
    jobs.clear();
    // The fitted head lived in that worker: animation and export need a new fit.
    if (app.fit) forgetFit('The fitted head was in the stopped worker: fit again to animate or export.');
    if (document.body.dataset.state !== 'loading') {
      startWorker().catch((e) => {
        // Nothing the user gave is lost: the scan, photos and clicks live on
        // the page; the next job starts a worker again.
        showError('The core stopped and could not be started again: ' + (e && e.message ? e.message : e) +
                  '. Your scan and photos are kept; the next action tries again.');
      });
    }
  }

  // Cancels whatever the worker is doing (the Cancel button).
  function cancelJobs() {
    if (jobs.size) workerDied(app.worker, 'cancelled', true);
  }
  app.cancel = cancelJobs;

  // Runs a worker job; resolves with the core's result object, rejects when
  // the worker dies on the way (the page then has a fresh worker).
  // The job counts as running from the call on (so Cancel reaches it even
  // while a fresh worker is still starting).
  function runJob(message, transfer, onProgress) {
    return new Promise((resolve, reject) => {
      const id = nextJobId++;
      jobs.set(id, { resolve, reject, onProgress });
      // The last start failed (e.g. the server was away): try again now.
      if (workerStartFailed && document.body.dataset.state !== 'loading' && !app.startupFailed) startWorker().catch(() => {});
      workerReady.then(() => {
        if (jobs.has(id)) app.worker.postMessage(Object.assign({ id }, message), transfer);
      }, (err) => {
        if (jobs.delete(id)) reject(err);
      });
    });
  }

  app.runJob = runJob;
  app.fitHead = () => runFit();

  // ---- the viewer -----------------------------------------------------------
  function loadScript(src) {
    return new Promise((resolve, reject) => {
      const s = document.createElement('script');
      s.src = src;
      s.onload = resolve;
      s.onerror = () => reject(new Error('could not load ' + src));
      document.head.appendChild(s);
    });
  }

  // Resolves once the viewer has drawn at least one frame with the head.
  function firstFrame(viewer) {
    return new Promise((resolve, reject) => {
      const poll = () => {
        const why = viewer.startup_error();
        if (why) reject(new Error('the 3D viewer could not start: ' + why));
        else if (viewer.frames_drawn() > 0) resolve();
        else requestAnimationFrame(poll);
      };
      poll();
    });
  }

  // True when WebGL2 is drawn on the CPU (SwiftShader, llvmpipe): no GPU.
  function softwareWebGL() {
    try {
      const gl = document.createElement('canvas').getContext('webgl2');
      if (!gl) return false;
      let name = String(gl.getParameter(gl.RENDERER));
      const info = gl.getExtension('WEBGL_debug_renderer_info');
      if (info) name += ' ' + gl.getParameter(info.UNMASKED_RENDERER_WEBGL);
      const lose = gl.getExtension('WEBGL_lose_context');
      if (lose) lose.loseContext();
      return /swiftshader|llvmpipe|softpipe|software/i.test(name);
    } catch (e) {
      return false;
    }
  }

  async function startViewer() {
    await loadScript('likeness_viewer.js');
    // Multisampling doubles SwiftShader's cost of a level-3 frame (measured:
    // docs/web.md), so a software WebGL gets none; ?msaa=N overrides.
    app.software = softwareWebGL();
    app.msaa = params.has('msaa') ? Math.max(0, Number(params.get('msaa')) || 0) : app.software ? 0 : 4;
    const viewer = await LikenessViewer({
      canvas: ui.canvas,
      arguments: ['--msaa', String(app.msaa)],
      print: (t) => console.log('[viewer]', t),
      printErr: (t) => console.warn('[viewer]', t),
      onAbort: (what) => fatalStartup('The 3D viewer stopped: ' + what),
    });
    app.viewer = viewer;
    app.timings.viewerModule = performance.now() - app.startedAt;
    await firstFrame(viewer);
    app.timings.firstFrame = performance.now() - app.startedAt;
    ui.overlay.hidden = true;
    return viewer;
  }

  // ---- files ----------------------------------------------------------------
  function extension(name) {
    const dot = name.lastIndexOf('.');
    return dot < 0 ? '' : name.slice(dot + 1).toLowerCase();
  }

  function formatBytes(n) {
    if (n < 1024) return n + ' B';
    if (n < 1024 * 1024) return (n / 1024).toFixed(1) + ' KB';
    if (n < 1024 * 1024 * 1024) return (n / 1024 / 1024).toFixed(1) + ' MB';
    return (n / 1024 / 1024 / 1024).toFixed(2) + ' GB';
  }

  function listFile(file, note, cls) {
    const li = document.createElement('li');
    if (cls) li.className = cls;
    const name = document.createElement('span');
    name.className = 'file-name';
    name.textContent = file.name;
    const meta = document.createElement('span');
    meta.className = 'file-meta';
    meta.textContent = formatBytes(file.size) + ' · ' + note;
    li.append(name, meta);
    ui.fileList.prepend(li);
    while (ui.fileList.children.length > 6) ui.fileList.lastChild.remove();
    return meta;
  }

  async function handleFiles(fileList) {
    const files = Array.from(fileList || []);
    if (!files.length) return;
    // One job at a time; a drop meanwhile is declined in the status line
    // (not as an error: the running job's state must stay "working").
    const state = document.body.dataset.state;
    if (state === 'loading' || app.startupFailed) return;
    if (state === 'working') {
      setStatus('Still working: drop ' + files[0].name + ' again when the current job has finished (or cancel it).');
      return;
    }
    clearError();
    stopAnimation();
    const photos = files.filter((f) => PHOTO_EXTENSIONS.includes(extension(f.name)));
    const pointFiles = files.filter((f) => extension(f.name) === 'txt');
    const scans = files.filter((f) => !photos.includes(f) && !pointFiles.includes(f));
    for (const extra of scans.slice(1)) listFile(extra, 'ignored: one scan at a time', 'ignored');
    if (scans.length) await loadScan(scans[0]);
    if (photos.length && document.body.dataset.state !== 'error') await checkPhotos(photos, !scans.length);
    if (pointFiles.length && document.body.dataset.state !== 'error') await readPointFiles(pointFiles);
    if ((photos.length || pointFiles.length) && ui.autoFit.checked && app.fit && texturable().length &&
        document.body.dataset.state === 'done') await runTexture();
  }

  // Photos are decoded once in the worker to catch broken files now rather
  // than at the Texture stage; the File objects are kept for that stage.
  async function checkPhotos(photos, alone) {
    const before = document.body.dataset.state;
    setState('working');
    const failures = [];
    for (const file of photos) {
      const meta = listFile(file, 'checking…');
      if (file.size > MAX_SCAN_BYTES) {
        meta.textContent = formatBytes(file.size) + ' · too large';
        failures.push(file.name + ' is ' + formatBytes(file.size) + '; photos up to ' + formatBytes(MAX_SCAN_BYTES) + ' are accepted.');
        continue;
      }
      let result;
      try {
        const buffer = await file.arrayBuffer();
        result = await runJob({ type: 'image', name: file.name, buffer }, [buffer]);
      } catch (e) {
        if (e && e.cancelled) {
          meta.textContent = formatBytes(file.size) + ' · cancelled';
          break;
        }
        result = { ok: false, message: file.name + ': ' + (e && e.message ? e.message : e) };
      }
      if (!result.ok) {
        meta.textContent = formatBytes(file.size) + ' · not an image';
        failures.push(result.message);
        continue;
      }
      meta.textContent = formatBytes(file.size) + ' · ' + result.width + '×' + result.height + ' photo';
      meta.parentElement.title = file.name + ': ' + result.width + '×' + result.height +
                                 ' photo, kept for the Texture stage';
      addPhoto({ name: file.name, file, width: result.width, height: result.height });
    }
    renderPhotos();
    setState(before === 'loading' ? 'ready' : before);
    if (failures.length) {
      showError(failures.join(' '));
    } else if (alone) {
      setStatus(app.photos.length + ' photo(s) kept for the Texture stage. ' +
                (app.fit ? 'Give each its points (a .txt of the same name, or click the photo), then Texture.'
                  : app.model ? 'Fit the head, then texture it.' : 'Drop a head scan (PLY, OBJ, XYZ or VTK) to start.'));
    }
  }

  // ---- photos and their correspondences (tarini2002 Sec. 3) -------------------
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
    if (old >= 0) {
      const prev = app.photos[old];
      URL.revokeObjectURL(prev.url);
      Object.assign(entry, { filePoints: prev.filePoints, pointsName: prev.pointsName, clicks: prev.clicks, role: prev.role || 'face' });
      app.photos[old] = entry;
    } else {
      app.photos.push(entry);
    }
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
  async function readPointFiles(files) {
    const failures = [];
    const before = document.body.dataset.state;
    setState('working');
    for (const file of files) {
      const photo = app.photos.find((p) => baseName(p.name) === baseName(file.name));
      const meta = listFile(file, 'reading…');
      if (!photo) {
        meta.textContent = formatBytes(file.size) + ' · no photo named ' + baseName(file.name) + '.jpg/.png';
        meta.parentElement.classList.add('ignored');
        failures.push(file.name + ' is not a scan, and no photo is named ' + baseName(file.name) + '.jpg or .png: a points ' +
                      'file (.txt, "u v X Y Z" per line) goes with the photo of the same name; drop both together.');
        continue;
      }
      let result;
      try {
        result = file.size > 4 * 1024 * 1024 ? { ok: false, message: 'larger than 4 MB: not a points file' }
          : await runJob({ type: 'points', text: await file.text() }, []);
      } catch (e) {
        result = { ok: false, message: e && e.message ? e.message : String(e) };
      }
      if (!result.ok) {
        meta.textContent = formatBytes(file.size) + ' · not a points file';
        failures.push(file.name + ': ' + result.message + ' (expected one "u v X Y Z" per line)');
        continue;
      }
      photo.filePoints = result.points;
      photo.pointsName = file.name;
      photo.calib = null;
      meta.textContent = formatBytes(file.size) + ' · ' + result.points.length / 5 + ' points for ' + photo.name;
    }
    renderPhotos();
    setState(before === 'loading' ? 'ready' : before);
    if (failures.length) showError(failures.join(' '));
  }

  // The correspondences a photo contributes: its clicks when it has any
  // (landmarks placed on the fitted head), else its points file.
  function photoPoints(photo) {
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
  function texturable() { return facePhotos().filter((p) => photoPoints(p).list.length > 0); }
  // Photos of role "face" (the default) texture the skin; "eye" and "smile"
  // photos only make the iris and teeth textures.
  function facePhotos() { return app.photos.filter((p) => (p.role || 'face') === 'face'); }

  function renderPhotos() {
    ui.photoList.textContent = '';
    for (const [index, photo] of app.photos.entries()) {
      const li = document.createElement('li');
      li.tabIndex = 0;
      li.setAttribute('role', 'button');
      li.dataset.index = String(index);
      li.classList.toggle('open', clicker.photo === photo);
      const img = document.createElement('img');
      img.src = photo.url;
      img.alt = '';
      const text = document.createElement('div');
      const name = document.createElement('div');
      name.className = 'photo-name';
      name.textContent = photo.name;
      const meta = document.createElement('div');
      meta.className = 'photo-meta';
      const pts = photoPoints(photo);
      let note = photo.width + '×' + photo.height + ' · ';
      if (pts.source === 'clicks') note += pts.list.length + ' of ' + app.fit.landmarks.length + ' landmarks clicked';
      else if (pts.source === 'file') note += pts.list.length + ' points from ' + photo.pointsName;
      else note += app.fit ? 'no points yet: click to mark landmarks' : 'no points yet';
      if (pts.list.length > 0 && pts.list.length < 6) { note += ' (6 needed)'; meta.classList.add('bad'); }
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
      li.append(img, text, remove);
      li.title = photo.name + ': click to mark landmarks on it' + (photo.calib && !photo.calib.ok ? ' (' + photo.calib.message + ')' : '');
      li.addEventListener('click', () => openClicker(photo));
      li.addEventListener('keydown', (e) => { if (e.key === 'Enter' || e.key === ' ') { e.preventDefault(); openClicker(photo); } });
      ui.photoList.append(li);
    }
    ui.photoCount.textContent = app.photos.length ? app.photos.length + ' photo(s), ' + texturable().length + ' with points' : '';
    setState(document.body.dataset.state);
  }

  // ---- photo roles: eye (iris) and smile (teeth) photos (tarini2002 Sec. 4) ---
  const PHOTO_ROLES = [['face', 'Face (skin)'], ['eye', 'Eye (iris)'], ['smile', 'Smile (teeth)']];

  // Forgets the iris / teeth texture this photo made (role changed, photo
  // removed); the components go back to the generic textures.
  function dropRoleTexture(photo) {
    let changed = false;
    if (app.eyePhoto && app.eyePhoto.name === photo.name) { app.eyePhoto = null; changed = true; }
    if (app.smilePhoto && app.smilePhoto.name === photo.name) { app.smilePhoto = null; changed = true; }
    if (changed && app.viewer && app.componentsData) showComponents(app.componentsData);
  }

  // An eye photo runs the iris synthesis in the worker and dresses both
  // eyeballs; a smile photo makes the teeth texture. Errors go to the banner;
  // the photo keeps its role (and its clicks), the textures stay as they were.
  async function setPhotoRole(photo, role) {
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
    const before = document.body.dataset.state;
    const eye = role === 'eye';
    photo.roleNote = eye ? 'finding the iris…' : 'making the teeth texture…';
    setState('working');
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
    setState(before === 'error' ? stateBeforeError : before);
    if (photo.role !== role || !app.photos.includes(photo)) { renderPhotos(); return; }
    if (!result.ok) {
      photo.roleFailed = true;
      photo.roleNote = eye ? 'no iris found' : 'no teeth found';
      renderPhotos();
      setStatus(photo.name + ': ' + photo.roleNote + '; the ' + (eye ? 'eyes' : 'teeth') + ' keep their texture.');
      // The worker's message starts with the photo's name.
      showError((eye ? 'Eye photo ' : 'Smile photo ') + (result.message || photo.name + ': ' + result.code) +
                (eye ? '. An eye photo is a close-up of one open eye, the iris near the middle.'
                  : '. A smile photo shows the front teeth, lips apart, filling most of the picture.'));
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

  // ---- the landmark clicker ------------------------------------------------------
  // The photo large beside the 3D view; the landmarks are asked in turn, the
  // one asked is marked red on the head. Clicks live in photo.clicks, so they
  // survive picking another photo, an error, or a new fit of the same scan.
  const clicker = { photo: null, image: null, current: 0, view: null };

  function openClicker(photo) {
    if (photo && (photo.role || 'face') !== 'face') {
      setStatus(photo.name + ' is ' + (photo.role === 'eye' ? 'an eye' : 'a smile') + ' photo: it needs no landmarks ' +
                '(set its role to "Face (skin)" to texture the skin with it).');
      return;
    }
    if (!app.fit || !app.fit.landmarks || !app.fit.landmarks.length) {
      setStatus('Fit the head first: the landmarks are placed on the fitted head.');
      return;
    }
    stopAnimation();
    clicker.photo = photo;
    clicker.image = new Image();
    clicker.image.onload = () => drawClicker();
    clicker.image.src = photo.url;
    clicker.current = nextLandmark(0);
    ui.clicker.hidden = false;
    ui.viewerPane.classList.add('clicking');
    reframeSoon();
    renderPhotos();
    updateClicker();
  }

  function closeClicker() {
    if (!clicker.photo) return;
    clicker.photo = null;
    ui.clicker.hidden = true;
    ui.viewerPane.classList.remove('clicking');
    reframeSoon();
    if (app.viewer) app.viewer.set_markers(new Float32Array(0), null);
    renderPhotos();
  }

  // The 3D view's width changes with the clicker: frame the head again once
  // the viewer has taken the new canvas size (it does so each frame).
  function reframeSoon() {
    requestAnimationFrame(() => requestAnimationFrame(() => { if (app.viewer) app.viewer.reset_view(); }));
  }

  // The first landmark from `from` on that has neither a click nor a skip.
  function nextLandmark(from) {
    const lms = app.fit.landmarks;
    for (let k = 0; k < lms.length; k++) {
      const i = (from + k) % lms.length;
      if (!clicker.photo.clicks.has(lms[i].id)) return i;
    }
    return -1;
  }

  function updateClicker() {
    const photo = clicker.photo;
    if (!photo) return;
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

  function clickerClick(e) {
    const photo = clicker.photo, v = clicker.view;
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
  app.openClicker = (i) => openClicker(app.photos[i]);


  const SCAN_EXTENSIONS = ['ply', 'obj', 'xyz', 'vtk'];

  // Every stride-th point of a parsed point cloud (positions, normals, colors).
  function thinPoints(result, stride) {
    const n = Math.ceil(result.vertexCount / stride);
    const pick = (a) => {
      if (!a || a.length === 0) return a;
      const out = new Float32Array(n * 3);
      for (let i = 0, j = 0; j < n; i += stride, j++) out.set(a.subarray(3 * i, 3 * i + 3), 3 * j);
      return out;
    };
    return Object.assign({}, result, { positions: pick(result.positions), normals: pick(result.normals),
                                       colors: pick(result.colors), vertexCount: n });
  }

  // A failed load: the message goes to the banner, the stage and the file
  // list say so, and the status line says what is still shown.
  function loadFailed(file, meta, note, message) {
    meta.textContent = formatBytes(file.size) + ' · ' + note;
    setStage('load', 'failed', 0, 'failed');
    const kept = app.model ? ' The previous model (' + app.model.name + ') is still shown.' : '';
    setStatus('Could not load ' + file.name + '.' + kept);
    showError(message);
  }

  async function loadScan(file) {
    const meta = listFile(file, 'reading…');
    if (file.size > MAX_SCAN_BYTES) {
      loadFailed(file, meta, 'too large', file.name + ' is ' + formatBytes(file.size) +
                 '; the web app accepts scans up to ' + formatBytes(MAX_SCAN_BYTES) +
                 '. Decimate the scan or use the native tool (likeness).');
      return;
    }
    if (file.size === 0) {
      loadFailed(file, meta, 'empty', file.name + ' is empty.');
      return;
    }
    setState('working');
    setStage('load', 'reading', 0, 'active');
    setStatus('Reading ' + file.name + '…');
    const t0 = performance.now();
    let result;
    try {
      const buffer = await file.arrayBuffer();
      setStage('load', 'parsing', 0.05, 'active');
      result = await runJob({ type: 'parse', name: file.name, buffer }, [buffer], (stage, fraction) => {
        if (stage === 'load') setStage('load', 'parsing', 0.05 + 0.9 * fraction, 'active');
      });
    } catch (e) {
      if (e && e.cancelled) {
        meta.textContent = formatBytes(file.size) + ' · cancelled';
        setStage('load', 'cancelled', 0);
        setStatus('Cancelled loading ' + file.name + '.' +
                  (app.model ? ' The previous model (' + app.model.name + ') is still shown.' : ''));
        setState(app.model ? 'done' : 'ready');
        return;
      }
      result = { ok: false, code: 'Internal', message: file.name + ': ' + (e && e.message ? e.message : e) +
                 '. Try a smaller or decimated scan.' };
    }
    if (!result.ok) {
      let message = result.message || (file.name + ': ' + result.code);
      // The core guessed the format from the bytes; say what we expected.
      if (!SCAN_EXTENSIONS.includes(extension(file.name))) {
        message = file.name + ' is not a PLY, OBJ, XYZ or VTK scan (' +
                  message.replace(file.name + ': ', '') + ').';
      }
      loadFailed(file, meta, 'not loaded', message);
      return;
    }
    // Display budget: the viewer holds what it shows in its own 32-bit heap
    // and on the GPU (meshes unrolled, ~170 bytes per triangle), so very
    // large scans are thinned for display. The full data stays with the
    // worker's stages.
    let display = result, stride = 1;
    if (result.kind === 'points' && result.vertexCount > MAX_DISPLAY_POINTS) {
      stride = Math.ceil(result.vertexCount / MAX_DISPLAY_POINTS);
      display = thinPoints(result, stride);
    }
    if (result.kind === 'mesh' && result.triangleCount > MAX_DISPLAY_TRIANGLES) {
      loadFailed(file, meta, 'too many triangles', file.name + ' has ' + result.triangleCount.toLocaleString('en') +
                 ' triangles; the web viewer shows meshes up to ' + MAX_DISPLAY_TRIANGLES.toLocaleString('en') +
                 '. Decimate it, or drop its vertices as a point cloud (XYZ).');
      return;
    }
    const shown = display.kind === 'mesh'
      ? app.viewer.show_mesh(display.positions, display.normals, display.colors, display.indices)
      : app.viewer.show_points(display.positions, display.normals, display.colors);
    const ms = performance.now() - t0;
    if (shown !== '') {
      loadFailed(file, meta, 'not shown', file.name + ': ' + shown);
      return;
    }
    app.model = { name: file.name, kind: result.kind, vertexCount: result.vertexCount,
                  triangleCount: result.triangleCount, loadMs: ms, displayStride: stride };
    // A new scan: the old fit no longer belongs to what is shown.
    if (app.fit) forgetFit();
    app.viewer.set_overlay_points(new Float32Array(0), null, null);
    app.scan = { file, display: { positions: display.positions, normals: display.normals, colors: display.colors } };
    for (const st of FIT_STAGES) { setStage(st.row, 'waiting', 0); stageItem(st.row).classList.remove('coming'); }
    const what = result.kind === 'mesh'
      ? 'mesh, ' + result.vertexCount.toLocaleString('en') + ' vertices, ' +
        result.triangleCount.toLocaleString('en') + ' triangles'
      : 'point cloud, ' + result.vertexCount.toLocaleString('en') + ' points' +
        (stride > 1 ? ' (showing 1 in ' + stride + ')' : '');
    meta.textContent = formatBytes(file.size) + ' · ' + (result.kind === 'mesh'
      ? result.triangleCount.toLocaleString('en') + ' triangles'
      : result.vertexCount.toLocaleString('en') + ' points');
    meta.parentElement.title = file.name + ': ' + what;
    setStage('load', 'done', 1, 'complete');
    setStatus(file.name + ': ' + what + ' (loaded in ' + Math.round(ms) + ' ms).');
    setState('done');
    if (ui.autoFit.checked) await runFit();
  }

  // The built-in sample (a synthetic head from our virtual scanner, no real
  // person) is put beside the page by scripts/demo; it comes from this page's
  // own origin like everything else.
  const SAMPLE_URL = 'sample/scan.ply';
  async function loadSample() {
    if (document.body.dataset.state === 'working') return;
    clearError();
    let response;
    try {
      response = await fetch(SAMPLE_URL, { cache: 'no-store' });
    } catch (e) {
      showError('Could not fetch the sample (' + SAMPLE_URL + '): ' + (e && e.message ? e.message : e));
      return;
    }
    if (!response.ok) {
      showError('The built-in sample is not installed next to this page (' + SAMPLE_URL + ': HTTP ' +
                response.status + '). scripts/demo makes it; or drop your own scan.');
      return;
    }
    const blob = await response.blob();
    // Synthetic photos of the sample head with their points files (made by
    // `likeness texture --make-synthetic`, listed in sample/texture.json by
    // scripts/demo): the Texture stage's demo. Missing ones are skipped.
    const extra = [];
    try {
      const list = await fetch(SAMPLE_TEXTURE_URL, { cache: 'no-store' });
      const manifest = list.ok ? await list.json() : { photos: [] };
      for (const name of (manifest.photos || []).slice(0, 8)) {
        if (typeof name !== 'string' || !/^[\w.-]+\.(png|jpe?g)$/i.test(name)) continue;
        const txt = name.replace(/\.[^.]*$/, '.txt');
        const [photo, points] = await Promise.all([fetch('sample/' + name, { cache: 'no-store' }),
                                                   fetch('sample/' + txt, { cache: 'no-store' })]);
        if (photo.ok) extra.push(new File([await photo.blob()], name));
        if (photo.ok && points.ok) extra.push(new File([await points.blob()], txt));
      }
    } catch (e) {
      console.warn('sample photos not loaded:', e && e.message ? e.message : e);
    }
    await handleFiles([new File([blob], 'sample_scan.ply'), ...extra]);
  }
  const SAMPLE_TEXTURE_URL = 'sample/texture.json';


  // ---- fitting the head (jeong2002 Sec. 4-5) ----------------------------------
  // Core stage names -> the Pipeline rows, and the mesh each row shows.
  const FIT_STAGES = [
    { core: 'initial_alignment', row: 'align', mesh: 'aligned' },
    { core: 'local_fitting', row: 'local_fit', mesh: 'local' },
    { core: 'global_fitting', row: 'global_fit', mesh: 'control' },
    { core: 'subdivision', row: 'subdivide', mesh: 'level' },
  ];
  const rowOf = (core) => (FIT_STAGES.find((s) => s.core === core) || {}).row;

  function stageStats(row) { return stageItem(row).querySelector('.stage-stats'); }

  function markShown(row) {
    app.shownStage = row;
    if (row !== 'subdivide') {
      viewerLevel = null;
      ui.distanceLegend.hidden = true;  // the map is of the subdivided head only
    }
    for (const st of FIT_STAGES) stageItem(st.row).classList.toggle('shown', st.row === row);
  }

  // The fit died with its worker, or a new scan came: rows keep their numbers
  // until the next fit, but nothing can be animated or exported.
  function forgetFit(why) {
    stopAnimation(false);
    closeClicker();
    app.fit = null;
    ui.distanceLegend.hidden = true;
    forgetTexture();
    if (app.viewer) app.viewer.clear_components();
    ui.fitView.hidden = true;
    ui.fitQuality.hidden = true;
    for (const st of FIT_STAGES) stageItem(st.row).classList.remove('viewable', 'shown');
    if (why) setStatus(why);
    setState(document.body.dataset.state);
  }

  async function runFit() {
    const state = document.body.dataset.state;
    if (!app.scan || state === 'working' || state === 'loading' || app.startupFailed) return;
    clearError();
    stopAnimation();
    const file = app.scan.file;
    setState('working');
    for (const st of FIT_STAGES) {
      setStage(st.row, 'waiting', 0);
      stageStats(st.row).textContent = '';
    }
    ui.fitTotal.textContent = '';
    ui.fitQuality.hidden = true;
    setStatus('Fitting the generic head to ' + file.name + '…');
    const t0 = performance.now();
    let result;
    try {
      const buffer = await file.arrayBuffer();
      result = await runJob({ type: 'fit', name: file.name, buffer, options: { levels: 3 } }, [buffer],
        (stage, fraction) => {
          const row = rowOf(stage);
          if (!row) return;
          // Earlier rows are complete once a later stage starts.
          for (const st of FIT_STAGES) {
            if (st.row === row) break;
            const li = stageItem(st.row);
            if (!li.classList.contains('complete')) setStage(st.row, 'done', 1, 'complete');
          }
          setStage(row, fraction >= 1 ? 'measuring' : Math.round(fraction * 100) + '%', fraction, 'active');
        });
    } catch (e) {
      if (e && e.cancelled) {
        for (const st of FIT_STAGES) setStage(st.row, 'cancelled', 0);
        setStatus('Fit cancelled. ' + (app.model ? app.model.name + ' is still shown.' : ''));
        setState(app.model ? 'done' : 'ready');
        return;
      }
      result = { ok: false, code: 'Internal', message: file.name + ': ' + (e && e.message ? e.message : e) };
    }
    const wallMs = performance.now() - t0;
    if (!result.ok) {
      const failedRow = FIT_STAGES.find((st) => stageItem(st.row).classList.contains('active'));
      for (const st of FIT_STAGES) {
        if (!stageItem(st.row).classList.contains('complete')) setStage(st.row, st === failedRow ? 'failed' : 'waiting', 0, st === failedRow ? 'failed' : undefined);
      }
      let message = result.message || result.code;
      if (result.code === 'not a head' || result.code === 'NotAHead') message = 'This does not look like a head scan, so no head was fitted: ' + message;
      setStatus('The fit failed.' + (app.model ? ' ' + app.model.name + ' is still shown.' : ''));
      showError(message);
      return;
    }
    app.fit = { name: file.name, stages: result.stages, meshes: result.meshes, fitMs: result.fitMs,
                parseMs: result.parseMs, wallMs, points: result.points, fittedPoints: result.fittedPoints,
                animatedVertices: result.animatedVertices, landmarks: result.landmarks || [],
                headFacing: result.headFacing || [0, 0, 1], headUp: result.headUp || [0, 1, 0] };
    forgetTexture();
    for (const st of FIT_STAGES) {
      const s = result.stages.find((x) => x.name === st.core);
      setStage(st.row, s ? Math.round(s.ms) + ' ms' : 'done', 1, 'complete');
      if (s) stageStats(st.row).textContent = 'mean ' + s.meanPct.toFixed(3) + ' % · max ' + s.maxPct.toFixed(2) + ' % of diagonal';
      const li = stageItem(st.row);
      li.classList.add('viewable');
      li.tabIndex = 0;
      li.setAttribute('role', 'button');
    }
    ui.fitTotal.textContent = 'fit ' + (result.fitMs / 1000).toFixed(2) + ' s (+ parse ' + Math.round(result.parseMs) +
                              ' ms) · ' + result.fittedPoints.toLocaleString('en') + ' points fitted' +
                              (app.workerThreads ? ' · ' + app.workerThreads.threads + (app.workerThreads.threads === 1 ? ' thread' : ' threads') +
                               (app.workerThreads.fallback ? ' (threads could not start here)' : '') : '');
    ui.fitView.hidden = false;
    showFitNotes(result.notes || []);
    const levels = result.meshes.levels.length;
    for (const opt of ui.level.options) opt.disabled = Number(opt.value) > levels;
    if (Number(ui.level.value) > levels) ui.level.value = String(levels);
    app.viewer.set_overlay_points(app.scan.display.positions, app.scan.display.normals, app.scan.display.colors);
    app.viewer.set_overlay_visible(ui.showPoints.checked);
    showComponents(result.components);
    showStage('subdivide');
    // Look at the new head's face: it is shown over the scan in the scan's
    // orientation, which need not face +z (Fran's faces 37 degrees off +x),
    // and the view was framed on the scan, which may be a face only.
    const [f, u] = [app.fit.headFacing, app.fit.headUp];
    app.viewer.set_head_frame(f[0], f[1], f[2], u[0], u[1], u[2]);
    setStatus(file.name + ': head fitted in ' + (result.fitMs / 1000).toFixed(2) + ' s. Click a stage to see its mesh; ' +
              'pick a level, animate or export.');
    setState('done');
    renderPhotos();
    // Sent before anything else can reach the worker, so the checks see the
    // head at rest; not awaited: the page stays usable meanwhile.
    checkFitQuality(app.fit);
    if (ui.autoFit.checked && texturable().length) await runTexture();
  }

  // What the fit decided on its own about the scan (turned to face +z, a
  // face-only capture, ...), as `likeness fit` prints them: the user should
  // know, and can pass the conventions next time.
  function showFitNotes(notes) {
    ui.fitNotes.replaceChildren();
    for (const n of notes) {
      const li = document.createElement('li');
      li.textContent = n;
      ui.fitNotes.appendChild(li);
    }
    ui.fitNotes.hidden = notes.length === 0;
  }

  // ---- the fitted head's checks ----------------------------------------------
  // What `likeness fit` prints after Table 1 (core/pipeline/fit_quality.h),
  // measured in the worker after the timed fit: triangles of the finest level
  // turned over by a displacement or degenerate, self-intersecting triangle
  // pairs by region (of the level and of its smooth surface without the
  // scan's detail), and the control mesh's own crossings. Worded for a user:
  // what is fine, what to look at. fit.quality holds the worker's numbers.
  const count = (x) => Number(x).toLocaleString('en');
  const byRegion = (c) => 'lips ' + count(c.lips) + ', ears ' + count(c.ears) + ', eye sockets ' + count(c.eyeSockets || 0) +
                          ', elsewhere ' + count(c.rest);

  function qualityItem(cls, text) {
    const li = document.createElement('li');
    li.className = cls;
    li.textContent = text;
    ui.qualityList.appendChild(li);
  }

  function showQuality(q) {
    const L = q.level, c = q.crossings, sm = q.smoothCrossings;
    ui.qualityTitle.textContent = 'Checks of level ' + L + ' (' + count(q.triangles) + ' triangles)';
    ui.qualityList.replaceChildren();
    if (q.flipped + q.degenerate === 0) {
      qualityItem('ok', 'No folds: no triangle turned over by the scan\'s detail, none degenerate.');
    } else {
      qualityItem('look', count(q.flipped) + ' triangles turned over by the scan\'s detail, ' + count(q.degenerate) +
                  ' degenerate (no area): they can show as dark specks; look at level ' + L + ' with Wireframe on.');
    }
    if (c.total === 0) {
      qualityItem('ok', 'No self-intersections: the surface never passes through itself.');
    } else {
      let text = count(c.total) + ' self-intersecting triangle pairs (' + byRegion(c) + ').';
      if (c.lips) text += ' The lips cross each other: they may show through one another when the mouth opens.';
      if (c.ears) text += ' At the ears: folds of the ear rims, which scans rarely capture well; the ears do not move in the animation.';
      if (c.eyeSockets) text += ' In the eye sockets: behind the lids, where the eyeballs sit; hidden when the eyes are shown.';
      if (c.rest) text += ' Elsewhere: small overlaps, often at the eye rims, nose or brow; look there with Wireframe on.';
      qualityItem('look', text);
    }
    qualityItem('note', 'The smooth surface under the detail (level ' + L + ' of the control mesh, without displacements): ' +
                (sm.total === 0 ? 'no self-intersections' : count(sm.total) + ' pairs (' + byRegion(sm) + ')') +
                (c.total === 0 ? '.' : sm.total === 0 ? ': every crossing above comes from the scan\'s detail.'
                                     : ': crossings there come from the fitted shape, not from the detail.'));
    if (q.controlCrossings === 0) qualityItem('ok', 'The control mesh does not cross itself.');
    else qualityItem('look', 'The control mesh crosses itself in ' + count(q.controlCrossings) +
                     ' triangle pairs: the fit folded it there, and every level inherits the fold.');
    if (q.faceToScan) {
      const d = q.faceToScan;
      const against = d.to === 'points' ? 'Against your scan\'s points (a small surface fitted to each vertex\'s 16 nearest), where it was scanned'
                                        : 'Against your scan\'s own triangles, where it was scanned';
      if (d.vertices === 0) qualityItem('note', against + ': no vertex of the face lies over a scanned part of it.');
      else qualityItem('note', against + ': the face of level ' + L + ' lies ' +
                       d.meanMm.toFixed(2) + ' mm from it on average, 99 % of its ' + count(d.vertices) + ' vertices within ' +
                       d.p99Mm.toFixed(1) + ' mm, the farthest ' + d.maxMm.toFixed(1) + ' mm.');
    }
    qualityItem('note', 'Checked in ' + (q.checkMs / 1000).toFixed(2) + ' s in the worker, after the timed fit (as likeness fit does).');
    const look = [];
    if (q.flipped + q.degenerate) look.push(count(q.flipped + q.degenerate) + ' folded or degenerate triangles');
    if (c.total) {
      const where = [['the lips', c.lips], ['the ears', c.ears], ['the eye sockets', c.eyeSockets || 0], ['elsewhere', c.rest]]
        .filter((w) => w[1])
        .map((w) => w[0] + ' ' + count(w[1]));
      look.push('the surface crosses itself in ' + count(c.total) + ' triangle pairs (' + where.join(', ') + ')');
    }
    if (q.controlCrossings) look.push('the control mesh crosses itself (' + count(q.controlCrossings) + ' pairs)');
    ui.qualitySummary.className = 'quality-summary ' + (look.length ? 'look' : 'ok');
    ui.qualitySummary.textContent = look.length ? 'Worth a look: ' + look.join('; ') + '.'
                                                : 'All checks passed: no folds and no self-intersections.';
  }

  app.showQuality = showQuality;  // tests: the wording for a head that does cross itself

  async function checkFitQuality(fit) {
    fit.quality = null;
    ui.fitQuality.hidden = false;
    ui.showDistance.disabled = true;
    ui.fitQuality.classList.add('checking');
    ui.qualityTitle.textContent = 'Checks';
    ui.qualitySummary.className = 'quality-summary';
    ui.qualitySummary.textContent = 'checking… (folds and self-intersections of the finest level; animate or export meanwhile)';
    ui.qualityList.replaceChildren();
    let q;
    try {
      q = await runJob({ type: 'quality' }, []);
    } catch (e) {
      q = { ok: false, message: e && e.cancelled ? 'cancelled' : (e && e.message ? e.message : String(e)) };
    }
    if (app.fit !== fit) return;  // a newer fit, or none, is shown now
    ui.fitQuality.classList.remove('checking');
    if (!q.ok) {
      fit.quality = { ok: false, message: q.message || q.code };
      ui.qualitySummary.textContent = 'The checks could not run: ' + (q.message || q.code) + '.';
      return;
    }
    fit.quality = q;
    showQuality(q);
    ui.showDistance.disabled = !distanceMap(true);
    ui.exportMap.disabled = ui.exportObj.disabled || !distanceMap(true);
    if (ui.showDistance.checked && app.shownStage === 'subdivide') showStage('subdivide');
  }

  // The finest level's distance map from the checks (faceToScan.colors), or
  // null; anyLevel: whether there is one at all, else only while the finest
  // level is the one shown.
  function distanceMap(anyLevel = false) {
    const q = app.fit && app.fit.quality;
    const colors = q && q.ok && q.faceToScan && q.faceToScan.colors;
    if (!colors || !colors.length) return null;
    return anyLevel || shownLevel() === q.level ? colors : null;
  }

  // Shows a fit stage's mesh over the scan points, keeping the view.
  function fitMesh(row) {
    const m = app.fit.meshes;
    if (row === 'align') return m.aligned;
    if (row === 'local_fit') return m.local;
    if (row === 'global_fit') return m.control;
    const level = shownLevel();  // the chosen level, or the adaptation's while moving
    return level === 0 ? m.control : m.levels[level - 1];
  }

  // The generic eyeballs (iris texture), teeth and tongue of tarini2002
  // Sec. 4, placed by the worker from the fitted eye rims and lips. Drawn
  // with the subdivided head only (the earlier stages are not the final
  // shape); at rest, they do not follow the animated jaw.
  function showComponents(c) {
    app.viewer.clear_components();
    app.components = 0;
    app.componentsData = c || null;
    app.componentTextures = { eyes: 'none', teeth: 'none', teethTextured: false };
    if (!c) return;
    // A photo's iris / teeth texture replaces the generic one.
    const eyeTexture = app.eyePhoto ? app.eyePhoto.texture : c.eyeTexture;
    const teethTexture = app.smilePhoto ? app.smilePhoto.texture : c.teethTexture;
    const none = new Float32Array(0);
    const errors = [];
    const add = (m, texture) => {
      const t = texture || { width: 0, height: 0, channels: 0, pixels: new Uint8Array(0) };
      const err = app.viewer.add_component(m.positions, m.indices, m.colors || none, texture ? m.uvs : none,
                                           t.width, t.height, t.channels, t.pixels);
      if (err) errors.push(err); else app.components++;
    };
    app.jawComponents = [];
    const eyeTextured = !!eyeTexture && (c.eyes || []).every((eye) => !!eye.uvs);
    for (const eye of c.eyes || []) add(eye, eyeTextured ? eyeTexture : null);
    const teethTextured = !!teethTexture && !!c.teeth && !!c.teeth.uvs;
    if (c.teeth) add(c.teeth, teethTextured ? teethTexture : null);
    // The lower teeth and the tongue ride on the jaw (animate's jawMatrix).
    for (const [m, tex] of [[c.lowerTeeth, teethTextured && c.lowerTeeth && c.lowerTeeth.uvs ? teethTexture : null], [c.tongue, null]]) {
      if (!m) continue;
      const before = app.components;
      add(m, tex);
      if (app.components > before) app.jawComponents.push(before);
    }
    if (errors.length) console.warn('components not shown:', errors.join('; '));
    app.componentTextures = {
      eyes: !eyeTextured ? 'none' : app.eyePhoto ? 'photo:' + app.eyePhoto.name : 'generic',
      teeth: !teethTextured ? 'none' : app.smilePhoto ? 'photo:' + app.smilePhoto.name : 'generic',
      teethTextured: teethTextured && !errors.length,
    };
  }

  // quiet: no status line; posed: positions to show instead of the rest pose
  // (the adaptation swapping levels while moving).
  function showStage(row, quiet = false, posed = null) {
    if (!app.fit) return;
    app.viewer.set_components_visible(row === 'subdivide' && ui.showComponents.checked);
    if (row !== 'subdivide') stopAnimation(true, false);
    const mesh = fitMesh(row);
    const t = app.texture;
    const map = row === 'subdivide' && ui.showDistance.checked ? distanceMap() : null;
    const textured = row === 'subdivide' && t && !map;
    const err = map
      ? app.viewer.show_mesh_keep_view(posed || mesh.positions, null, map, mesh.indices)
      : textured
      ? app.viewer.show_textured_mesh(posed || mesh.positions, mesh.indices, t.uvs.subarray(0, 2 * mesh.vertexCount),
                                      t.skin.width, t.skin.height, t.skin.channels, t.skin.pixels)
      : app.viewer.show_mesh_keep_view(posed || mesh.positions, null, null, mesh.indices);
    if (err) { showError('Could not show the ' + row + ' mesh: ' + err); return; }
    viewerLevel = row === 'subdivide' ? shownLevel() : null;
    ui.distanceLegend.hidden = !map;
    markShown(row);
    if (quiet) return;
    const what = row === 'subdivide' ? (ui.level.value === '0' ? 'control mesh' : 'level ' + ui.level.value)
      : stageItem(row).querySelector('.stage-name').textContent + ' result';
    // A new fit's checks may not be in yet (fit.quality null): no map, no note.
    const mapNote = map ? ' coloured by its distance to the scan: white within 0.25 mm, yellow 1 mm, red 3 mm or more, ' +
                          'blue-grey not measured (outside the face, or not scanned)'
      : row === 'subdivide' && ui.showDistance.checked && distanceMap(true) ? ' (the distance map is of level ' + app.fit.quality.level + ')' : '';
    setStatus('Showing the ' + (textured ? 'textured ' : '') + what + ' (' + mesh.vertexCount.toLocaleString('en') + ' vertices, ' +
              mesh.triangleCount.toLocaleString('en') + ' triangles)' + mapNote + (ui.showPoints.checked ? ' over the scan points.' : '.'));
  }

  // ---- texturing (tarini2002 Sec. 3) ---------------------------------------------
  function forgetTexture() {
    app.texture = null;
    setStage('texture', 'waiting', 0);
    stageItem('texture').querySelector('.stage-stats').textContent = '';
    ui.textureTotal.textContent = '';
  }

  // Calibrates every photo that has correspondences and textures the fitted
  // head in the worker; the viewer then shows the skin on the chosen level.
  async function runTexture() {
    const state = document.body.dataset.state;
    if (state === 'working' || state === 'loading' || app.startupFailed) return;
    clearError();
    if (!app.fit) { showError('Fit the head before texturing it: the texture is laid on the fitted head.'); return; }
    const using = texturable();
    if (!facePhotos().length) {
      showError(app.photos.length ? 'No photo has the role "Face (skin)": only face photos texture the skin.'
        : 'Drop one or more photos of the head (JPG or PNG) to texture it.');
      return;
    }
    if (!using.length) {
      showError('No photo has correspondences yet: drop each photo\'s points file (same name, .txt) or click a photo ' +
                'to mark its landmarks (at least 6 each).');
      return;
    }
    const few = using.filter((p) => photoPoints(p).list.length < 6);
    if (few.length) {
      showError(few.map((p) => p.name + ' has ' + photoPoints(p).list.length + ' point(s)').join('; ') +
                '. Calibrating a photo needs at least 6 correspondences (12-15 spread over the face are best): ' +
                'click more landmarks or skip the photo by clearing its clicks.');
      return;
    }
    stopAnimation();
    setState('working');
    stageItem('texture').classList.remove('coming');
    setStage('texture', '0%', 0, 'active');
    setStatus('Texturing the head from ' + using.length + ' photo(s)…');
    const t0 = performance.now();
    let result;
    try {
      const photos = [];
      for (const p of using) {
        const pts = photoPoints(p);
        p.sent = pts.list.map((x) => ({ label: x.label }));
        const flat = new Float64Array(pts.list.length * 5);
        pts.list.forEach((x, k) => flat.set([x.u, x.v, x.p[0], x.p[1], x.p[2]], 5 * k));
        photos.push({ name: p.name, buffer: await p.file.arrayBuffer(), points: flat });
      }
      const size = Number(params.get('texture_size')) > 0 ? Number(params.get('texture_size')) : 1024;
      result = await runJob({ type: 'texture', photos, options: { size } }, photos.map((p) => p.buffer),
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
        setState('done');
        return;
      }
      result = { ok: false, code: 'Internal', message: e && e.message ? e.message : String(e) };
    }
    const wallMs = performance.now() - t0;
    // Per-photo calibration outcomes (also on failure: the page marks bad points).
    if (result.calib) using.forEach((p, i) => { p.calib = result.calib[i] || null; });
    renderPhotos();
    if (clicker.photo) updateClicker();
    if (!result.ok) {
      setStage('texture', 'failed', 0, 'failed');
      setStatus('Texturing failed; your points and clicks are kept.' + (app.fit ? ' The fitted head is still shown.' : ''));
      showError('Texture: ' + (result.message || result.code));
      return;
    }
    app.texture = { uvs: result.uvs, skin: result.skin, steps: result.steps, textureMs: result.textureMs, wallMs,
                    level: result.level, photos: using.length };
    setStage('texture', Math.round(result.textureMs) + ' ms', 1, 'complete');
    const rms = using.map((p) => p.calib && p.calib.ok ? p.calib.rms : NaN).filter((x) => !Number.isNaN(x));
    stageItem('texture').querySelector('.stage-stats').textContent = using.length + ' photo(s), calibration rms ' +
      (rms.length ? Math.min(...rms).toFixed(2) + '-' + Math.max(...rms).toFixed(2) : '?') + ' px · ' +
      result.skin.width + '² texels · ' + result.steps.map((x) => x.name + ' ' + Math.round(x.ms)).join(', ') + ' ms';
    ui.textureTotal.textContent = 'textured in ' + (result.textureMs / 1000).toFixed(2) + ' s';
    ui.showPoints.checked = false;
    app.viewer.set_overlay_visible(false);
    closeClicker();
    showStage('subdivide');
    setStatus('Textured from ' + using.length + ' photo(s) in ' + (result.textureMs / 1000).toFixed(2) + ' s. ' +
              'Animate it, pick a level, or export the textured head.');
    setState('done');
  }
  app.textureHead = () => runTexture();

  async function exportTextured() {
    if (!app.fit || !app.texture) return;
    const level = Number(ui.level.value);
    const base = app.fit.name.replace(/\.[^.]*$/, '') + '_textured' + (level === 0 ? '_control' : '_level' + level);
    try {
      const r = await runJob({ type: 'exportTextured', level, base }, []);
      if (!r.ok) { showError('Export failed: ' + r.message); return; }
      download(base + '.obj', r.obj, 'model/obj');
      download(base + '.mtl', r.mtl, 'model/mtl');
      download(base + '.png', r.png, 'image/png');
      setStatus('Exported ' + base + '.obj, .mtl and .png.');
    } catch (e) {
      showError('Export failed: ' + (e && e.message ? e.message : e));
    }
  }

  // ---- animation (jeong2002 Sec. 6: local update of the multires head) --------
  // The worker owns the MultiresMesh; each frame asks it for one pose and
  // uploads the returned level positions into the shown mesh.
  // Frames are double-buffered: the next pose is requested as soon as one is
  // handed to the viewer, so the worker computes frame n+1 while frame n is
  // uploaded and drawn. At most one job is in flight, and a pose is uploaded
  // only after the previous one was drawn, so no work is thrown away (on two
  // cores a worker running ahead would steal the CPU the drawing needs).
  //
  // Adaptive detail while moving: without a GPU (SwiftShader, llvmpipe, VMs)
  // a level-3 frame costs 140-250 ms, so while the head moves the page steps
  // down along a ladder of cheaper renderings (subdivision level and
  // drawing-buffer scale, in the order measured in docs/web.md "Adaptive
  // detail while animating") whenever the frames of a short window are
  // slower than the budget, and back up when there is headroom.
  // Only what is drawn while moving changes: the Level select, export and
  // texturing always use the chosen level, and stopping shows the chosen
  // level at full resolution again. "Full detail while animating" turns it off.
  const ADAPT_BUDGET_MS = Number(params.get('anim_budget_ms')) > 0 ? Number(params.get('anim_budget_ms')) : 1000 / 15;
  const ADAPT_WINDOW = 4;          // frames averaged before a decision (2-4 fps: about a second)
  const ADAPT_UP_FRACTION = 0.55;  // step up only below this share of the budget...
  const ADAPT_MEMORY_MS = 15000;   // ...and not onto a step measured too slow within this time
  // The ladder for a chosen level: each step is what is drawn while moving.
  // Measured on SwiftShader (docs/web.md): level 3 -> 2 nearly triples the
  // frame rate for the smallest visible change (0.3 % of pixels), while a
  // lower scale on level 3 gains little (its triangles, not its pixels, cost);
  // so the level drops to 2 first (what the paper animated), then the scale,
  // then the level again.
  function adaptLadder(chosen) {
    const moving = Math.min(chosen, 2);
    const steps = [{ level: chosen, scale: 1 }];
    if (moving < chosen) steps.push({ level: moving, scale: 1 });
    steps.push({ level: moving, scale: 0.75 }, { level: moving, scale: 0.5 });
    for (let l = moving - 1; l >= Math.min(1, moving); --l) steps.push({ level: l, scale: 0.5 });
    return steps;
  }
  app.animation.adaptive = { enabled: true, budgetMs: ADAPT_BUDGET_MS, step: 0, level: null, scale: 1,
                             frameMs: 0, changes: 0, ladder: [] };
  // Last settled step per chosen level, so the next start begins there.
  const adaptStartStep = {};
  let adaptIntervals = [], adaptLastPoseT = 0, adaptSlow = {};
  let viewerLevel = null;  // the level of the fit mesh in the viewer (null: another stage or mesh)

  // The level drawn now: the chosen one, or the adaptation's while moving.
  function shownLevel() {
    const a = app.animation;
    return a.running && a.adaptive.level !== null ? a.adaptive.level : Number(ui.level.value);
  }

  // Puts step `step` of the ladder on screen: the scale at once; a new level
  // with its first pose (applyPose swaps the mesh, so the head never jumps
  // back to the rest pose), dropping a pose of the old level in flight.
  function applyAdaptStep(step) {
    const ad = app.animation.adaptive;
    const s = ad.ladder[step];
    if (!s) return;
    const levelChanged = s.level !== shownLevel();
    ad.step = step;
    ad.scale = s.scale;
    app.viewer.set_render_scale(s.scale);
    ad.level = s.level;
    adaptIntervals = [];
    adaptLastPoseT = 0;
    if (levelChanged) {
      animGeneration++;               // an in-flight pose of the old level is dropped
      requestPose();
    }
  }

  // Back to the chosen level at full resolution (nothing temporary left).
  function restoreFullDetail() {
    const ad = app.animation.adaptive;
    const wasLevel = ad.level;
    ad.level = null;
    ad.step = 0;
    ad.scale = 1;
    ad.frameMs = 0;
    adaptIntervals = [];
    adaptLastPoseT = 0;
    if (app.viewer) app.viewer.set_render_scale(1);
    return (wasLevel !== null && wasLevel !== Number(ui.level.value)) || viewerLevel !== Number(ui.level.value);
  }

  // Called once per pose put on screen: measures the frame time over a short
  // window and steps down (too slow) or up (headroom).
  function adaptAfterFrame(now) {
    const a = app.animation, ad = a.adaptive;
    if (adaptLastPoseT > 0) adaptIntervals.push(now - adaptLastPoseT);
    adaptLastPoseT = now;
    if (!ad.enabled || adaptIntervals.length < ADAPT_WINDOW) return;
    const ms = adaptIntervals.reduce((s, x) => s + x, 0) / adaptIntervals.length;
    adaptIntervals.shift();
    ad.frameMs = ms;
    if (ms > ad.budgetMs && ad.step + 1 < ad.ladder.length) {
      adaptSlow[ad.step] = { ms, t: now };
      ad.changes++;
      applyAdaptStep(ad.step + 1);
    } else if (ms < ADAPT_UP_FRACTION * ad.budgetMs && ad.step > 0) {
      const slow = adaptSlow[ad.step - 1];
      if (slow && now - slow.t < ADAPT_MEMORY_MS) return;
      ad.changes++;
      applyAdaptStep(ad.step - 1);
    }
    adaptStartStep[Number(ui.level.value)] = ad.step;
  }

  function setAdaptive(on) {
    const a = app.animation, ad = a.adaptive;
    ad.enabled = on;
    for (const k of Object.keys(adaptStartStep)) delete adaptStartStep[k];  // start over from full detail
    if (!a.running) return;
    if (!on && ad.step !== 0) applyAdaptStep(0);
    adaptIntervals = [];
    adaptLastPoseT = 0;
  }

  function animStatsText(a, r) {
    const ad = a.adaptive;
    const parts = [(a.fps < 10 ? a.fps.toFixed(1) : a.fps.toFixed(0)) + ' fps'];
    if (!ad.enabled) parts.push('full detail');
    else if (ad.step > 0) {
      const chosen = Number(ui.level.value);
      if (ad.level !== chosen) parts.push((ad.level === 0 ? 'control mesh' : 'level ' + ad.level) + ' while moving');
      if (ad.scale !== 1) parts.push(Math.round(ad.scale * 100) + ' % resolution');
    }
    parts.push('update ' + a.updateMs.toFixed(1) + ' ms');
    parts.push(r.changed.toLocaleString('en') + ' of ' + r.vertexCount.toLocaleString('en') + ' vertices');
    return parts.join(' · ');
  }

  let animT0 = 0, animFpsT = 0, animFpsFrames = 0, animGeneration = 0, animDrawnAtUpload = -1;
  function requestPose() {
    const a = app.animation;
    if (!a.running || !app.fit) return;
    const generation = animGeneration;
    const t = (performance.now() - animT0) / 1000;
    const amount = 0.5 - 0.5 * Math.cos(t * Math.PI);  // open and close every 2 s
    const tJob = performance.now();
    const level = shownLevel();
    runJob({ type: 'animate', amount, level }, []).then((r) => {
      if (!a.running || generation !== animGeneration) return;
      if (!r.ok) { stopAnimation(); showError('Animation: ' + r.message); return; }
      a.profile.jobMs += performance.now() - tJob;
      applyPose(r, generation, level);
    }, () => stopAnimation());
  }

  function applyPose(r, generation, level) {
    const a = app.animation;
    if (!a.running || generation !== animGeneration) return;
    const viewer = app.viewer;
    if (viewer.frames_drawn() === animDrawnAtUpload) {  // the last pose is not on screen yet
      requestAnimationFrame(() => applyPose(r, generation, level));
      return;
    }
    const tUpload = performance.now();
    if (level !== viewerLevel) {  // the adaptation's new level: its mesh, in this pose
      showStage('subdivide', true, r.positions);
      if (viewerLevel !== level) { stopAnimation(); return; }  // showStage said why
    } else {
      const err = viewer.update_positions(r.positions);
      if (err) { stopAnimation(); showError('Animation: ' + err); return; }
    }
    moveJaw(r.jawMatrix);
    animDrawnAtUpload = viewer.frames_drawn();
    const p = a.profile;
    p.frames++;
    p.workerMs += r.workerMs || 0;
    p.coreMs += r.updateMs;
    p.uploadMs += performance.now() - tUpload;
    p.drawMs += viewer.last_draw_ms();
    requestPose();
    a.frames++;
    animFpsFrames++;
    a.updateMs = r.updateMs;
    const now = performance.now();
    if (now - animFpsT > 500 || a.fps === 0) {
      a.fps = animFpsFrames * 1000 / (now - animFpsT);
      animFpsT = now;
      animFpsFrames = 0;
    }
    adaptAfterFrame(now);
    ui.animStats.textContent = animStatsText(a, r);
  }

  function startAnimation() {
    if (!app.fit || app.animation.running) return;
    if (app.shownStage !== 'subdivide') showStage('subdivide');
    const a = app.animation;
    Object.assign(a, { running: true, frames: 0, fps: 0,
      profile: { frames: 0, jobMs: 0, workerMs: 0, coreMs: 0, uploadMs: 0, drawMs: 0 } });
    animT0 = animFpsT = performance.now();
    animFpsFrames = 0;
    animGeneration++;
    animDrawnAtUpload = -1;
    ui.animate.checked = true;
    const ad = a.adaptive;
    const chosen = Number(ui.level.value);
    ad.ladder = adaptLadder(chosen);
    ad.level = chosen;
    ad.step = 0;
    ad.changes = 0;
    adaptSlow = {};
    // Begin where the last run at this level settled (no second slideshow).
    const start = ad.enabled ? Math.min(adaptStartStep[chosen] || 0, ad.ladder.length - 1) : 0;
    if (start > 0) applyAdaptStep(start);  // re-shows the mesh and requests the first pose
    else requestPose();
  }

  function moveJaw(matrix) {
    if (!matrix || !app.jawComponents) return;
    for (const i of app.jawComponents) app.viewer.set_component_matrix(i, matrix);
  }

  // Stops and (restPose) puts the head back at rest, the pose export writes,
  // at the chosen level and full resolution. reshow=false when the caller
  // shows another mesh right after.
  function stopAnimation(restPose = true, reshow = true) {
    const a = app.animation;
    ui.animate.checked = false;
    if (!a.running) return;
    a.running = false;
    animGeneration++;  // a pose still in flight is dropped
    const levelWasTemporary = restoreFullDetail();
    if (levelWasTemporary && reshow && app.fit && app.shownStage === 'subdivide') showStage('subdivide');
    if (!app.fit || !restPose) return;
    const level = Number(ui.level.value);
    runJob({ type: 'animate', amount: 0, level }, []).then((r) => {
      if (r.ok && app.shownStage === 'subdivide' && !app.animation.running && viewerLevel === level &&
          r.vertexCount === fitMesh('subdivide').vertexCount) {
        app.viewer.update_positions(r.positions);
        moveJaw(r.jawMatrix);
      }
    }, () => {});
  }

  // ---- export -----------------------------------------------------------------
  function download(name, bytes, mime) {
    const url = URL.createObjectURL(new Blob([bytes], { type: mime }));
    const a = document.createElement('a');
    a.href = url;
    a.download = name;
    document.body.appendChild(a);
    a.click();
    a.remove();
    setTimeout(() => URL.revokeObjectURL(url), 10000);
    app.downloads.push({ name, size: bytes.length });
  }

  async function exportHead(format) {
    if (!app.fit) return;
    const level = Number(ui.level.value);
    const base = app.fit.name.replace(/\.[^.]*$/, '') + '_head';
    const wanted = [{ level, name: base + (level === 0 ? '_control' : '_level' + level) + '.' + format }];
    if (format === 'obj' && level !== 0) wanted.push({ level: 0, name: base + '_control.obj' });
    try {
      for (const w of wanted) {
        const r = await runJob({ type: 'export', level: w.level, format }, []);
        if (!r.ok) { showError('Export failed: ' + r.message); return; }
        download(w.name, r.bytes, format === 'obj' ? 'model/obj' : 'application/octet-stream');
      }
      setStatus('Exported ' + wanted.map((w) => w.name).join(' and ') + '.');
    } catch (e) {
      showError('Export failed: ' + (e && e.message ? e.message : e));
    }
  }

  // The checks' distance map: the finest level at rest with the colours of
  // "Distance to scan" (as likeness fit's face_to_scan.ply).
  async function exportMap() {
    if (!app.fit || !distanceMap(true)) return;
    const name = app.fit.name.replace(/\.[^.]*$/, '') + '_head_distance_map.ply';
    try {
      const r = await runJob({ type: 'export', level: app.fit.quality.level, format: 'map' }, []);
      if (!r.ok) { showError('Export failed: ' + r.message); return; }
      download(name, r.bytes, 'application/octet-stream');
      setStatus('Exported ' + name + ' (level ' + app.fit.quality.level + ' at rest).');
    } catch (e) {
      showError('Export failed: ' + (e && e.message ? e.message : e));
    }
  }

  // ---- wiring -----------------------------------------------------------------
  function wire() {
    ui.maxSize.textContent = formatBytes(MAX_SCAN_BYTES);
    // ?autofit=0 starts with Auto-run off (load scans without fitting them).
    if (params.get('autofit') === '0') ui.autoFit.checked = false;
    // ?full_detail=1 starts with the animation's adaptive detail off.
    if (params.get('full_detail') === '1') { ui.fullDetail.checked = true; setAdaptive(false); }
    ui.fileInput.addEventListener('change', () => {
      const files = ui.fileInput.files;
      handleFiles(files).finally(() => { ui.fileInput.value = ''; });
    });
    // Dropping anywhere on the page counts, so a near miss never makes the
    // browser navigate away to the file.
    let dragDepth = 0;
    window.addEventListener('dragenter', (e) => { e.preventDefault(); dragDepth++; ui.dropZone.classList.add('over'); });
    window.addEventListener('dragleave', () => { if (--dragDepth <= 0) { dragDepth = 0; ui.dropZone.classList.remove('over'); } });
    window.addEventListener('dragover', (e) => e.preventDefault());
    window.addEventListener('drop', (e) => {
      e.preventDefault();
      dragDepth = 0;
      ui.dropZone.classList.remove('over');
      handleFiles(e.dataTransfer && e.dataTransfer.files);
    });
    ui.dismiss.addEventListener('click', clearError);
    ui.sample.addEventListener('click', loadSample);
    ui.cancel.addEventListener('click', cancelJobs);
    ui.reset.addEventListener('click', () => app.viewer && app.viewer.reset_view());
    ui.generic.addEventListener('click', () => {
      if (!app.viewer) return;
      stopAnimation();
      app.viewer.show_generic_head();
      app.viewer.set_overlay_points(new Float32Array(0), null, null);
      app.viewer.set_components_visible(false);
      markShown(null);
      app.model = null;
      clearError();
      setStatus('Showing the generic head model.');
    });
    // Keyboard control of the focused canvas. Only the view keys are taken;
    // Tab and everything else keep their usual meaning.
    ui.canvas.addEventListener('keydown', (e) => {
      const v = app.viewer;
      if (!v || e.ctrlKey || e.metaKey || e.altKey) return;
      const step = 40;  // pixels of drag per key press
      const arrows = { ArrowLeft: [-step, 0], ArrowRight: [step, 0], ArrowUp: [0, -step], ArrowDown: [0, step] };
      if (arrows[e.key]) {
        const [dx, dy] = arrows[e.key];
        if (e.shiftKey) v.pan(dx, dy); else v.orbit(dx, dy);
      } else if (e.key === '+' || e.key === '=') v.zoom(120);
      else if (e.key === '-' || e.key === '_') v.zoom(-120);
      else if (e.key === 'r' || e.key === 'R') v.reset_view();
      else return;
      e.preventDefault();
    });
    ui.fit.addEventListener('click', runFit);
    for (const st of FIT_STAGES) {
      const li = stageItem(st.row);
      li.addEventListener('click', () => { if (li.classList.contains('viewable')) showStage(st.row); });
      li.addEventListener('keydown', (e) => {
        if ((e.key === 'Enter' || e.key === ' ') && li.classList.contains('viewable')) { e.preventDefault(); showStage(st.row); }
      });
    }
    // Another level, or the distance map on or off: the head shown again,
    // an animation restarted around it.
    const reshowHead = () => {
      const wasRunning = app.animation.running;
      if (wasRunning) { app.animation.running = false; animGeneration++; restoreFullDetail(); ui.animate.checked = false; }
      showStage('subdivide');
      if (wasRunning) startAnimation();
    };
    ui.level.addEventListener('change', reshowHead);
    ui.showDistance.addEventListener('change', () => {
      // The scan's points would hide the colours: off with the map on (the
      // user may turn them back on).
      if (ui.showDistance.checked && ui.showPoints.checked) {
        ui.showPoints.checked = false;
        if (app.viewer) app.viewer.set_overlay_visible(false);
      }
      if (app.fit && app.shownStage === 'subdivide') reshowHead();
    });
    ui.showPoints.addEventListener('change', () => {
      if (!app.viewer) return;
      app.viewer.set_overlay_visible(ui.showPoints.checked);
      const text = ui.status.textContent;
      if (/^Showing /.test(text)) setStatus(text.replace(/( over the scan points)?\.$/, ui.showPoints.checked ? ' over the scan points.' : '.'));
    });
    ui.animate.addEventListener('change', () => (ui.animate.checked ? startAnimation() : stopAnimation()));
    ui.fullDetail.addEventListener('change', () => setAdaptive(!ui.fullDetail.checked));
    ui.showComponents.addEventListener('change', () => {
      if (app.viewer) app.viewer.set_components_visible(ui.showComponents.checked && app.shownStage === 'subdivide');
    });
    ui.exportObj.addEventListener('click', () => exportHead('obj'));
    ui.exportPly.addEventListener('click', () => exportHead('ply'));
    ui.exportTextured.addEventListener('click', exportTextured);
    ui.exportMap.addEventListener('click', exportMap);
    ui.texture.addEventListener('click', runTexture);
    ui.clickerCanvas.addEventListener('click', clickerClick);
    ui.clickerUndo.addEventListener('click', clickerUndo);
    ui.clickerSkip.addEventListener('click', clickerSkip);
    ui.clickerClear.addEventListener('click', clickerClear);
    ui.clickerClose.addEventListener('click', closeClicker);
    window.addEventListener('resize', () => drawClicker());
    ui.clicker.addEventListener('keydown', (e) => {
      if (e.key === 'Escape') closeClicker();
      else if ((e.ctrlKey || e.metaKey) && e.key === 'z') { e.preventDefault(); clickerUndo(); }
    });
    ui.wireframe.addEventListener('change', () => app.viewer && app.viewer.set_wireframe(ui.wireframe.checked));
    ui.pointSize.addEventListener('input', () => app.viewer && app.viewer.set_point_size(Number(ui.pointSize.value)));
  }

  // Said when the page could have run the threaded core but it did not start
  // (worker.js fell back to one thread): the fit is slower, its result the same.
  function threadsNote() {
    const why = app.workerThreads && app.workerThreads.fallback;
    return why ? ' Note: the multi-threaded core could not start in this browser (' + why +
                 '), so the core runs on one thread: slower, same results.' : '';
  }

  async function start() {
    setState('loading');
    wire();
    setStatus('Starting the viewer and the core…');
    let coreFailed = null;
    try {
      const workerUp = startWorker().catch((e) => { coreFailed = e; throw e; });
      workerUp.catch(() => {});  // handled below, after the viewer
      const viewer = await startViewer();
      await workerUp;
      viewer.set_point_size(Number(ui.pointSize.value));
      // ?profile=1: the viewer waits for each draw to finish (glFinish) so
      // animation.profile can split a frame's time; it slows drawing down.
      if (params.get('profile') === '1') viewer.set_profiling(true);
      app.loadMs = performance.now() - app.startedAt;
      warmUp(app.workerThreads.variant).catch(() => {});
      setState('ready');
      setStatus('Ready. Showing the generic head. Drop a head scan to begin.' + threadsNote());
    } catch (e) {
      const why = e && e.message ? e.message : String(e);
      if (coreFailed) {
        // The viewer may be fine; the core (WebAssembly in a Web Worker) is not.
        fatalStartup('The core of Likeness could not start: ' + why + '. Reload the page to try again' +
                     ' (if it keeps failing, the site is missing files: scripts/build makes them).');
      } else {
        fatalStartup('Could not start Likeness: ' + why + '. This app needs WebGL 2 and WebAssembly.');
      }
    }
  }

  if (document.readyState === 'loading') document.addEventListener('DOMContentLoaded', start);
  else start();
})();
