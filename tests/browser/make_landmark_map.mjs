// Makes core/head/data/mediapipe_landmark_map.json: where each of MediaPipe
// Face Mesh's 468 landmarks lies on the generic head (issue 37, stage 1).
//
// The generic head's smooth surface with its eyeballs (the control mesh, core/head/data/
// generic_head.obj, subdivided three times by `likeness subdiv`) is rendered
// by `likeness render` from known cameras (yaw/pitch around the face, each
// camera written by --camera-out); the page's own detector code
// (web/js/landmarks.js, with @mediapipe/face_mesh from vendor/) finds the
// landmarks on each render in Chromium; each landmark's pixel is cast as a
// ray onto the rendered surface. A view counts for a landmark when its ray
// meets the surface at less than 70 degrees from the normal (a grazing hit
// is unreliable); the per-coordinate median of the views' hits, moved onto
// the surface, is the landmark's place, unless the views disagree (see
// MAX_SPREAD). Printed: per-view detection, the spread of the views' hits
// around the result by region, the worst landmarks, those left null.
//
// Usage: node tests/browser/make_landmark_map.mjs [--likeness BIN] [--out FILE]
//        [--work DIR] [--render-check PNG]   (scripts/make-landmark-map runs it)
// Redo it whenever the generic head changes.
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { execFileSync } from 'node:child_process';
import { fileURLToPath } from 'node:url';
import { closeChromium, decodePng, launchChromium, makePhotoPng, serveDir, takeOption } from './harness.mjs';
import { castPixel, binTriangles, headWithEyes, closestOnMesh, project, projectWithMatrices, readObj, trianglesAround, vec } from './landmark_geometry.mjs';

const ROOT = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '../..');
const args = process.argv.slice(2);
const bin = takeOption(args, '--likeness', path.join(ROOT, 'build/bin/likeness'));
const out = takeOption(args, '--out', path.join(ROOT, 'core/head/data/mediapipe_landmark_map.json'));
const work = takeOption(args, '--work', fs.mkdtempSync(path.join(os.tmpdir(), 'likeness-landmark-map-')));
const renderCheck = takeOption(args, '--render-check', '');
fs.mkdirSync(work, { recursive: true });
const SIZE = 800;
// Yaw (degrees, + turns the camera to the head's left) and pitch (+ above).
const VIEWS = [[0, 0], [15, 0], [-15, 0], [30, 0], [-30, 0], [0, 12], [0, -12], [15, 8], [-15, 8]];
const MIN_COS = Math.cos((70 * Math.PI) / 180);
// Views that disagree by more than this (median distance of their hits from the result)
// mark a landmark that is not a fixed place on the head: the face outline's
// points follow the silhouette, which moves over the cheeks and jaw as the
// head turns. Those are left null (docs/design/photos.md).
const MAX_SPREAD = 0.010;
const COUNT = 468;
const FM = path.join(ROOT, 'vendor/node_modules/@mediapipe/face_mesh');

const run = (...a) => execFileSync(bin, a, { encoding: 'utf8' });
if (!fs.existsSync(bin)) throw new Error(bin + ' is missing: build the native tree (scripts/build --native-only)');
if (!fs.existsSync(path.join(FM, 'face_mesh.js'))) throw new Error(FM + ' is missing: run scripts/setup');

// 1. The surface: the generic head at level 3, with its eyeballs.
const headObj = headWithEyes(bin, ROOT, work);
const mesh = readObj(headObj);
console.log(`surface: ${mesh.pos.length} vertices, ${mesh.tri.length} triangles (generic head at level 3, eyeballs)`);

