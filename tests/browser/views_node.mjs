// The view guide of "Take photos" (web/js/views.js) under Node, on the
// page's detector points of Kira's real photos (tests/photos/data/kira):
// each photo's view as a person sees it in the photo (docs/design/photos.md
// lists them: 0002, 0008, 0010 show her left cheek and ear; 0003, 0006,
// 0009 her right; 0001 and 0007 are frontal), the misread profile 0004
// (mouth above the eyes) counts as no view, and the missing views follow
// the photos taken.
// Usage: node tests/browser/views_node.mjs   (exit 0: every check passed)
import assert from 'node:assert/strict';
import fs from 'node:fs';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { noseOffset, viewGuide, viewOf } from '../../web/js/views.js';

const KIRA = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '../photos/data/kira');
const points = (id) => JSON.parse(fs.readFileSync(path.join(KIRA, id + '.json'), 'utf8')).points;
const seen = { '0001': 'front', '0007': 'front', '0002': 'left', '0008': 'left', '0010': 'left',
               '0003': 'right', '0006': 'right', '0009': 'right', '0004': null };
let checks = 0;
for (const [id, want] of Object.entries(seen)) {
  assert.equal(viewOf(points(id)), want, `${id}: nose offset ${noseOffset(points(id)).toFixed(2)}`);
  checks++;
}
// Mirrored (a selfie saved as a mirror image): the detector sees the
// person's sides swapped (its cheek outline points trade places), so the
// sides swap and front stays.
const mirror = (pts) => {
  const m = pts.map((p) => (p ? [1800 - p[0], p[1]] : p));
  [m[234], m[454]] = [m[454], m[234]];
  return m;
};
assert.equal(viewOf(mirror(points('0002'))), 'right');
assert.equal(viewOf(mirror(points('0001'))), 'front');
checks += 2;
// No face, or too few points: no view.
assert.equal(viewOf(null), null);
assert.equal(viewOf(new Array(468).fill(null)), null);
checks += 2;

// The guide as photos come in: what is missing, then enough.
let g = viewGuide([]);
assert.deepEqual(g.missing.map((v) => v.id), ['front', 'left', 'right']);
assert.equal(g.next.id, 'front');
g = viewGuide([points('0001'), null, points('0004')]);
assert.deepEqual(g.missing.map((v) => v.id), ['left', 'right'], 'a photo with no face or an upside-down face fills no view');
assert.equal(g.withFace, 1);
g = viewGuide([points('0001'), points('0002'), points('0003')]);
assert.deepEqual(g.missing, []);
assert.equal(g.enough, false, 'three photos: every view, but fewer than five');
g = viewGuide(['0001', '0002', '0003', '0009', '0010'].map(points));
assert.equal(g.enough, true);
assert.deepEqual(g.counts, { front: 1, left: 2, right: 2 });
checks += 8;
console.log(`views: ${checks}/${checks} checks passed`);
