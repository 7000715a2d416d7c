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
//               {type:'starting', step}               start-up progress (the page's watch
//                                                     restarts its clock on each)
//               {type:'startFailed', message}         no core could start (why, for the user)
//               {type:'warm', ok, fitMs, ms}          only from a ?warmup=1 worker (see WARM_UP)
// To add a stage: bind it in wasm/worker_bindings.cpp (bytes as pointer+size,
// a progress function, a {ok, code, message, ...} result) and add it to JOBS.
//
// Two builds of the same core: likeness_worker_mt (pthreads: the fit's
// parallel loops on up to 4 cores, same results as one thread) needs
// SharedArrayBuffer, which the browser only gives a cross-origin isolated
// page (served with COOP: same-origin + COEP: require-corp, as scripts/serve.py
// does); anywhere else, or with worker.js?threads=1, the single-threaded
// likeness_worker runs.
//
// The threaded core needs its pool of pthread workers (nested Web Workers)
// before it can start. Emscripten 3.1.6 waits for every pool worker to say
// 'loaded' and never gives up: a pool worker whose script fails to load, or
// a browser that never starts nested workers, would leave the page waiting
// for 'ready' forever. So the pool is watched (see startThreadedCore): an
// error from a pool worker, or a pool that is not up THREAD_START_MS after
// the module was compiled, stops the threaded core and starts the single-
// threaded one; 'ready' then carries {fallback: why} and the page says so.
//
// Each core's .wasm is fetched, compiled and instantiated here (Emscripten's
// Module.instantiateWasm hook) rather than by Emscripten 3.1.6's loader, which
// reports a failed fetch only as "failed to load wasm binary file" and waits
// forever for a download that never ends. A download with no new byte for
// CORE_STALL_MS, an HTTP error, a file that is not WebAssembly or does not
// match its .js, or a compile that takes over CORE_COMPILE_MS, fails the start
// with a message naming the file; the threaded core then falls back to the
// single-threaded one, the single-threaded one reports 'startFailed'.
'use strict';
const params = new URLSearchParams(self.location.search);
const wantThreads = self.crossOriginIsolated === true && typeof SharedArrayBuffer === 'function'
  && params.get('threads') !== '1';
// The pool of 1-3 workers loads in ~0.1 s on an idle machine (each only
// instantiates the already compiled module); 10 s leaves room for a busy one.
// ?thread_start_ms=N (forwarded by the page) shortens it for the tests.
const THREAD_START_MS = Number(params.get('thread_start_ms')) > 0 ? Number(params.get('thread_start_ms')) : 10000;
// A 1.5 MB module comes from the page's own server: 20 s without a byte is a
// server or network that will not answer. Compiling takes ~0.3 s idle (Liftoff)
// and a few seconds on a saturated machine. ?core_stall_ms, ?core_compile_ms
// (forwarded by the page) shorten them for the tests.
const numberParam = (name, fallback) => (Number(params.get(name)) > 0 ? Number(params.get(name)) : fallback);
const CORE_STALL_MS = numberParam('core_stall_ms', 20000);
const CORE_COMPILE_MS = numberParam('core_compile_ms', 60000);

let core = null;
let variant = null;  // 'threads' | 'single': the core that runs
let fallback = null;  // why the threaded core did not start (null: it did, or was not tried)
const pending = [];

function fatal(message) {
  postMessage({ type: 'fatal', message: String(message) });
}

function errorText(e) { return e && e.message ? e.message : String(e); }

function startStep(step) { postMessage({ type: 'starting', step }); }

// The bytes at url; a stall (no byte for CORE_STALL_MS) aborts the download.
async function fetchWatched(url, name) {
  const controller = new AbortController();
  let timer = 0, stalled = false;
  const arm = () => {
    clearTimeout(timer);
    timer = setTimeout(() => { stalled = true; controller.abort(); }, CORE_STALL_MS);
  };
  const noAnswer = () => new Error(name + ': no answer from the server for ' + CORE_STALL_MS / 1000 + ' s');
  arm();
  try {
    let response;
    try {
      response = await fetch(url, { credentials: 'same-origin', signal: controller.signal });
    } catch (e) {
      throw stalled ? noAnswer() : new Error(name + ' could not be downloaded (' + errorText(e) + ')');
    }
    if (!response.ok) throw new Error(name + ': the server answered HTTP ' + response.status + (response.statusText ? ' ' + response.statusText : ''));
    const reader = response.body.getReader();
    const chunks = [];
    let total = 0;
    for (;;) {
      arm();
      let part;
      try {
        part = await reader.read();
      } catch (e) {
        throw stalled ? noAnswer() : new Error(name + ': the download broke off (' + errorText(e) + ')');
      }
      if (part.done) break;
      chunks.push(part.value);
      total += part.value.length;
    }
    const bytes = new Uint8Array(total);
    let at = 0;
    for (const c of chunks) { bytes.set(c, at); at += c.length; }
    return bytes;
  } finally {
    clearTimeout(timer);
  }
}

