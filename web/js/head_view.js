// What the viewer shows of a fit: a stage's mesh over the scan points, the
// chosen level (plain, textured, or coloured by its distance to the scan),
// and the eyeballs, teeth and tongue; and the controls that pick them.
import { app, ui, setStatus, showError, stageItem } from './state.js';
import { FIT_STAGES } from './fit.js';
import { distanceMap } from './checks.js';
import { reshowHead, shownLevel, stopAnimation } from './animation.js';

// The level of the fit mesh in the viewer (null: another stage or mesh).
export const view = { level: null };

export function markShown(row) {
  app.shownStage = row;
  if (row !== 'subdivide') {
    view.level = null;
    ui.distanceLegend.hidden = true;  // the map is of the subdivided head only
  }
  for (const st of FIT_STAGES) stageItem(st.row).classList.toggle('shown', st.row === row);
}

// A fit stage's mesh (the Subdivide row: the level drawn now).
export function fitMesh(row) {
  const m = app.fit.meshes;
  if (row === 'align') return m.aligned;
  if (row === 'local_fit') return m.local;
  if (row === 'global_fit') return m.control;
  const level = shownLevel();  // the chosen level, or the adaptation's while moving
  return level === 0 ? m.control : m.levels[level - 1];
}

// The generic eyeballs (iris texture), teeth and tongue of tarini2002
// Sec. 4, placed by the worker from the fitted eye rims and lips. Drawn
// with the subdivided head only (the earlier stages are not the final
// shape); at rest, they do not follow the animated jaw.
export function showComponents(c) {
  app.viewer.clear_components();
  app.components = 0;
  app.componentsData = c || null;
  app.componentTextures = { eyes: 'none', teeth: 'none', teethTextured: false };
  if (!c) return;
  // A photo's iris / teeth texture replaces the generic one.
  const eyeTexture = app.eyePhoto ? app.eyePhoto.texture : c.eyeTexture;
  const teethTexture = app.smilePhoto ? app.smilePhoto.texture : c.teethTexture;
  const none = new Float32Array(0);
  const errors = [];
  const add = (m, texture) => {
    const t = texture || { width: 0, height: 0, channels: 0, pixels: new Uint8Array(0) };
    const err = app.viewer.add_component(m.positions, m.indices, m.colors || none, texture ? m.uvs : none,
                                         t.width, t.height, t.channels, t.pixels);
    if (err) errors.push(err); else app.components++;
  };
  app.jawComponents = [];
  app.tongueComponent = null;  // the tongue's component number (expressions.js bends it out)
  // The eyeballs turn with the gaze shapes (expressions.js): their
  // component numbers, the left eye's first ([null] where one failed).
  app.eyeComponents = [];
  const eyeTextured = !!eyeTexture && (c.eyes || []).every((eye) => !!eye.uvs);
  for (const eye of c.eyes || []) {
    const before = app.components;
    add(eye, eyeTextured ? eyeTexture : null);
    app.eyeComponents.push(app.components > before ? before : null);
  }
  const teethTextured = !!teethTexture && !!c.teeth && !!c.teeth.uvs;
  if (c.teeth) add(c.teeth, teethTextured ? teethTexture : null);
  // The lower teeth and the tongue ride on the jaw (animate's jawMatrix).
  for (const [m, tex] of [[c.lowerTeeth, teethTextured && c.lowerTeeth && c.lowerTeeth.uvs ? teethTexture : null], [c.tongue, null]]) {
    if (!m) continue;
    const before = app.components;
    add(m, tex);
    if (app.components > before) app.jawComponents.push(before);
    if (app.components > before && m === c.tongue) app.tongueComponent = before;
  }
  if (errors.length) console.warn('components not shown:', errors.join('; '));
  app.componentTextures = {
    eyes: !eyeTextured ? 'none' : app.eyePhoto ? 'photo:' + app.eyePhoto.name : 'generic',
    teeth: !teethTextured ? 'none' : app.smilePhoto ? 'photo:' + app.smilePhoto.name : 'generic',
    teethTextured: teethTextured && !errors.length,
  };
}

// f() after the subdivided head is shown at rest (expressions.js poses it again).
const shownListeners = [];
export function onHeadShown(f) { shownListeners.push(f); }

// Shows a fit stage's mesh over the scan points, keeping the view.
// quiet: no status line; posed: positions to show instead of the rest pose
// (the adaptation swapping levels while moving).
export function showStage(row, quiet = false, posed = null) {
  if (!app.fit) return;
  app.viewer.set_components_visible(row === 'subdivide' && ui.showComponents.checked);
  if (row !== 'subdivide') stopAnimation(true, false);
  const mesh = fitMesh(row);
  const t = app.texture;
  const map = row === 'subdivide' && ui.showDistance.checked ? distanceMap() : null;
  const textured = row === 'subdivide' && t && !map;
  const err = map
    ? app.viewer.show_mesh_keep_view(posed || mesh.positions, null, map, mesh.indices)
    : textured
    ? app.viewer.show_textured_mesh(posed || mesh.positions, mesh.indices, t.uvs.subarray(0, 2 * mesh.vertexCount),
                                    t.skin.width, t.skin.height, t.skin.channels, t.skin.pixels)
    : app.viewer.show_mesh_keep_view(posed || mesh.positions, null, null, mesh.indices);
  if (err) { showError('Could not show the ' + row + ' mesh: ' + err); return; }
  view.level = row === 'subdivide' ? shownLevel() : null;
  ui.distanceLegend.hidden = !map;
  markShown(row);
  if (row === 'subdivide' && !posed) for (const f of shownListeners) f();
  if (quiet) return;
  const what = row === 'subdivide' ? (ui.level.value === '0' ? 'control mesh' : 'level ' + ui.level.value)
    : stageItem(row).querySelector('.stage-name').textContent + ' result';
  // A new fit's checks may not be in yet (fit.quality null): no map, no note.
  const mapNote = map ? ' coloured by its distance to the scan: white within 0.25 mm, yellow 1 mm, red 3 mm or more, ' +
                        'blue-grey not measured (outside the face, or not scanned)'
    : row === 'subdivide' && ui.showDistance.checked && distanceMap(true) ? ' (the distance map is of level ' + app.fit.quality.level + ')' : '';
  setStatus('Showing the ' + (textured ? 'textured ' : '') + what + ' (' + mesh.vertexCount.toLocaleString('en') + ' vertices, ' +
            mesh.triangleCount.toLocaleString('en') + ' triangles)' + mapNote + (ui.showPoints.checked ? ' over the scan points.' : '.'));
}

// Level, Scan points, Distance to scan, Eyes & teeth.
export function wireHeadView() {
  ui.level.addEventListener('change', reshowHead);
  ui.showDistance.addEventListener('change', () => {
    // The scan's points would hide the colours: off with the map on (the
    // user may turn them back on).
    if (ui.showDistance.checked && ui.showPoints.checked) {
      ui.showPoints.checked = false;
      if (app.viewer) app.viewer.set_overlay_visible(false);
    }
    if (app.fit && app.shownStage === 'subdivide') reshowHead();
  });
  ui.showPoints.addEventListener('change', () => {
    if (!app.viewer) return;
    app.viewer.set_overlay_visible(ui.showPoints.checked);
    const text = ui.status.textContent;
    if (/^Showing /.test(text)) setStatus(text.replace(/( over the scan points)?\.$/, ui.showPoints.checked ? ' over the scan points.' : '.'));
  });
  ui.showComponents.addEventListener('change', () => {
    if (app.viewer) app.viewer.set_components_visible(ui.showComponents.checked && app.shownStage === 'subdivide');
  });
}
