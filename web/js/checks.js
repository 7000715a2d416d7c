// The fitted head's checks: what `likeness fit` prints after Table 1
// (core/pipeline/fit_quality.h), measured in the worker after the timed fit:
// triangles of the finest level turned over by a displacement or
// degenerate, self-intersecting triangle pairs by region (of the level and
// of its smooth surface without the scan's detail), the control mesh's own
// crossings, and the face's distance to the scan (the "Distance to scan"
// map). Worded for a user: what is fine, what to look at. fit.quality holds
// the worker's numbers.
import { app, ui, distanceColors } from './state.js';
import { runJob } from './worker_client.js';
import { shownLevel } from './animation.js';
import { showStage } from './head_view.js';

const count = (x) => Number(x).toLocaleString('en');
const byRegion = (c) => 'lips ' + count(c.lips) + ', ears ' + count(c.ears) + ', eye sockets ' + count(c.eyeSockets || 0) +
                        ', elsewhere ' + count(c.rest);

function qualityItem(cls, text) {
  const li = document.createElement('li');
  li.className = cls;
  li.textContent = text;
  ui.qualityList.appendChild(li);
}

export function showQuality(q) {
  const L = q.level, c = q.crossings, sm = q.smoothCrossings;
  ui.qualityTitle.textContent = 'Checks of level ' + L + ' (' + count(q.triangles) + ' triangles)';
  ui.qualityList.replaceChildren();
  if (q.flipped + q.degenerate === 0) {
    qualityItem('ok', 'No folds: no triangle turned over by the scan\'s detail, none degenerate.');
  } else {
    qualityItem('look', count(q.flipped) + ' triangles turned over by the scan\'s detail, ' + count(q.degenerate) +
                ' degenerate (no area): they can show as dark specks; look at level ' + L + ' with Wireframe on.');
  }
  if (c.total === 0) {
    qualityItem('ok', 'No self-intersections: the surface never passes through itself.');
  } else {
    let text = count(c.total) + ' self-intersecting triangle pairs (' + byRegion(c) + ').';
    if (c.lips) text += ' The lips cross each other: they may show through one another when the mouth opens.';
    if (c.ears) text += ' At the ears: folds of the ear rims, which scans rarely capture well; the ears do not move in the animation.';
    if (c.eyeSockets) text += ' In the eye sockets: behind the lids, where the eyeballs sit; hidden when the eyes are shown.';
    if (c.rest) text += ' Elsewhere: small overlaps, often at the eye rims, nose or brow; look there with Wireframe on.';
    qualityItem('look', text);
  }
  qualityItem('note', 'The smooth surface under the detail (level ' + L + ' of the control mesh, without displacements): ' +
              (sm.total === 0 ? 'no self-intersections' : count(sm.total) + ' pairs (' + byRegion(sm) + ')') +
              (c.total === 0 ? '.' : sm.total === 0 ? ': every crossing above comes from the scan\'s detail.'
                                   : ': crossings there come from the fitted shape, not from the detail.'));
  if (q.controlCrossings === 0) qualityItem('ok', 'The control mesh does not cross itself.');
  else qualityItem('look', 'The control mesh crosses itself in ' + count(q.controlCrossings) +
                   ' triangle pairs: the fit folded it there, and every level inherits the fold.');
  if (q.faceToScan && !(app.fit && app.fit.fromPhotos)) {  // a head from photos has no scan to measure against
    const d = q.faceToScan;
    const against = d.to === 'points' ? 'Against your scan\'s points (a small surface fitted to each vertex\'s 16 nearest), where it was scanned'
                                      : 'Against your scan\'s own triangles, where it was scanned';
    if (d.vertices === 0) qualityItem('note', against + ': no vertex of the face lies over a scanned part of it.');
    else qualityItem('note', against + ': the face of level ' + L + ' lies ' +
                     d.meanMm.toFixed(2) + ' mm from it on average, 99 % of its ' + count(d.vertices) + ' vertices within ' +
                     d.p99Mm.toFixed(1) + ' mm, the farthest ' + d.maxMm.toFixed(1) + ' mm.');
  }
  qualityItem('note', 'Checked in ' + (q.checkMs / 1000).toFixed(2) + ' s in the worker, after the timed fit (as likeness fit does).');
  const look = [];
  if (q.flipped + q.degenerate) look.push(count(q.flipped + q.degenerate) + ' folded or degenerate triangles');
  if (c.total) {
    const where = [['the lips', c.lips], ['the ears', c.ears], ['the eye sockets', c.eyeSockets || 0], ['elsewhere', c.rest]]
      .filter((w) => w[1])
      .map((w) => w[0] + ' ' + count(w[1]));
    look.push('the surface crosses itself in ' + count(c.total) + ' triangle pairs (' + where.join(', ') + ')');
  }
  if (q.controlCrossings) look.push('the control mesh crosses itself (' + count(q.controlCrossings) + ' pairs)');
  ui.qualitySummary.className = 'quality-summary ' + (look.length ? 'look' : 'ok');
  ui.qualitySummary.textContent = look.length ? 'Worth a look: ' + look.join('; ') + '.'
                                              : 'All checks passed: no folds and no self-intersections.';
}

app.showQuality = showQuality;  // tests: the wording for a head that does cross itself

export async function checkFitQuality(fit) {
  fit.quality = null;
  ui.fitQuality.hidden = false;
  ui.showDistance.disabled = true;
  ui.fitQuality.classList.add('checking');
  ui.qualityTitle.textContent = 'Checks';
  ui.qualitySummary.className = 'quality-summary';
  ui.qualitySummary.textContent = 'checking… (folds and self-intersections of the finest level; animate or export meanwhile)';
  ui.qualityList.replaceChildren();
  let q;
  try {
    q = await runJob({ type: 'quality' }, []);
  } catch (e) {
    q = { ok: false, message: e && e.cancelled ? 'cancelled' : (e && e.message ? e.message : String(e)) };
  }
  if (app.fit !== fit) return;  // a newer fit, or none, is shown now
  ui.fitQuality.classList.remove('checking');
  if (!q.ok) {
    fit.quality = { ok: false, message: q.message || q.code };
    ui.qualitySummary.textContent = 'The checks could not run: ' + (q.message || q.code) + '.';
    return;
  }
  fit.quality = q;
  showQuality(q);
  ui.showDistance.disabled = !distanceMap(true);
  ui.exportMap.disabled = ui.exportObj.disabled || !distanceMap(true);
  if (ui.showDistance.checked && app.shownStage === 'subdivide') showStage('subdivide');
}

// The finest level's distance map from the checks (faceToScan.colors), or
// null; anyLevel: whether there is one at all, else only while the finest
// level is the one shown.
export function distanceMap(anyLevel = false) {
  const colors = distanceColors();
  if (!colors) return null;
  return anyLevel || shownLevel() === app.fit.quality.level ? colors : null;
}
