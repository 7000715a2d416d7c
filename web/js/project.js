// Save project / Open project: the head the worker holds as one
// .likeness.glb file (core/project/project_file.h: a GLB whose scene is the
// head, the project in its extras), and such a file shown again without
// fitting, over the scan it keeps.
import { app, ui, beginJob, endJob, live, setStage, setStatus, showError, stageItem } from './state.js';
import { runJob } from './worker_client.js';
import { download } from './export.js';
import { formatBytes, listFile, refuseFile } from './files.js';
import { FIT_STAGES, forgetFit, showHead } from './fit.js';
import { MAX_DISPLAY_POINTS, thinPoints } from './scan.js';
import { stopAnimation } from './animation.js';
import { showStage } from './head_view.js';
import { renderPhotos } from './photos.js';
import { checkFitQuality } from './checks.js';
import { projectInputs, takeInputs } from './project_inputs.js';
import { photoCount } from './wording.js';

function projectName() {
  const base = (app.fit && app.fit.name ? app.fit.name : 'head').replace(/\.likeness\.glb$/i, '').replace(/\.[^.]*$/, '');
  return base + '.likeness.glb';
}

// The eyes' and teeth's textures the page shows (made from the eye and
// smile photos), which the project file keeps with their photos' names
// (core's ProjectParts); null where the generic one is shown. Copied to
// the worker, not transferred: the page keeps showing them.
export function projectParts() {
  const e = app.eyePhoto, s = app.smilePhoto;
  return { eyeTexture: e ? e.texture : null, eyeSource: e ? e.name : '',
           teethTexture: s ? s.texture : null, teethSource: s ? s.name : '' };
}

// An opened project's eye and smile textures become the ones shown (as if
// made from photos of those names); a project without them leaves the
// user's own eye or smile photo, and drops one that came with an earlier
// project (no photo of the page made it).
function takeParts(parts) {
  const own = (entry) => !!entry && !entry.fromProject;
  const p = parts || {};
  app.eyePhoto = p.eyeTexture ? { name: p.eyeSource || 'the project', texture: p.eyeTexture, ms: 0, fromProject: true }
    : own(app.eyePhoto) ? app.eyePhoto : null;
  app.smilePhoto = p.teethTexture ? { name: p.teethSource || 'the project', texture: p.teethTexture, ms: 0, fromProject: true }
    : own(app.smilePhoto) ? app.smilePhoto : null;
  return [p.eyeTexture ? 'the eyes from ' + app.eyePhoto.name : '', p.teethTexture ? 'the teeth from ' + app.smilePhoto.name : '']
    .filter(Boolean).join(' and ');
}

export async function saveProject() {
  if (!app.fit || document.body.dataset.state === 'working') return;
  stopAnimation();
  try {
    // With the photos' files, their face points and the page's options.
    const r = await runJob({ type: 'saveProject', parts: projectParts(), inputs: await projectInputs() }, []);
    if (!r.ok) { showError('Could not save the project: ' + r.message); return; }
    const name = projectName();
    download(name, r.bytes, 'model/gltf-binary');
    setStatus('Saved ' + name + ' (' + formatBytes(r.bytes.length) + '): Open project shows it again without fitting.');
  } catch (e) {
    showError('Could not save the project: ' + (e && e.message ? e.message : e));
  }
}

