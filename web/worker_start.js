// The core's start-up inside worker.js (loaded there by importScripts, so it
// shares worker.js's globals: params, core, fallback, startStep, coreReady, ...).
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
