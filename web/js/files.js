// Files given to the page (Choose files…, or dropped anywhere on it): the
// size limit, the list of received files, and the sorting of a drop into one
// scan, photos and their points files. Everything is read locally.
import { app, params, ui, clearError, setStatus } from './state.js';
import { stopAnimation } from './animation.js';
import { loadScan } from './scan.js';
import { checkPhotos, readPointFiles, texturable } from './photos.js';
import { runTexture } from './texture.js';
import { openProject } from './project.js';

// Largest file accepted at all (scans and photos), checked on the page.
// A scan is also refused by the worker, from its size and before a byte is
// read, when the core's memory could not fit it (worker.js, streamScan: the
// wasm heap's 2 GiB over the heap a fit takes per byte of file, about
// 158 MB of PLY and 341 MB of OBJ, XYZ or VTK; the drop zone shows those
// limits once the core is up). ?max_mb=N overrides this one.
const DEFAULT_MAX_SCAN_MB = 256;
const maxScanMb = Number(params.get('max_mb')) > 0 ? Number(params.get('max_mb')) : DEFAULT_MAX_SCAN_MB;
export const MAX_SCAN_BYTES = maxScanMb * 1024 * 1024;
const PHOTO_EXTENSIONS = ['jpg', 'jpeg', 'png'];

export function extension(name) {
  const dot = name.lastIndexOf('.');
  return dot < 0 ? '' : name.slice(dot + 1).toLowerCase();
}

export function formatBytes(n) {
  if (n < 1024) return n + ' B';
  if (n < 1024 * 1024) return (n / 1024).toFixed(1) + ' KB';
  if (n < 1024 * 1024 * 1024) return (n / 1024 / 1024).toFixed(1) + ' MB';
  return (n / 1024 / 1024 / 1024).toFixed(2) + ' GB';
}

// A row of the received files (the newest first, six at most); returns its
// note, which the caller updates as the file is read.
export function listFile(file, note, cls) {
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

// A file the page could not use: its row says so, and why, in full under its
// name (visible, not only a tooltip, so touch screens show it too). The
// reason is the core's or the page's message without the leading "name: ".
export function refuseFile(meta, file, note, reason) {
  const li = meta.parentElement;
  const why = String(reason).replace(file.name + ': ', '');
  meta.textContent = formatBytes(file.size) + ' · ' + note;
  li.classList.add('refused');
  li.title = file.name + ': ' + why;
  let line = li.querySelector('.file-reason');
  if (!line) {
    line = document.createElement('span');
    line.className = 'file-reason';
    li.append(line);
  }
  line.textContent = why;
}

export async function handleFiles(fileList) {
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
  // A saved project (.likeness.glb) is opened on its own: it is a whole head.
  const project = files.find((f) => extension(f.name) === 'glb');
  if (project) {
    for (const extra of files.filter((f) => f !== project)) listFile(extra, 'ignored: a project opens on its own', 'ignored');
    await openProject(project);
    return;
  }
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

// The file input and the drop zone.
export function wireFiles() {
  ui.maxSize.textContent = formatBytes(MAX_SCAN_BYTES);
  // Once the core is up (worker_client.js): the scan limit its memory sets.
  // PLY's limit, and the text formats' when it is higher (they are parsed
  // as they come, and take more bytes a point).
  app.showScanLimit = (limit, textLimit) => {
    const ply = Math.min(MAX_SCAN_BYTES, limit), text = Math.min(MAX_SCAN_BYTES, textLimit || limit);
    ui.maxSize.textContent = text > ply ? formatBytes(ply) + ' (PLY), ' + formatBytes(text) + ' (OBJ, XYZ, VTK)' : formatBytes(ply);
  };
  if (app.scanLimit) app.showScanLimit(app.scanLimit, app.textScanLimit);
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
}
