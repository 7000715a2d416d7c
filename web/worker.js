// The Web Worker that runs the core (likeness_worker.wasm) off the main thread.
//
// Messages in:  {type:'parse', id, name, buffer: ArrayBuffer}  (buffer transferred)
// Messages out: {type:'ready'}
//               {type:'progress', id, stage, fraction}
//               {type:'result', id, result}   result = the core's {ok, code, message, ...};
//                                              typed arrays are transferred back
//               {type:'fatal', message}        the module aborted (e.g. out of memory);
//                                              the page starts a fresh worker
'use strict';
importScripts('likeness_worker.js');

let core = null;
const pending = [];

function fatal(message) {
  postMessage({ type: 'fatal', message: String(message) });
}

LikenessWorker({
  print: (t) => console.log('[worker]', t),
  printErr: (t) => console.warn('[worker]', t),
  onAbort: (what) => fatal('the core stopped: ' + what),
}).then((m) => {
  core = m;
  postMessage({ type: 'ready' });
  while (pending.length) handle(pending.shift());
}, (err) => fatal('could not start the core: ' + err));

// Copies the bytes into the wasm heap, runs the job, frees the copy.
function withHeapBytes(buffer, fn) {
  const bytes = new Uint8Array(buffer);
  const ptr = core._malloc(Math.max(1, bytes.length));
  if (!ptr) return { ok: false, code: 'TooLarge', message: 'not enough memory to hold the file (' + bytes.length + ' bytes)' };
  try {
    core.HEAPU8.set(bytes, ptr);
    return fn(ptr, bytes.length);
  } finally {
    core._free(ptr);
  }
}

function transferables(result) {
  const out = [];
  for (const key of ['positions', 'normals', 'colors', 'indices']) {
    if (result[key] && result[key].buffer) out.push(result[key].buffer);
  }
  return out;
}

function handle(msg) {
  if (msg.type === 'parse') {
    const progress = (stage, fraction) => {
      postMessage({ type: 'progress', id: msg.id, stage, fraction });
    };
    let result;
    try {
      result = withHeapBytes(msg.buffer, (ptr, size) => core.parse_geometry(msg.name, ptr, size, progress));
    } catch (e) {
      // Only an abort (a bug or memory exhaustion) gets here: the core returns
      // errors as values. The module is unusable afterwards.
      fatal(msg.name + ': ' + (e && e.message ? e.message : e));
      return;
    }
    postMessage({ type: 'result', id: msg.id, result }, transferables(result));
  } else {
    postMessage({ type: 'result', id: msg.id, result: { ok: false, code: 'Internal', message: 'unknown job ' + msg.type } });
  }
}

onmessage = (e) => {
  if (!core) pending.push(e.data);
  else handle(e.data);
};
