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
// worker_start.js starts the core: the threaded one where the page is cross-
// origin isolated, watched while its thread pool starts; each core's .wasm
// downloaded and compiled with time limits and messages naming the file.
'use strict';
const params = new URLSearchParams(self.location.search);
const wantThreads = self.crossOriginIsolated === true && typeof SharedArrayBuffer === 'function'
  && params.get('threads') !== '1';

let core = null;
let variant = null;  // 'threads' | 'single': the core that runs
let fallback = null;  // why the threaded core did not start (null: it did, or was not tried)
const pending = [];

function fatal(message) {
  postMessage({ type: 'fatal', message: String(message) });
}

function errorText(e) { return e && e.message ? e.message : String(e); }

function startStep(step) { postMessage({ type: 'starting', step }); }

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
// tier (docs/journal.md, "The first fit"). Then it says 'warm' and the page ends it.
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
  postMessage({ type: 'ready', variant, threads: core.parallel_workers(), fallback, scanLimit: scanLimitBytes(),
                textScanLimit: scanLimitBytes('scan.obj') });
  while (pending.length) enqueue(pending.shift());
}

// The start-up code (functions only; it runs below, once JOBS exist).
try {
  importScripts('worker_start.js');
} catch (e) {
  postMessage({ type: 'startFailed', message: 'worker_start.js did not load: ' + errorText(e).replace(/\.$/, '') });
  throw e;
}

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

// Scans are read from the File in slices (File.slice + arrayBuffer), each
// copied into one reused heap buffer and pushed into the core's stream reader
// (io/scan_stream.h): neither the JS heap nor the wasm heap ever holds the
// whole file, and PLY is parsed as it comes.
const SCAN_SLICE = 8 * 1024 * 1024;
// Fitting a scan takes at most this many bytes of wasm heap per byte of
// binary PLY (x y z and normals as floats, 24 bytes a point), measured on a
// 2M and a 5M-point scan (docs/design/page.md, "Very large scans"); the heap
// cannot grow beyond core.heap_max_bytes() (2 GiB).
const FIT_HEAP_PER_FILE_BYTE = 13;
// And per point the header declares (a PLY with fewer bytes a point, x y z
// only, has more points in the same bytes).
const FIT_HEAP_PER_POINT = 320;
// A text scan (OBJ, XYZ, VTK) is parsed as it comes and never held whole,
// and takes more bytes a point: a fit took at most 6 bytes of heap per byte
// of the 2M-point OBJ and XYZ with normals at 6 decimals (5.0 and 6.0,
// docs/design/page.md). A denser text file (x y z only) has more points in
// the same bytes: it is refused by the points counted as it is read.
const FIT_HEAP_PER_TEXT_BYTE = 6;
const TEXT_SCAN = /\.(obj|xyz|txt|pts|asc|xyzn|xyzrgb|vtk)$/i;

// Frees the reader of a scan given up on (an empty one takes its place).
function dropScanStream() { core.scan_stream_begin('', 0); }

function heapPerFileByte(name) { return TEXT_SCAN.test(name) ? FIT_HEAP_PER_TEXT_BYTE : FIT_HEAP_PER_FILE_BYTE; }

function scanLimitBytes(name = '') { return Math.floor(core.heap_max_bytes() / heapPerFileByte(name)); }

function mb(n) { return (n / 1024 / 1024).toFixed(n < 10 * 1024 * 1024 ? 1 : 0) + ' MB'; }

