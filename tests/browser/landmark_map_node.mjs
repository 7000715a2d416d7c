// Checks core/head/data/mediapipe_landmark_map.json, the face landmarks'
// places on the generic head (made by make_landmark_map.mjs, then re-made
// with the detector's view-dependent slide by `likeness learn-landmark-map
// --slide`: core/head/data/README.md), under Node: its format (version 2:
// a "slide" per landmark); 468 entries, each null or three finite numbers;
// every point within MAX_OFF_MM of the generic head's control mesh (the
// detector sees its points up to 12 mm off the skin, and the core refuses a
// map point beyond 16 mm: PhotosJobOptions::map_max_distance_m); every point on the face's side of the head (z > -20 mm; the back of the
// head is at about -100 mm; the outline's temple point 127 sits at -8 mm
// where the detector sees it, beside the ear: a ray
// that went through an opening, e.g. an eye without its eyeball, ends there);
// and the face's layout in the head's frame (head_model.h: +x is
// the head's left, +y up, +z forward): the nose tip in front of the eyes and
// mouth, the head's right eye (landmarks 33, 133) at -x and its left (263,
// 362) at +x, the mouth below the nose and the brows above the eyes, the
// mouth corners apart by a mouth's width. A map made from mislabelled or
// mis-projected detections fails these.
import fs from 'node:fs';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { closestOnMesh, readObj, trianglesAround } from './landmark_geometry.mjs';

const ROOT = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '../..');
const MAX_OFF_MM = 16;
let failed = 0;
function check(name, ok, detail = '') {
  console.log(`${ok ? 'PASS' : 'FAIL'}  ${name}${detail ? '  (' + detail + ')' : ''}`);
  if (!ok) failed++;
}

const map = JSON.parse(fs.readFileSync(path.join(ROOT, 'core/head/data/mediapipe_landmark_map.json'), 'utf8'));
check('format likeness-landmark-map version 2, detector mediapipe-face-mesh, with a slide per landmark',
      map.format === 'likeness-landmark-map' && map.version === 2 && map.detector === 'mediapipe-face-mesh' &&
      map.slide && Array.isArray(map.slide.shifts) && map.slide.shifts.length === 468 &&
      Array.isArray(map.slide.sigma) && map.slide.sigma.length === 468);
check('468 entries', Array.isArray(map.points) && map.points.length === 468, `${map.points && map.points.length}`);
const bad = map.points.map((p, k) => [p, k]).filter(([p]) => p !== null &&
  !(Array.isArray(p) && p.length === 3 && p.every((v) => typeof v === 'number' && Number.isFinite(v))));
check('each entry null or three finite numbers', bad.length === 0, bad.slice(0, 3).map(([p, k]) => `#${k}: ${JSON.stringify(p)}`).join(', '));
const present = map.points.filter(Boolean).length;
check('at least 400 of the 468 landmarks mapped', present >= 400, `${present}`);

const mesh = readObj(path.join(ROOT, 'core/head/data/generic_head.obj'));
const around = trianglesAround(mesh);
const off = map.points.map((p) => (p ? closestOnMesh(mesh, p, 24, around).distance * 1000 : 0));
const worst = off.map((d, k) => [d, k]).sort((a, b) => b[0] - a[0])[0];
const sorted = [...off].sort((a, b) => a - b);
check(`every mapped point within ${MAX_OFF_MM} mm of the generic head's control mesh`, worst[0] <= MAX_OFF_MM,
      `median ${sorted[sorted.length >> 1].toFixed(2)} mm, max ${worst[0].toFixed(2)} mm at #${worst[1]}`);

const behind = map.points.map((p, k) => [p, k]).filter(([p]) => p && p[2] <= -0.02).map(([, k]) => k);
check('every mapped point on the face\'s side of the head (z > -20 mm)', behind.length === 0, behind.slice(0, 8).map((k) => '#' + k).join(', '));

const P = (k) => map.points[k];
const named = [4, 33, 133, 263, 362, 61, 291, 13, 14, 105, 334, 159, 386];
if (named.every((k) => P(k))) {
  const [nose, rOut, rIn, lOut, lIn, rMouth, lMouth, upperLip, lowerLip, rBrow, lBrow, rLid, lLid] = named.map(P);
  check('the nose tip is in front of the eyes and the mouth corners',
        [rOut, rIn, lOut, lIn, rMouth, lMouth].every((q) => nose[2] > q[2] + 0.01), `nose z ${nose[2]}`);
  check('the head\'s right eye at -x, its left eye at +x', rOut[0] < rIn[0] && rIn[0] < 0 && lOut[0] > lIn[0] && lIn[0] > 0,
        `x: 33 ${rOut[0]}, 133 ${rIn[0]}, 362 ${lIn[0]}, 263 ${lOut[0]}`);
  check('lips and mouth corners below the nose tip, above the chin (152)', [upperLip, lowerLip, rMouth, lMouth].every((q) =>
    q[1] < nose[1] - 0.005 && q[1] > P(152)[1]) && upperLip[1] > lowerLip[1], `y: nose ${nose[1]}, lips ${upperLip[1]} ${lowerLip[1]}, chin ${P(152)[1]}`);
  check('brows above the eyelids', rBrow[1] > rLid[1] + 0.005 && lBrow[1] > lLid[1] + 0.005, `y: brows ${rBrow[1]} ${lBrow[1]}, lids ${rLid[1]} ${lLid[1]}`);
  const mouth = Math.hypot(lMouth[0] - rMouth[0], lMouth[1] - rMouth[1], lMouth[2] - rMouth[2]) * 1000;
  check('the mouth corners 35-65 mm apart', mouth > 35 && mouth < 65, `${mouth.toFixed(1)} mm`);
} else {
  check('the named landmarks are mapped', false, named.filter((k) => !P(k)).join(', '));
}
console.log(failed ? `landmark map: ${failed} check(s) failed` : 'landmark map: all checks passed');
process.exit(failed ? 1 : 0);