// Emscripten's Module.instantiateWasm for the module whose binary is `file`:
// download, compile and instantiate with clear errors and time limits;
// onFail(Error) gets any failure (the module itself then never starts).
function watchedInstantiate(file, onFail) {
  return (imports, receiveInstance) => {
    (async () => {
      if (givenModule) {  // a warm-up worker: the core worker's compiled module (see WARM_UP)
        startStep('instantiate the given module');
        return { instance: await WebAssembly.instantiate(givenModule, imports), module: givenModule };
      }
      startStep('download ' + file);
      const bytes = await fetchWatched(new URL(file, self.location.href).href, file);
      startStep('compile ' + file);
      let timer = 0;
      const tooSlow = new Promise((resolve, reject) => {
        timer = setTimeout(() => reject(new Error(file + ' did not compile within ' + CORE_COMPILE_MS / 1000 + ' s')), CORE_COMPILE_MS);
      });
      try {
        return await Promise.race([WebAssembly.instantiate(bytes, imports), tooSlow]);
      } catch (e) {
        if (e instanceof WebAssembly.CompileError) {
          throw new Error(file + ' is not a valid WebAssembly module (' + bytes.length + ' bytes: ' + e.message + ')');
        }
        if (e instanceof WebAssembly.LinkError) {
          throw new Error(file + ' does not belong to its .js (the two come from different builds: ' + e.message + ')');
        }
        throw e;
      } finally {
        clearTimeout(timer);
      }
    })().then((result) => {
      coreModule = result.module;
      receiveInstance(result.instance, result.module);
    }, onFail);
    return {};  // the exports arrive through receiveInstance
  };
}

// The wasm heap as bytes. In the threaded build the memory is shared and may
// have been grown by another thread since the module's own views were made,
// so the view is taken over the memory's current buffer.
function heapBytes() {
  return core.wasmMemory ? new Uint8Array(core.wasmMemory.buffer) : core.HEAPU8;
}

// ?warmup=1: a throw-away worker the page starts once its core is up. It
// gets the core worker's compiled WebAssembly.Module (job 'module', passed on
// by the page: the same compiled code, not a second compile of the bytes),
// instantiates it and runs one small fit (warm_up_job), so that V8 compiles
// the fit's hot functions with its optimizing tier; that code belongs to the
// module, so the core worker's first fit no longer runs them on the baseline
// tier (docs/web.md, "The first fit"). Then it says 'warm' and the page ends it.
const WARM_UP = params.get('warmup') === '1';
let givenModule = null;  // the module a warm-up worker was given
let coreModule = null;   // this worker's compiled module (for job 'module')

function coreReady(m, which) {
  core = m;
  variant = which;
  if (WARM_UP) {
    const t0 = performance.now();
    let result;
    try {
      result = core.warm_up_job(1);
    } catch (e) {
      result = { ok: false, message: errorText(e) };
    }
    postMessage({ type: 'warm', variant, ok: !!result.ok, message: result.message || '', fitMs: result.fitMs || 0,
                  ms: performance.now() - t0 });
    return;
  }
  postMessage({ type: 'ready', variant, threads: core.parallel_workers(), fallback });
  while (pending.length) handle(pending.shift());
}

// A release build aborts without a reason on out-of-memory; say what is
// likely. (Before the core is up, the start-up's rejection handles it.)
function onAbort(what) {
  if (core) fatal(what ? 'the core stopped: ' + what
    : 'the core ran out of memory at ' + Math.round(heapBytes().length / 1048576) + ' MB of wasm heap');
}

// The single-threaded core: the last resort, so its failures end the start
// ('startFailed': the page says why; the user's files stay on the page).
function startSingleCore() {
  let failed = false;
  const fail = (why) => {
    if (failed || core) return;
    failed = true;
    postMessage({ type: 'startFailed', message: why + (fallback ? ' (the multi-threaded core did not start either: ' + fallback + ')' : '') });
  };
  startStep('script likeness_worker.js');
  try {
    importScripts('likeness_worker.js');
  } catch (e) {
    fail('likeness_worker.js did not load: ' + errorText(e));
    return;
  }
  let starting;
  try {
    starting = LikenessWorker({
      instantiateWasm: watchedInstantiate('likeness_worker.wasm', (e) => fail(errorText(e))),
      print: (t) => console.log('[worker]', t),
      printErr: (t) => console.warn('[worker]', t),
      onAbort,
    });
  } catch (e) {
    fail(errorText(e));
    return;
  }
  starting.then((m) => { if (!failed) coreReady(m, 'single'); }, (err) => fail(errorText(err)));
}