// Reads `file` into the core's scan stream; progress('read', fraction) per
// slice. -> {ok} or the refusal (a file too large for the heap is refused
// from its size before a byte is read; a PLY whose header declares too many
// points, once the header is read).
async function streamScan(file, progress) {
  const name = String(file.name || 'scan');
  const heapMax = core.heap_max_bytes();
  const limit = scanLimitBytes(name);
  if (file.size > limit) {
    return { ok: false, code: 'TooLarge', message: name + ' is ' + mb(file.size) + ': the page fits ' + (TEXT_SCAN.test(name) ? 'OBJ, XYZ and VTK scans' : /\.ply$/i.test(name) ? 'PLY scans' : 'scans') + ' up to ' +
             mb(limit) + ' (its WebAssembly memory ends at ' + mb(heapMax) + ', and a fit needs about ' +
             heapPerFileByte(name) + ' times the file). Thin the scan in your scanning software, or use the ' +
             'Likeness command-line tool.', bytesRead: 0 };
  }
  let r = core.scan_stream_begin(name, file.size);
  if (!r.ok) return r;
  const ptr = core._malloc(Math.max(1, Math.min(SCAN_SLICE, file.size)));
  if (!ptr) return { ok: false, code: 'TooLarge', message: 'not enough memory to read ' + name };
  let read = 0;
  try {
    progress('read', 0);
    while (read < file.size) {
      let bytes;
      try {
        bytes = new Uint8Array(await file.slice(read, read + SCAN_SLICE).arrayBuffer());
      } catch (e) {  // e.g. the file was changed or removed on disk since it was chosen
        dropScanStream();
        return { ok: false, code: 'InvalidInput', message: name + ' could not be read (' + errorText(e) + ')', bytesRead: read };
      }
      if (bytes.length === 0) {
        dropScanStream();
        return { ok: false, code: 'Truncated', message: name + ': the file ended early while being read', bytesRead: read };
      }
      heapBytes().set(bytes, ptr);
      r = core.scan_stream_push(ptr, bytes.length);
      read += bytes.length;
      if (!r.ok) return r;
      // The count a PLY header or .pts line declares, or the OBJ / XYZ
      // vertices read so far: refused as soon as either is too many.
      const points = Math.max(r.vertices || 0, r.verticesRead || 0);
      if (points * FIT_HEAP_PER_POINT > heapMax) {
        dropScanStream();
        return { ok: false, code: 'TooLarge', message: name + (r.vertices ? ' declares ' : ' has at least ') + points.toLocaleString('en') +
                 ' points: the page fits scans up to ' + Math.floor(heapMax / FIT_HEAP_PER_POINT).toLocaleString('en') +
                 ' points (its WebAssembly memory ends at ' + mb(heapMax) + '). Thin the scan in your scanning ' +
                 'software, or use the Likeness command-line tool.', bytesRead: read };
      }
      progress('read', read / file.size);
    }
  } finally {
    core._free(ptr);
  }
  return { ok: true, bytesRead: read };
}

// Photos are decoded by the browser's own decoders (createImageBitmap, the
// most fuzzed decoders there are, and faster than stb in wasm), after the
// core's inspect_image has checked the bytes: JPEG or PNG, whole, within the
// pixel limit, no decompression bomb (io.h). EXIF orientation is applied
// ('from-image'), as the page's <img> shows the photo and as read_image does.
// Where createImageBitmap or OffscreenCanvas are missing (or with
// ?decoder=stb) the core decodes the bytes itself (stb behind the same checks).
const BROWSER_DECODER = typeof createImageBitmap === 'function' && typeof OffscreenCanvas === 'function' &&
  params.get('decoder') !== 'stb';

