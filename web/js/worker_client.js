// The page's side of worker.js (the Web Worker running the core): starting
// it (threaded core where the page is cross-origin isolated, else one
// thread), a job as a promise (runJob), progress callbacks, Cancel (the
// worker is terminated and replaced), and the start-up warm-up worker.
// The protocol is described at the top of worker.js.
import { app, params, showError } from './state.js';
import { forgetFit } from './fit.js';

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

export function startWorker() {
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
  for (const p of ['thread_start_ms', 'core_stall_ms', 'core_compile_ms', 'decoder']) if (params.get(p)) workerParams.set(p, params.get(p));
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
        // The largest scan the core's memory fits (worker.js refuses larger
        // files from their size): the drop zone says so.
        if (msg.scanLimit > 0) {
          app.scanLimit = msg.scanLimit;
          app.textScanLimit = msg.textScanLimit || msg.scanLimit;
          if (app.showScanLimit) app.showScanLimit(msg.scanLimit, app.textScanLimit);  // files.js
        }
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
// docs/journal.md, "The first fit"). A throw-away worker running one small fit
// of the same module right after start-up gets them compiled by the
// optimizing tier, and that code is shared with the core's worker. It runs
// on its own thread (never delays a job) and ends itself; ?warmup=0 skips it.
export async function warmUp(variant) {
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
  for (const p of ['thread_start_ms', 'core_stall_ms', 'core_compile_ms', 'decoder']) if (params.get(p)) workerParams.set(p, params.get(p));
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
  // The fitted head lived in that worker: keep.js puts it back from its
  // kept copy when it has one, else animation and export need a new fit.
  if (app.fit && !(app.reviveHead && app.reviveHead())) forgetFit('The fitted head was in the stopped worker: fit again to animate or export.');
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
export function cancelJobs() {
  if (jobs.size) workerDied(app.worker, 'cancelled', true);
}
app.cancel = cancelJobs;

// Runs a worker job; resolves with the core's result object, rejects when
// the worker dies on the way (the page then has a fresh worker).
// The job counts as running from the call on (so Cancel reaches it even
// while a fresh worker is still starting).
export function runJob(message, transfer, onProgress) {
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