// The threaded core, watched while its pthread pool starts. Every Web Worker
// the module makes during start-up is a pool worker: self.Worker is wrapped
// for that time so each one is seen (its errors, its 'loaded' message, and
// the module's 'load' command to it, which is sent once the module is
// compiled). giveUp() terminates them and starts the single-threaded core.
function startThreadedCore() {
  const NativeWorker = self.Worker;
  const poolWorkers = [];
  let settled = false;  // the threaded core either started or was given up
  let watchdog = 0;
  const settle = () => {
    settled = true;
    clearTimeout(watchdog);
    self.Worker = NativeWorker;
  };
  const giveUp = (why) => {
    if (settled) return;
    settle();
    for (const w of poolWorkers) w.terminate();
    fallback = why;
    console.warn('[worker] the threaded core did not start (' + why + '): one thread');
    startSingleCore();
  };
  if (typeof NativeWorker !== 'function') {
    giveUp('this browser cannot start workers inside a worker');
    return;
  }
  startStep('script likeness_worker_mt.js');
  try {
    importScripts('likeness_worker_mt.js');
  } catch (e) {
    giveUp('its script did not load: ' + errorText(e));
    return;
  }
  self.Worker = function PoolWorker(url, options) {
    const w = new NativeWorker(url, options);
    poolWorkers.push(w);
    // Registered before Emscripten's own onerror (which rethrows, and would
    // reach the page as this worker's error): handled here instead.
    w.addEventListener('error', (e) => {
      e.preventDefault();
      e.stopImmediatePropagation();
      giveUp('a thread of its pool did not start: ' + (e.message || 'its script did not load'));
    });
    const post = w.postMessage.bind(w);
    w.postMessage = (message, transfer) => {
      if (message && message.cmd === 'load' && !watchdog && !settled) {
        startStep('threads');
        watchdog = setTimeout(() => giveUp('its pool of ' + poolWorkers.length + ' thread(s) was not up after ' +
                                           THREAD_START_MS + ' ms'), THREAD_START_MS);
      }
      return transfer ? post(message, transfer) : post(message);
    };
    return w;
  };
  let starting;
  try {
    starting = LikenessWorker({
      // The pthread workers load the module's script by URL (this worker's
      // own URL is worker.js, which they must not run).
      mainScriptUrlOrBlob: new URL('likeness_worker_mt.js', self.location.href).href,
      instantiateWasm: watchedInstantiate('likeness_worker_mt.wasm', (e) => giveUp(errorText(e))),
      print: (t) => console.log('[worker]', t),
      printErr: (t) => console.warn('[worker]', t),
      onAbort: (what) => { if (!settled) giveUp('it stopped: ' + what); else onAbort(what); },
    });
  } catch (e) {  // e.g. no memory for the shared heap, or workers refused
    giveUp(errorText(e));
    return;
  }
  starting.then((m) => {
    if (settled) {  // given up already (too late): its pool is gone
      return;
    }
    settle();
    coreReady(m, 'threads');
  }, (err) => giveUp(errorText(err)));
}

if (WARM_UP) {
  // Waits for the page to pass the core worker's module on.
  self.onmessage = (e) => {
    if (givenModule || !e.data || !(e.data.module instanceof WebAssembly.Module)) return;
    givenModule = e.data.module;
    if (wantThreads) startThreadedCore();
    else startSingleCore();
  };
} else if (wantThreads) startThreadedCore();
else startSingleCore();

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
  // {}: this worker's compiled WebAssembly.Module (structured-cloned, i.e.
  // shared, not copied), for the page's warm-up worker.
  module: () => ({ ok: !!coreModule, module: coreModule, message: coreModule ? '' : 'no compiled module' }),
  // {}: the kept head's checks (turned-over, degenerate and self-intersecting
  // triangles of the finest level), as `likeness fit` prints them.
  quality: () => core.fit_quality_job(),
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

if (!WARM_UP) {
  onmessage = (e) => {
    if (!core) pending.push(e.data);
    else handle(e.data);
  };
}
