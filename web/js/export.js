// Export: the worker writes the fitted head's files (OBJ, PLY, a GLB, the
// textured OBJ + MTL + PNG, the distance map's PLY) and the page hands them to the
// browser as downloads, in the scan's own units and orientation.
import { app, ui, setStatus, showError } from './state.js';
import { runJob } from './worker_client.js';
import { distanceMap } from './checks.js';
import { pageSpeech } from './speech.js';

export function download(name, bytes, mime) {
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

// The chosen level as OBJ (plus the control mesh) or PLY.
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

// The chosen level with its uvs, its material and the skin PNG.
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

// The head as one GLB for avatar tools and viewers: the chosen level
// (level 0 gives level 2: a control mesh is no avatar) with its skin when
// textured, the eyes, teeth and tongue under their nodes, at rest.
async function exportGlb() {
  if (!app.fit) return;
  const level = Number(ui.level.value) || 2;
  const name = app.fit.name.replace(/\.[^.]*$/, '') + '_head_level' + level + '.glb';
  try {
    // The irises and teeth from the eye and smile photos, when there are.
    const parts = { eyeTexture: app.eyePhoto ? app.eyePhoto.texture : null, teethTexture: app.smilePhoto ? app.smilePhoto.texture : null };
    // The words typed beside Talk go along as a "Say" animation (none
    // when nothing in them can be said).
    const words = ui.sayText.value.trim();
    const speech = words ? await pageSpeech(words, ui.sayLang.value) : null;
    const say = speech && !speech.error && speech.visemes.length ? JSON.stringify(speech) : '';
    const r = await runJob({ type: 'exportGlb', level, parts, say }, []);
    if (!r.ok) { showError('Export failed: ' + r.message); return; }
    download(name, r.bytes, 'model/gltf-binary');
    const from = [app.eyePhoto ? 'the irises from ' + app.eyePhoto.name : '', app.smilePhoto ? 'the teeth from ' + app.smilePhoto.name : '']
      .filter(Boolean).join(' and ');
    setStatus('Exported ' + name + ' (level ' + r.level + ', ' + r.vertices.toLocaleString('en') + ' vertices' +
              (app.texture ? ', textured' : '') + ', with eyes, teeth and tongue' + (from ? ', ' + from : '') + '; at rest).');
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

export function wireExport() {
  ui.exportObj.addEventListener('click', () => exportHead('obj'));
  ui.exportPly.addEventListener('click', () => exportHead('ply'));
  ui.exportGlb.addEventListener('click', exportGlb);
  ui.exportTextured.addEventListener('click', exportTextured);
  ui.exportMap.addEventListener('click', exportMap);
}