// 2. The renders and their cameras, in a folder served with the detector.
const site = path.join(work, 'site');
fs.mkdirSync(path.join(site, 'js'), { recursive: true });
fs.mkdirSync(path.join(site, 'vendor'), { recursive: true });
fs.copyFileSync(path.join(ROOT, 'web/js/landmarks.js'), path.join(site, 'js/landmarks.js'));
fs.cpSync(FM, path.join(site, 'vendor/face_mesh'), { recursive: true });
fs.writeFileSync(path.join(site, 'index.html'), `<!doctype html><meta charset="utf-8"><title>landmark map</title>
<script type="module">
import { detectLandmarks } from './js/landmarks.js';
window.detect = async (url) => {
  const img = new Image();
  img.src = url;
  await img.decode();
  return detectLandmarks(img, img.naturalWidth, img.naturalHeight);
};
window.ready = true;
</script>`);
const cams = [];
for (const [i, [yaw, pitch]] of VIEWS.entries()) {
  const png = path.join(site, `view${i}.png`), camFile = path.join(work, `view${i}.json`);
  run('render', '--mesh', headObj, '--yaw', String(yaw), '--pitch', String(pitch),
      '--size', String(SIZE), '--camera-out', camFile, '--out', png);
  cams.push(JSON.parse(fs.readFileSync(camFile, 'utf8')));
}
// The camera model read here must be the renderer's: project a vertex both ways.
for (const cam of cams) {
  const a = project(cam, mesh.pos[0]), b = projectWithMatrices(cam, mesh.pos[0]);
  if (Math.hypot(a.x - b.x, a.y - b.y) > 0.05) throw new Error(`camera model mismatch: ${JSON.stringify([a, b])}`);
}

// 3. Detection in Chromium, from this folder's origin only.
const server = await serveDir(site, { isolation: false });
const origin = `http://127.0.0.1:${server.address().port}`;
const context = await launchChromium('landmark-map', { width: 900, height: 700 });
const foreign = [];
context.on('request', (r) => { if (!r.url().startsWith(origin + '/')) foreign.push(r.url()); });
const page = await context.newPage();
await page.goto(origin + '/index.html');
await page.waitForFunction(() => window.ready);
const detections = [];
for (const [i, [yaw, pitch]] of VIEWS.entries()) {
  const t0 = Date.now();
  const r = await page.evaluate((u) => window.detect(u), `view${i}.png`);
  console.log(`view ${i} (yaw ${yaw}, pitch ${pitch}): ${r.faces} face(s), ${r.points ? r.points.length : 0} points, ${Date.now() - t0} ms`);
  detections.push(r);
}
// The detector's own landmark groups (pairs of indices), to report by region.
const groups = await page.evaluate(() => Object.fromEntries(['FACE_OVAL', 'LIPS', 'LEFT_EYE', 'RIGHT_EYE', 'LEFT_EYEBROW', 'RIGHT_EYEBROW']
  .map((g) => [g, Array.from(new Set(window['FACEMESH_' + g].flat())).sort((a, b) => a - b)])));
await closeChromium(context, server);
if (foreign.length) throw new Error('requests left the origin: ' + foreign.join(', '));

// 4. Rays onto the surface; the median of the views that see a landmark well.
const binned = cams.map((cam) => binTriangles(mesh, cam));
const around = trianglesAround(mesh);
const median = (xs) => { const s = [...xs].sort((a, b) => a - b); const m = s.length >> 1; return s.length % 2 ? s[m] : (s[m - 1] + s[m]) / 2; };
const points = [], spreads = [], counts = [];
for (let k = 0; k < COUNT; k++) {
  const hits = [];
  for (const [v, det] of detections.entries()) {
    if (!det.points || det.faces !== 1) continue;
    const [x, y] = det.points[k];
    const hit = castPixel(mesh, cams[v], binned[v], x, y);
    if (!hit) continue;
    const dir = vec.norm(vec.sub(hit.point, cams[v].eye));
    if (Math.abs(vec.dot(dir, hit.normal)) < MIN_COS) continue;
    hits.push(hit.point);
  }
  counts.push(hits.length);
  if (!hits.length) { points.push(null); spreads.push(null); continue; }
  const m = [0, 1, 2].map((c) => median(hits.map((h) => h[c])));
  const onSurface = closestOnMesh(mesh, m, 16, around).point;
  points.push(onSurface);
  // Spread: the median distance of the views' hits from the result (one
  // stray view, e.g. a grazing ray past the nose tip, does not count).
  spreads.push(median(hits.map((h) => Math.hypot(h[0] - onSurface[0], h[1] - onSurface[1], h[2] - onSurface[2]))));
}

const unfixed = spreads.map((x, k) => [x, k]).filter(([x]) => x !== null && x > MAX_SPREAD).map(([, k]) => k);

// 5. The map, and what it is worth.
const mm = (v) => (v * 1000).toFixed(2);
const found = spreads.filter((s) => s !== null);
const sorted = [...found].sort((a, b) => a - b);
console.log(`mapped ${found.length} of ${COUNT} landmarks; views per landmark: min ${Math.min(...counts)}, ` +
            `median ${median(counts)}; spread of the views' hits (median distance from the result, mm): median ${mm(median(found))}, ` +
            `p95 ${mm(sorted[Math.floor(0.95 * (sorted.length - 1))])}, max ${mm(sorted[sorted.length - 1])}`);