// -> {buffer, decoded: {width, height}, decoder} with the RGBA pixels, or
// {buffer (the file's bytes), decoded: null, decoder: 'stb'}, or {error: result}.
// smallPx > 0: also {small}, the photo scaled down to smallPx on its longer
// side from the same decode (an ImageBitmap, for the page's face detector:
// the page need not decode the photo again), when it is larger than that.
// probe false: no truncation probe (a photo the image job already checked).
async function photoPixels(name, buffer, smallPx = 0, probe = true) {
  if (!BROWSER_DECODER) return { buffer, decoded: null, decoder: 'stb' };
  const info = withHeapBytes(buffer, (ptr, size) => core.inspect_image(name, ptr, size));
  if (!info.ok) return { error: info };
  const fail = (why, code = 'InvalidInput') => ({ error: { ok: false, code, message: name + ': ' + why } });
  let small = null;
  const decode = async (bytes, wantSmall) => {
    let bitmap;
    try {
      bitmap = await createImageBitmap(new Blob([bytes]), { imageOrientation: 'from-image', premultiplyAlpha: 'none' });
    } catch (e) {
      return { why: 'the browser could not decode this ' + info.format + ' (' + errorText(e) + ')' };
    }
    try {
      if (bitmap.width !== info.width || bitmap.height !== info.height) {
        return { why: 'the browser decoded ' + bitmap.width + '×' + bitmap.height + ' pixels from a ' + info.format +
                      ' that declares ' + info.width + '×' + info.height };
      }
      const canvas = new OffscreenCanvas(bitmap.width, bitmap.height);
      const ctx = canvas.getContext('2d', { willReadFrequently: true });
      if (!ctx) return { why: 'no 2-D canvas to read the decoded pixels from' };
      ctx.drawImage(bitmap, 0, 0);
      const scale = wantSmall ? smallPx / Math.max(bitmap.width, bitmap.height) : 1;
      if (scale < 1) {
        small = await createImageBitmap(bitmap, { resizeWidth: Math.round(bitmap.width * scale),
                                                  resizeHeight: Math.round(bitmap.height * scale), resizeQuality: 'high' });
      }
      return { pixels: ctx.getImageData(0, 0, bitmap.width, bitmap.height).data };
    } finally {
      bitmap.close();
    }
  };
  const first = await decode(buffer, smallPx > 0);
  if (first.why) return fail(first.why);
  // A JPEG whose image data ends early is filled in silently by the decoder;
  // its probe (one-bits after each scan, io.h) then decodes differently.
  const probed = probe ? withHeapBytes(buffer, (ptr, size) => core.jpeg_truncation_probe(name, ptr, size)) : { ok: true, probe: [] };
  if (!probed.ok) {
    if (small) small.close();
    return { error: probed };
  }
  if (probed.probe.length) {
    const second = await decode(probed.probe);
    const a = first.pixels, b = second.pixels;
    let same = !second.why && b.length === a.length;
    if (same) {  // four bytes at a time (RGBA rows: a multiple of 4)
      const a4 = new Uint32Array(a.buffer, a.byteOffset, a.length >> 2), b4 = new Uint32Array(b.buffer, b.byteOffset, b.length >> 2);
      for (let i = 0; same && i < a4.length; i++) same = a4[i] === b4[i];
    }
    if (!same) {
      if (small) small.close();
      return fail('truncated JPEG: its image data ends before its last blocks (the decoder would fill them with grey)', 'Truncated');
    }
  }
  return { buffer: first.pixels.buffer, decoded: { width: info.width, height: info.height }, decoder: 'browser', small };
}

// A photo's outline on a plain background (the core's plain_outline, which
// finds it on the photo shrunk to 1280 px, kPlainOutlineMaxSide), in its
// width x height pixels, from photoPixels' result. From the photo's own
// pixels, as `likeness photos` finds it, up to twice that size; a larger
// photo's (a 12-megapixel one's) from the detector's 1280-px copy, shrunk by
// the browser (left open for the page): the core's shrinking would cost a
// third of a second a photo. -> {points: Float64Array x y nx ny ...} or
// {message} (why there is none: a room behind the person).
function photoOutline(name, photo, width, height) {
  const viaSmall = photo.small && Math.max(width, height) > 2 * core.PLAIN_OUTLINE_MAX_SIDE;
  const r = viaSmall ? smallOutline(name, photo.small, width, height)
    : withHeapBytes(photo.buffer, (ptr, size) => core.plain_outline(name, ptr, size, photo.decoded, width, height));
  return r.ok ? { points: r.points } : { message: r.message || r.code };
}

function smallOutline(name, bitmap, width, height) {
  const canvas = new OffscreenCanvas(bitmap.width, bitmap.height);
  const ctx = canvas.getContext('2d', { willReadFrequently: true });
  if (!ctx) return { ok: false, message: 'no 2-D canvas to read the photo from' };
  ctx.drawImage(bitmap, 0, 0);
  const pixels = ctx.getImageData(0, 0, bitmap.width, bitmap.height).data;
  return withHeapBytes(pixels.buffer, (ptr, size) =>
    core.plain_outline(name, ptr, size, { width: bitmap.width, height: bitmap.height }, width, height));
}

// Runs fn(ptr, size, decoded) on a photo's pixels (or bytes) in the heap;
// the result says which decoder ran.
async function withPhoto(name, buffer, fn, smallPx = 0) {
  const photo = await photoPixels(name, buffer, smallPx);
  if (photo.error) return photo.error;
  const result = withHeapBytes(photo.buffer, (ptr, size) => fn(ptr, size, photo.decoded));
  if (result && typeof result === 'object') {
    result.decoder = photo.decoder;
    if (photo.small) {
      if (result.ok) result.small = photo.small;
      else photo.small.close();
    }
  }
  return result;
}