// A refused file (cut, damaged, newer, not a project) leaves everything shown
// as it was: the worker keeps its head until a file loads.
export async function openProject(file) {
  const state = document.body.dataset.state;
  if (state === 'working' || state === 'loading' || app.startupFailed) return;
  stopAnimation();
  const job = beginJob('project');
  if (!job) return;
  const meta = listFile(file, 'opening…');
  setStatus('Opening ' + file.name + '…');
  const t0 = performance.now();
  let result;
  try {
    const buffer = await file.arrayBuffer();
    result = await runJob({ type: 'openProject', name: file.name, buffer }, [buffer]);
  } catch (e) {
    if (e && e.cancelled) {
      meta.textContent = formatBytes(file.size) + ' · cancelled';
      setStatus('Cancelled opening ' + file.name + '.');
      return;
    }
    result = { ok: false, code: 'Internal', message: file.name + ': ' + (e && e.message ? e.message : e) };
  }
  if (!live(job)) return;
  if (!result.ok) {
    refuseFile(meta, file, 'not opened', result.message || result.code);
    setStatus('Could not open ' + file.name + '.' + (app.model ? ' ' + app.model.name + ' is still shown.' : ''));
    showError(result.message || result.code);
    return;
  }
  if (app.fit) forgetFit();
  // The scan it was fitted to, as points under the head (thinned as a
  // dropped scan is); shown first so the view is framed on it. A head made
  // from photos keeps no scan ("no vertices" to show, which refused every
  // such project): none is loaded, the head alone is shown, and Make head
  // from photos works on the photos it brings back.
  const hasScan = result.scan.vertexCount > 0;
  let display = { positions: result.scan.positions, normals: new Float32Array(0), colors: new Float32Array(0),
                  vertexCount: result.scan.vertexCount };
  if (display.vertexCount > MAX_DISPLAY_POINTS) display = thinPoints(display, Math.ceil(display.vertexCount / MAX_DISPLAY_POINTS));
  const shown = hasScan ? app.viewer.show_points(display.positions, display.normals, display.colors) : '';
  if (shown !== '') {
    app.model = null;
    showError(file.name + ': ' + shown);
    return;
  }
  app.model = { name: file.name, kind: 'project', vertexCount: result.scan.vertexCount, triangleCount: 0 };
  // kept: the worker's head keeps these points, so Fit head fits them again.
  app.scan = hasScan
    ? { file: null, kept: true, name: file.name, display: { positions: display.positions, normals: display.normals, colors: display.colors } }
    : null;
  setStage('load', 'project', 1, 'complete');
  for (const st of FIT_STAGES) stageItem(st.row).classList.remove('coming');
  const wallMs = performance.now() - t0;
  app.project = { name: file.name, loadMs: result.loadMs, wallMs };
  const partsFrom = takeParts(result.parts);  // before showHead: it dresses the eyes and teeth
  showHead(result, file.name, wallMs);
  if (result.texture) {
    app.texture = { uvs: result.texture.uvs, skin: result.texture.skin, steps: [], textureMs: 0, wallMs: 0,
                    level: result.texture.level, photos: 0 };
    stageItem('texture').classList.remove('coming');
    setStage('texture', 'saved', 1, 'complete');
    stageItem('texture').querySelector('.stage-stats').textContent = result.texture.skin.width + '² texels, from the project';
    ui.showPoints.checked = false;
    app.viewer.set_overlay_visible(false);
    showStage('subdivide');
  }
  meta.textContent = formatBytes(file.size) + ' · project';
  // The photos it keeps (version 3) replace the page's, with their face points.
  const photos = takeInputs(result.inputs);
  app.project.photos = photos;
  setStatus('Opened ' + file.name + (result.texture ? ' (textured)' : '') + (partsFrom ? ', with ' + partsFrom : '') +
            (photos ? ', its ' + photoCount(photos) + ' (' + app.photos.filter((p) => p.detect && p.detect.points).length + ' with face points)' : '') + ' in ' + Math.round(wallMs) +
            ' ms, without fitting: animate it, texture it or export it.');
  endJob(job);
  renderPhotos();
  checkFitQuality(app.fit);
}

export function wireProject() {
  ui.saveProject.addEventListener('click', saveProject);
  ui.projectInput.addEventListener('change', () => {
    const f = ui.projectInput.files && ui.projectInput.files[0];
    if (f) openProject(f).finally(() => { ui.projectInput.value = ''; });
  });
}