const region = (k) => Object.keys(groups).find((g) => groups[g].includes(k)) || 'other';
for (const g of [...Object.keys(groups), 'other']) {
  const s = spreads.filter((x, k) => x !== null && region(k) === g).sort((a, b) => a - b);
  if (s.length) console.log(`  ${g}: ${s.length} landmarks, spread median ${mm(median(s))} mm, p95 ${mm(s[Math.floor(0.95 * (s.length - 1))])} mm`);
}
console.log('named: ' + [[4, 'nose tip'], [1, 'below the nose tip'], [33, 'right eye outer'], [133, 'right eye inner'], [263, 'left eye outer'],
  [362, 'left eye inner'], [61, 'right mouth corner'], [291, 'left mouth corner'], [13, 'upper lip'], [14, 'lower lip'], [152, 'chin']]
  .map(([k, n]) => `${n} #${k} ${spreads[k] === null ? 'unmapped' : mm(spreads[k]) + ' mm'}`).join(', '));
const worst = spreads.map((s, k) => [s, k]).filter(([s]) => s !== null).sort((a, b) => b[0] - a[0]).slice(0, 8);
console.log('widest spread: ' + worst.map(([s, k]) => `#${k} ${region(k)} ${mm(s)} mm (${counts[k]} views)`).join(', '));
console.log(`left null (views disagree by more than ${mm(MAX_SPREAD)} mm): ${unfixed.length}: ` +
            unfixed.map((k) => `#${k} ${region(k)}`).join(', '));
const round = (v) => Math.round(v * 1e6) / 1e6;
const map = { format: 'likeness-landmark-map', version: 1, detector: 'mediapipe-face-mesh',
              points: points.map((p, k) => (p && !unfixed.includes(k) ? p.map(round) : null)) };
fs.writeFileSync(out, '{"format":"likeness-landmark-map","version":1,"detector":"mediapipe-face-mesh","points":[\n' +
                 map.points.map((p) => JSON.stringify(p)).join(',\n') + '\n]}\n');
console.log('wrote ' + out);

// 6. For the eye: renders side by side (front, yaw 30), each with the
// detector's points (green) and the mapped points projected back (lips red,
// eyes blue, brows yellow, face outline magenta, others white), hidden ones
// left out. A mapped point far from its green twin is a bad one.
if (renderCheck) {
  const colour = { LIPS: [255, 40, 40], LEFT_EYE: [60, 120, 255], RIGHT_EYE: [60, 120, 255], LEFT_EYEBROW: [255, 220, 0],
                   RIGHT_EYEBROW: [255, 220, 0], FACE_OVAL: [255, 0, 255], other: [255, 255, 255] };
  const panels = [0, 3].map((v) => {
    const img = decodePng(fs.readFileSync(path.join(site, `view${v}.png`)));
    const put = (x, y, c, r) => {
      for (let dy = -r; dy <= r; dy++) for (let dx = -r; dx <= r; dx++) {
        const px = Math.round(x) + dx, py = Math.round(y) + dy;
        if (px >= 0 && py >= 0 && px < img.width && py < img.height) img.data.set(c, (py * img.width + px) * 4);
      }
    };
    for (const p of detections[v].points || []) put(p[0], p[1], [0, 230, 0], 1);
    for (const [k, p] of map.points.entries()) {
      if (!p) continue;
      const q = project(cams[v], p);
      const hit = castPixel(mesh, cams[v], binned[v], q.x, q.y);
      if (hit && Math.hypot(...vec.sub(hit.point, p)) > 0.002) continue;  // hidden behind the head
      put(q.x, q.y, colour[region(k)], 1);
    }
    return img;
  });
  const W = panels[0].width, H = panels[0].height;
  const px = (x, y) => { const p = panels[Math.floor(x / W)], i = (y * W + (x % W)) * 4; return [p.data[i], p.data[i + 1], p.data[i + 2]]; };
  fs.writeFileSync(renderCheck, makePhotoPng(2 * W, H, px));
  console.log('wrote ' + renderCheck + ' (front and yaw 30: detected points green, mapped points by region)');
}
console.log('work folder: ' + work);
