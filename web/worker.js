// The Web Worker that runs the core (likeness_worker.wasm) off the main thread.
//
// Messages in:  {type:<job>, id, ...job fields}; ArrayBuffers are transferred.
// Messages out: {type:'ready', threads, variant}      the core is up; threads = how many
//                                                     threads a loop of the core uses
//               {type:'progress', id, stage, fraction} from the job's ProgressFn
//               {type:'result', id, result}           the core's {ok, code, message, ...};
//                                                     typed arrays are transferred back
//               {type:'fatal', message}               the module aborted (out of memory,
//                                                     a bug): the page starts a new worker
// To add a stage: bind it in wasm/worker_bindings.cpp (bytes as pointer+size,
// a progress function, a {ok, code, message, ...} result) and add it to JOBS.
//
// Two builds of the same core: likeness_worker_mt (pthreads: the fit's
// parallel loops on up to 4 cores, same results as one thread) needs
// SharedArrayBuffer, which the browser only gives a cross-origin isolated
// page (served with COOP: same-origin + COEP: require-corp, as scripts/serve.py
// does); anywhere else, or with worker.js?threads=1, the single-threaded
// likeness_worker runs.
'use strict';
const wantThreads = self.crossOriginIsolated === true && typeof SharedArrayBuffer === 'function'
  && new URLSearchParams(self.location.search).get('threads') !== '1';

let core = null;
let variant = null;  // 'threads' | 'single': the core that runs
const pending = [];

function fatal(message) {
  postMessage({ type: 'fatal', message: String(message) });
}

// The wasm heap as bytes. In the threaded build the memory is shared and may
// have been grown by another thread since the module's own views were made,
// so the view is taken over the memory's current buffer.
function heapBytes() {
  return core.wasmMemory ? new Uint8Array(core.wasmMemory.buffer) : core.HEAPU8;
}

// Loads and starts one core. The threaded one falls back to the single-
// threaded one when its files are missing or it cannot start (e.g. a
// browser that refuses nested workers), so the page always gets a core.
function startCore(which) {
  try {
    importScripts(which === 'threads' ? 'likeness_worker_mt.js' : 'likeness_worker.js');
  } catch (e) {
    if (which === 'threads') {
      console.warn('[worker] the threaded core did not load (' + (e && e.message ? e.message : e) + '): one thread');
      startCore('single');
    } else {
      fatal('could not load the core: ' + (e && e.message ? e.message : e));
    }
    return;
  }
  LikenessWorker({
    // The pthread workers load the module's script by URL (this worker's
    // own URL is worker.js, which they must not run).
    mainScriptUrlOrBlob: new URL('likeness_worker_mt.js', self.location.href).href,
    print: (t) => console.log('[worker]', t),
    printErr: (t) => console.warn('[worker]', t),
    // A release build aborts without a reason on out-of-memory; say what is
    // likely. (Before the core is up, the rejection below handles it.)
    onAbort: (what) => { if (core) fatal(what ? 'the core stopped: ' + what
      : 'the core ran out of memory at ' + Math.round(heapBytes().length / 1048576) + ' MB of wasm heap'); },
  }).then((m) => {
    core = m;
    variant = which;
    postMessage({ type: 'ready', variant, threads: core.parallel_workers() });
    while (pending.length) handle(pending.shift());
  }, (err) => {
    if (which === 'threads') {
      console.warn('[worker] the threaded core did not start (' + err + '): one thread');
      startCore('single');
    } else {
      fatal('could not start the core: ' + err);
    }
  });
}
startCore(wantThreads ? 'threads' : 'single');

// Copies the bytes into the wasm heap, runs fn(pointer, size), frees the copy.
function withHeapBytes(buffer, fn) {
  const bytes = new Uint8Array(buffer);
  const ptr = core._malloc(Math.max(1, bytes.length));
  if (!ptr) return { ok: false, code: 'TooLarge', message: 'not enough memory to hold the file (' + bytes.length + ' bytes)' };
  try {
    heapBytes().set(bytes, ptr);
    return fn(ptr, bytes.length);
  } finally {
    core._free(ptr);
  }
}