// job name -> (message, progress) -> result (or a promise of it)
const JOBS = {
  // {name, buffer}: a dropped PLY / OBJ / XYZ / VTK file -> geometry arrays.
  parse: (msg, progress) =>
    withHeapBytes(msg.buffer, (ptr, size) => core.parse_geometry(msg.name, ptr, size, progress)),
  // {name, buffer, smallPx}: a dropped photo -> {width, height, channels,
  // decoder} once decoded, and focalPx, focalSource: the focal its EXIF gives
  // (0: none), read from the file's bytes (the browser's decoder leaves
  // pixels only); small: the photo at most smallPx on its longer side (an
  // ImageBitmap, transferred; none where the photo is smaller or stb decoded it).
  // outline: the photo's outline on a plain background for the head's
  // silhouettes (photoOutline).
  image: async (msg) => {
    const photo = await photoPixels(msg.name, msg.buffer, msg.smallPx | 0);
    if (photo.error) return photo.error;
    const r = withHeapBytes(photo.buffer, (ptr, size) => core.check_image(msg.name, ptr, size, photo.decoded));
    r.decoder = photo.decoder;
    if (!r.ok) {
      if (photo.small) photo.small.close();
      return r;
    }
    r.outline = photoOutline(msg.name, photo, r.width, r.height);
    if (photo.small) r.small = photo.small;
    // EXIF sits in the file's first segments (APP1, at most 64 kB).
    const head = msg.buffer.slice(0, 256 * 1024);
    const f = withHeapBytes(head, (ptr, size) => core.photo_focal(ptr, size, r.width, r.height));
    r.focalPx = f.focalPx;
    r.focalSource = f.source;
    return r;
  },
  // {file}: a scan as a File, read in slices -> what 'parse' returns.
  parseFile: async (msg, progress) => {
    const read = await streamScan(msg.file, progress);
    if (!read.ok) return read;
    const r = core.parse_scan_stream(progress);
    r.bytesRead = read.bytesRead;
    return r;
  },
  // {file, options}: 'fit' on a File read in slices.
  fitFile: async (msg, progress) => {
    const t0 = performance.now();
    const read = await streamScan(msg.file, progress);
    if (!read.ok) return read;
    const readMs = performance.now() - t0;
    const r = core.fit_head_stream_job(Object.assign({}, msg.options || {}, { name: String(msg.file.name || 'scan') }), progress);
    if (r.ok) r.parseMs = readMs + (r.parseMs || 0);  // the parse happens as the slices are read
    return r;
  },
  // {options: {levels, name}}: the kept head's own scan (a head opened from
  // a project keeps its points, not the file) fitted again; the kept head
  // stays when it fails.
  refit: (msg, progress) => core.refit_kept_scan_job(msg.options || {}, progress),
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
  // {photos: [{name, buffer, points: Float64Array, checked}], options}: calibrate each
  // photo and texture the kept head (tarini2002 Sec. 3). Progress 'texture'.
  texture: async (msg, progress) => {
    const photos = [];
    for (const p of msg.photos || []) {
      // checked: the image job checked this file's bytes when it was dropped;
      // its truncation probe (a second decode) is not made again.
      const photo = await photoPixels(String(p.name), p.buffer || new ArrayBuffer(0), 0, !p.checked);
      if (photo.error) return photo.error;
      photos.push({ name: p.name, buffer: photo.buffer, decoded: photo.decoded, points: p.points });
    }
    return withManyHeapBytes(photos, (placed) => core.texture_job(placed, msg.options || {}, progress));
  },
  // {level, base}: the textured head as {obj, mtl, png} bytes.
  exportTextured: (msg) => core.export_textured(msg.level, String(msg.base)),
  // {}: the kept head project as a .likeness.glb file's bytes.
  saveProject: (msg) => core.save_project_job(msg.parts || {}, msg.inputs || {}),
  // {level, parts: {eyeTexture, teethTexture}, say}: the head as a GLB; the
  // parts' textures (from eye and smile photos) replace the generic ones;
  // words to say add a "Say" animation.
  exportGlb: (msg) => core.export_glb_job(msg.level | 0, msg.parts || {}, String(msg.say || '')),
  // {level}: the muscle layer's 77 shapes baked on the kept head at level
  // (sparse offsets in the scan frame) for the page's Expressions panel.
  faceShapes: (msg) => core.face_shapes_job(msg.level | 0),
  // {text}: typed words as a clip for Talk ({clip, truncated}), or why not.
  sayClip: (msg) => core.say_clip_job(String(msg.speech || '')),
  // {weights: {name: w}, level}: one frame of the live muscle path (the
  // head posed by the muscle layer and the local update, read, put back at
  // rest): {positions, poseMs, restMs, changed}.
  expression: (msg) => core.expression_frame_job(msg.weights || {}, msg.level | 0),
  // {name, buffer}: a saved project -> the kept head, as 'fit' returns it
  // (plus scan positions, texture, loadMs), without fitting.
  openProject: (msg) => withHeapBytes(msg.buffer, (ptr, size) => core.load_project_job(msg.name, ptr, size)),
  // {name, buffer, guess?: [x, y]}: an eye photo -> the eyeball (iris) texture.
  eye: (msg, progress) => withPhoto(msg.name, msg.buffer, (ptr, size, decoded) =>
    core.eye_photo_job(msg.name, ptr, size, msg.guess || null, decoded, progress)),
  // {name, buffer, smallPx}: a photo's outline again (a photo restored from
  // a kept or saved project, which keeps its points, not its outline):
  // {ok, width, height, outline} (photoOutline's).
  outline: async (msg) => {
    const photo = await photoPixels(msg.name, msg.buffer, msg.smallPx | 0, false);
    if (photo.error) return photo.error;
    const size = photo.decoded || {};
    const outline = photoOutline(msg.name, photo, size.width | 0, size.height | 0);
    if (photo.small) photo.small.close();
    return { ok: true, outline };
  },
  // {photos: [{name, text, outline?}], options}: each photo's face landmarks
  // (likeness-landmarks JSON) and its outline ('image' job) -> cameras and
  // the person's head (issue 37), kept in this worker like a fitted head.
  photos: (msg) => core.photos_head_job(msg.photos || [], msg.options || {}),
  // {name, buffer}: a smile photo -> the teeth texture (teeth model's uvs).
  smile: (msg) => withPhoto(msg.name, msg.buffer, (ptr, size, decoded) => core.smile_photo_job(msg.name, ptr, size, decoded)),
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
      placed.push({ name: String(item.name), ptr, size: bytes.length, points: item.points || new Float64Array(0),
                    decoded: item.decoded || null });
      heapBytes().set(bytes, ptr);
    }
    return fn(placed);
  } finally {
    for (const p of placed) core._free(p.ptr);
  }
}

