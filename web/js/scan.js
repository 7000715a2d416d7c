// Loading a head scan: parsed in the worker, shown by the viewer (thinned
// beyond the display budget), then fitted when Auto-run is on; and the
// built-in sample fetched from beside the page.
import { app, params, ui, beginJob, endJob, live, setStage, setStatus, showError, stageItem } from './state.js';
import { extension, formatBytes, handleFiles, listFile, MAX_SCAN_BYTES, refuseFile } from './files.js';
import { runJob } from './worker_client.js';
import { FIT_STAGES, forgetFit, lookWithScanAxes, nameRows, runFit } from './fit.js';

const SCAN_EXTENSIONS = ['ply', 'obj', 'xyz', 'vtk'];
// What the viewer draws at most (see loadScan); ?max_display_points=N and
// ?max_display_triangles=N override.
export const MAX_DISPLAY_POINTS = Number(params.get('max_display_points')) > 0 ? Number(params.get('max_display_points')) : 4000000;
const MAX_DISPLAY_TRIANGLES = Number(params.get('max_display_triangles')) > 0 ? Number(params.get('max_display_triangles')) : 2000000;

// Every stride-th point of a parsed point cloud (positions, normals, colors).
export function thinPoints(result, stride) {
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

// A failed load: the reason goes beside the file and to the banner, the
// stage says so, and the status line says what is still shown.
function loadFailed(file, meta, note, message) {
  refuseFile(meta, file, note, message);
  setStage('load', 'failed', 0, 'failed');
  const kept = app.model ? ' The previous model (' + app.model.name + ') is still shown.' : '';
  setStatus('Could not load ' + file.name + '.' + kept);
  showError(message);
}

export async function loadScan(file) {
  const meta = listFile(file, 'reading…');
  if (file.size > MAX_SCAN_BYTES) {
    loadFailed(file, meta, 'too large', file.name + ' is ' + formatBytes(file.size) +
               '; the web app accepts scans up to ' + formatBytes(MAX_SCAN_BYTES) +
               '. Reduce the scan (fewer points or triangles) in your scanning software, or use the Likeness command-line tool.');
    return;
  }
  if (file.size === 0) {
    loadFailed(file, meta, 'empty', file.name + ' is empty.');
    return;
  }
  const job = beginJob('scan');
  if (!job) return;
  setStage('load', 'reading', 0, 'active');
  setStatus('Reading ' + file.name + '…');
  const t0 = performance.now();
  let result;
  try {
    // The worker reads the File in slices and parses them as they come
    // (worker.js, streamScan): progress is the bytes read.
    result = await runJob({ type: 'parseFile', file }, [], (stage, fraction) => {
      if (stage === 'read') {
        setStage('load', formatBytes(fraction * file.size) + ' of ' + formatBytes(file.size), 0.8 * fraction, 'active');
      }
      if (stage === 'load') setStage('load', 'parsing', 0.8 + 0.2 * fraction, 'active');
    });
  } catch (e) {
    if (e && e.cancelled) {
      meta.textContent = formatBytes(file.size) + ' · cancelled';
      setStage('load', 'cancelled', 0);
      setStatus('Cancelled loading ' + file.name + '.' +
                (app.model ? ' The previous model (' + app.model.name + ') is still shown.' : ''));
      endJob(job);
      return;
    }
    result = { ok: false, code: 'Internal', message: file.name + ': ' + (e && e.message ? e.message : e) +
               '. Try a smaller or decimated scan.' };
  }
  if (!live(job)) return;
  // What the worker read and its heap afterwards (the large-scan flow reads it).
  app.scanRead = { name: file.name, ok: !!result.ok, bytesRead: result.bytesRead, heapBytes: result.heapBytes || 0 };
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
  lookWithScanAxes();
  nameRows(false);
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
  endJob(job);
  if (ui.autoFit.checked) await runFit();
}

// The built-in sample (a synthetic head from our virtual scanner, no real
// person) is put beside the page by scripts/demo; it comes from this page's
// own origin like everything else.
const SAMPLE_URL = 'sample/scan.ply';
const SAMPLE_TEXTURE_URL = 'sample/texture.json';
export async function loadSample() {
  // Fetching is a job of its own, so Cancel ends it too.
  const job = beginJob('sample');
  if (!job) return;
  setStatus('Fetching the sample…');
  let response;
  try {
    response = await fetch(SAMPLE_URL, { cache: 'no-store' });
  } catch (e) {
    if (live(job)) showError('Could not fetch the sample (' + SAMPLE_URL + '): ' + (e && e.message ? e.message : e));
    return;
  }
  if (!live(job)) return;
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
  if (!endJob(job)) return;
  await handleFiles([new File([blob], 'sample_scan.ply'), ...extra]);
}

// The photos sample (scripts/demo puts it beside the page): five renders of
// a synthetic person from around the head (`likeness synth-photos`, no real
// person), listed in sample/photos.json. Dropped as photos alone, so with
// Auto-run on the head is made from them and textured, no click.
const SAMPLE_PHOTOS_URL = 'sample/photos.json';
export async function loadPhotosSample() {
  if (app.scan) {
    showError('A scan is loaded, and a head from photos is made only without one. Reload the page to try the photos ' +
              'sample (the head made so far is kept in this browser and offered back).');
    return;
  }
  const job = beginJob('sample');
  if (!job) return;
  setStatus('Fetching the photos sample…');
  const files = [];
  let why = '';
  try {
    const list = await fetch(SAMPLE_PHOTOS_URL, { cache: 'no-store' });
    if (!list.ok) why = SAMPLE_PHOTOS_URL + ': HTTP ' + list.status;
    const manifest = list.ok ? await list.json() : { photos: [] };
    for (const name of (manifest.photos || []).slice(0, 15)) {
      if (typeof name !== 'string' || !/^[\w.-]+\.(png|jpe?g)$/i.test(name)) continue;
      const photo = await fetch('sample/' + name, { cache: 'no-store' });
      if (photo.ok) files.push(new File([await photo.blob()], name, { type: photo.headers.get('content-type') || '' }));
    }
  } catch (e) {
    why = e && e.message ? e.message : String(e);
  }
  if (!live(job)) return;
  if (!files.length) {
    showError('The photos sample is not installed next to this page' + (why ? ' (' + why + ')' : '') +
              '. scripts/demo makes it; or drop your own photos.');
    return;
  }
  if (!endJob(job)) return;
  await handleFiles(files);
}