// job name -> (message, progress) -> result
const JOBS = {
  // {name, buffer}: a dropped PLY / OBJ / XYZ / VTK file -> geometry arrays.
  parse: (msg, progress) =>
    withHeapBytes(msg.buffer, (ptr, size) => core.parse_geometry(msg.name, ptr, size, progress)),
  // {name, buffer}: a dropped photo -> {width, height, channels} once decoded.
  image: (msg) => withHeapBytes(msg.buffer, (ptr, size) => core.check_image(msg.name, ptr, size)),
  // {name, buffer, options}: a scan -> the fitted head (jeong2002 Sec. 4-5),
  // kept in this worker for 'animate' and 'export'. Progress per stage.
  fit: (msg, progress) =>
    withHeapBytes(msg.buffer, (ptr, size) => core.fit_head_job(msg.name, ptr, size, msg.options || {}, progress)),
  // {amount, level}: one animation frame of the kept head (local update).
  animate: (msg) => core.animate_frame(msg.amount, msg.level),
  // {level, format: 'obj'|'ply'}: the kept head as file bytes.
  export: (msg) => core.export_head(msg.level, msg.format),
  // {text}: a points file (u v X Y Z per line) -> {points: Float64Array}.
  points: (msg) => core.parse_points(String(msg.text)),
  // {photos: [{name, buffer, points: Float64Array}], options}: calibrate each
  // photo and texture the kept head (tarini2002 Sec. 3). Progress 'texture'.
  texture: (msg, progress) => withManyHeapBytes(msg.photos || [], (placed) =>
    core.texture_job(placed, msg.options || {}, progress)),
  // {level, base}: the textured head as {obj, mtl, png} bytes.
  exportTextured: (msg) => core.export_textured(msg.level, String(msg.base)),
  // {name, buffer, guess?: [x, y]}: an eye photo -> the eyeball (iris) texture.
  eye: (msg) => withHeapBytes(msg.buffer, (ptr, size) => core.eye_photo_job(msg.name, ptr, size, msg.guess || null)),
  // {name, buffer}: a smile photo -> the teeth texture (teeth model's uvs).
  smile: (msg) => withHeapBytes(msg.buffer, (ptr, size) => core.smile_photo_job(msg.name, ptr, size)),
};

// withHeapBytes for a list of {name, buffer, points}: fn gets
// [{name, ptr, size, points}]; every copy is freed afterwards.
function withManyHeapBytes(items, fn) {
  const placed = [];
  try {
    for (const item of items) {
      const bytes = new Uint8Array(item.buffer || new ArrayBuffer(0));
      const ptr = core._malloc(Math.max(1, bytes.length));
      if (!ptr) return { ok: false, code: 'TooLarge', message: 'not enough memory to hold ' + item.name + ' (' + bytes.length + ' bytes)' };
      placed.push({ name: String(item.name), ptr, size: bytes.length, points: item.points || new Float64Array(0) });
      heapBytes().set(bytes, ptr);
    }
    return fn(placed);
  } finally {
    for (const p of placed) core._free(p.ptr);
  }
}

// Typed arrays anywhere in the result (fit results nest meshes) are
// transferred, not copied.
function transferables(result, out = []) {
  for (const value of Object.values(result)) {
    if (ArrayBuffer.isView(value)) { if (value.buffer.byteLength) out.push(value.buffer); }
    else if (value && typeof value === 'object') transferables(value, out);
  }
  return out;
}

function handle(msg) {
  const job = JOBS[msg.type];
  if (!job) {
    postMessage({ type: 'result', id: msg.id, result: { ok: false, code: 'Internal', message: 'unknown job ' + msg.type } });
    return;
  }
  const progress = (stage, fraction) => { postMessage({ type: 'progress', id: msg.id, stage, fraction }); };
  let result;
  const t0 = performance.now();
  try {
    result = job(msg, progress);
  } catch (e) {
    // The core returns errors as values, so only an abort or a binding
    // error (a bug) gets here; the module may be unusable afterwards.
    fatal(msg.type + ': ' + (e && e.message ? e.message : e));
    return;
  }
  // The job's time inside the worker (core + copies out of the heap), so the
  // page can tell it from the message round trip.
  if (result && typeof result === 'object') result.workerMs = performance.now() - t0;
  postMessage({ type: 'result', id: msg.id, result }, transferables(result));
}

onmessage = (e) => {
  if (!core) pending.push(e.data);
  else handle(e.data);
};