// Typed arrays anywhere in the result (fit results nest meshes) and image
// bitmaps are transferred, not copied.
function transferables(result, out = []) {
  for (const value of Object.values(result)) {
    if (ArrayBuffer.isView(value)) { if (value.buffer.byteLength) out.push(value.buffer); }
    else if (typeof ImageBitmap === 'function' && value instanceof ImageBitmap) out.push(value);
    else if (value && typeof value === 'object') transferables(value, out);
  }
  return out;
}

// Jobs run one at a time, in the order they came (a photo job awaits the
// browser's decoder, and the next message must not overtake it).
let queue = Promise.resolve();
function enqueue(msg) {
  // A failure outside the job's own try (posting the result) must not stop the queue.
  queue = queue.then(() => handle(msg)).catch((e) => fatal(msg.type + ': ' + errorText(e)));
}

async function handle(msg) {
  const job = JOBS[msg.type];
  if (!job) {
    postMessage({ type: 'result', id: msg.id, result: { ok: false, code: 'Internal', message: 'unknown job ' + msg.type } });
    return;
  }
  const progress = (stage, fraction) => { postMessage({ type: 'progress', id: msg.id, stage, fraction }); };
  let result;
  const t0 = performance.now();
  try {
    result = await job(msg, progress);
  } catch (e) {
    // The core returns errors as values, so only an abort or a binding
    // error (a bug) gets here; the module may be unusable afterwards.
    fatal(msg.type + ': ' + (e && e.message ? e.message : e));
    return;
  }
  // The job's time inside the worker (core + copies out of the heap), so the
  // page can tell it from the message round trip.
  if (result && typeof result === 'object') {
    result.workerMs = performance.now() - t0;
    // The core's memory (the wasm heap only grows: its size is the peak so far).
    result.heapBytes = heapBytes().length;
    result.heapMaxBytes = core.heap_max_bytes();
  }
  postMessage({ type: 'result', id: msg.id, result }, transferables(result));
}

// Start the core (a warm-up worker first waits for the module it is given).
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

if (!WARM_UP) {
  onmessage = (e) => {
    if (!core) pending.push(e.data);
    else enqueue(e.data);
  };
}
