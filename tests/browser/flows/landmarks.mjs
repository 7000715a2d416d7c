// Automatic face landmarks (issue 37, stage 1): the generic head rendered by
// the native `likeness render` from a camera none of the landmark map's
// views used (yaw 10, pitch 5; the camera written by --camera-out) is
// dropped as a photo with a flat grey one and one showing the head twice. On the render the page's
// detector (MediaPipe Face Mesh, served from the page's origin) finds one
// face of 468 points, and the nose tip, eye corners and mouth corners lie
// within TOLERANCE_PX of the generic head's mapped points
// (core/head/data/mediapipe_landmark_map.json) projected by that camera; on
// the flat image it says no face was found; on the double one, two faces. A point dragged in the photo
// view moves by the drag; Save points writes the likeness-landmarks JSON.
// Served without the detector's files, the page says so beside the photo.
// The run's closing check covers requests: none leaves the origin.
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { execFileSync } from 'node:child_process';
import { fileURLToPath } from 'node:url';
import { check, decodePng, likenessBin, makePhotoPng, note, READY_TIMEOUT_MS, runAlone, settled, waitForState } from '../harness.mjs';
import { headWithEyes, project } from '../landmark_geometry.mjs';

const ROOT = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '../../..');
// The render is 800 px square, the head about 330 px wide: 8 px is about
// 5.5 mm on the face. Measured: 2.1-7.1 px with the map re-made from the
// detector's points on synthetic people (core/head/data/README.md; 1.0-6.5
// px with the first map, made on this head's own renders); the map's slide
// for the view is not applied here. Lips mapped onto the chin would be
// some 60 px off.
const TOLERANCE_PX = 8;
const NAMED = [[4, 'nose tip'], [33, 'right eye outer corner'], [133, 'right eye inner corner'],
               [263, 'left eye outer corner'], [362, 'left eye inner corner'], [61, 'right mouth corner'],
               [291, 'left mouth corner']];

// The rendered head photo (with its eyeballs, as the map was made) and its camera.
function renderHead(bin) {
  const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'likeness-landmarks-'));
  const head = headWithEyes(bin, ROOT, dir);
  execFileSync(bin, ['render', '--mesh', head, '--yaw', '10', '--pitch', '5', '--size', '800',
                     '--camera-out', path.join(dir, 'camera.json'), '--out', path.join(dir, 'head.png')]);
  const out = { png: fs.readFileSync(path.join(dir, 'head.png')), camera: JSON.parse(fs.readFileSync(path.join(dir, 'camera.json'), 'utf8')) };
  fs.rmSync(dir, { recursive: true, force: true });
  return out;
}

// The middle 400 px of the 800-px render twice, side by side: two faces.
function twoHeads(png) {
  const img = decodePng(png);
  return makePhotoPng(800, 800, (x, y) => {
    const i = (y * img.width + (x < 400 ? x + 200 : x - 200)) * 4;
    return [img.data[i], img.data[i + 1], img.data[i + 2]];
  });
}

async function detections(page) {
  await page.waitForFunction(() => window.likeness.photos.length > 0 && window.likeness.photos.every((p) =>
    p.detect && !['waiting', 'running'].includes(p.detect.state)), null, { timeout: 180000 });
  return page.evaluate(() => Object.fromEntries(window.likeness.photos.map((p) => [p.name, {
    state: p.detect.state, faces: p.detect.faces, points: p.detect.points, message: p.detect.message, ms: p.detect.ms,
    row: Array.from(document.querySelectorAll('#photo-list li')).find((li) => li.querySelector('.photo-name').textContent === p.name)
      ?.querySelector('.photo-meta').textContent }])));
}

async function run(s) {
  const bin = likenessBin(s.webdir);
  if (!bin) {
    note('landmarks: skipped, no native likeness binary to render the head (set LK_LIKENESS_BIN)');
    return;
  }
  const map = JSON.parse(fs.readFileSync(path.join(ROOT, 'core/head/data/mediapipe_landmark_map.json'), 'utf8'));
  const { png, camera } = renderHead(bin);
  const page = await s.page();
  await page.setInputFiles('#file-input', [
    { name: 'rendered_head.png', mimeType: 'image/png', buffer: png },
    { name: 'flat_grey.png', mimeType: 'image/png', buffer: makePhotoPng(320, 240, () => [128, 128, 128]) },
    { name: 'two_heads.png', mimeType: 'image/png', buffer: twoHeads(png) },
  ]);
  await settled(page);
  const t0 = Date.now();
  const found = await detections(page);
  const head = found['rendered_head.png'], flat = found['flat_grey.png'], two = found['two_heads.png'];
  check('the rendered head: one face of 468 points found', head.state === 'found' && head.faces === 1 && head.points.length === 468,
        `${head.state}, ${head.faces} face(s), ${head.points ? head.points.length : 0} points in ${head.ms} ms; row "${head.row}"`);
  if (head.points) {
    const errors = NAMED.map(([k, name]) => {
      const q = project(camera, map.points[k]);
      return { name, k, err: Math.hypot(q.x - head.points[k][0], q.y - head.points[k][1]) };
    });
    check(`nose tip, eye and mouth corners within ${TOLERANCE_PX} px of the mapped generic-head points, projected`,
          errors.every((e) => e.err <= TOLERANCE_PX), errors.map((e) => `${e.name} (#${e.k}) ${e.err.toFixed(1)} px`).join(', '));
  }
  check('the flat grey image: "no face found", beside the photo', flat.state === 'none' && /no face found/.test(flat.row || ''),
        `${flat.state}: "${flat.row}"`);
  check('the image with the head twice: "2 faces found", beside the photo', two.state === 'many' && two.faces === 2 &&
        /2 faces found/.test(two.row || ''), `${two.state}, ${two.faces} face(s): "${two.row}"`);
  note(`detection of the three photos took ${Date.now() - t0} ms after the drop`);
  const fetched = s.requests.filter((u) => u.includes('/vendor/face_mesh/'));
  check('the detector and its model came from the page\'s origin', fetched.some((u) => u.endsWith('face_mesh_solution_packed_assets.data')) &&
        fetched.every((u) => s.ownOrigins.some((o) => u.startsWith(o + '/'))), `${fetched.length} requests under /vendor/face_mesh/`);

  if (!head.points) return;
  // Drag landmark 1 (under the nose tip) 30 CSS px right and 20 down in the photo view.
  await page.locator('#photo-list li', { hasText: 'rendered_head.png' }).click();
  await page.waitForFunction(() => !document.getElementById('clicker').hidden);
  await page.evaluate(() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r))));
  const at = await page.evaluate(() => {
    const c = document.getElementById('clicker-canvas').getBoundingClientRect();
    const p = window.likeness.photos.find((q) => q.name === 'rendered_head.png');
    return { c: { left: c.left, top: c.top }, p: p.detect.points[1] };
  });
  const view = await page.evaluate(() => {
    // clicker.view is module state; recompute it as drawClicker does.
    const canvas = document.getElementById('clicker-canvas'), dpr = window.devicePixelRatio || 1;
    const w = canvas.width, h = canvas.height, scale = Math.min(w / 800, h / 800);
    return { scale, ox: (w - 800 * scale) / 2, oy: (h - 800 * scale) / 2, dpr };
  });
  const sx = at.c.left + (view.ox + at.p[0] * view.scale) / view.dpr, sy = at.c.top + (view.oy + at.p[1] * view.scale) / view.dpr;
  await page.mouse.move(sx, sy);
  await page.mouse.down();
  await page.mouse.move(sx + 15, sy + 10);
  await page.mouse.move(sx + 30, sy + 20);
  await page.mouse.up();
  const moved = await page.evaluate(() => window.likeness.photos.find((q) => q.name === 'rendered_head.png').detect.points[1]);
  const want = [at.p[0] + 30 * view.dpr / view.scale, at.p[1] + 20 * view.dpr / view.scale];
  check('dragging a point (landmark 1) moves it by the drag (to within a pixel)', Math.hypot(moved[0] - want[0], moved[1] - want[1]) < 1.5,
        `from (${at.p.map((v) => v.toFixed(1))}) to (${moved.map((v) => v.toFixed(1))}), wanted (${want.map((v) => v.toFixed(1))})`);

  const downloads = await page.evaluate(() => window.likeness.downloads.length);
  await page.click('#clicker-save-points');
  const saved = await page.evaluate(async (n) => {
    const m = await import('./js/landmarks.js');
    const p = window.likeness.photos.find((q) => q.name === 'rendered_head.png');
    return { download: window.likeness.downloads.slice(n), json: m.landmarksJson(p.name, p.width, p.height, p.detect.points) };
  }, downloads);
  const j = saved.json;
  check('Save points writes rendered_head.landmarks.json in the likeness-landmarks format',
        saved.download.length === 1 && saved.download[0].name === 'rendered_head.landmarks.json' &&
        j.format === 'likeness-landmarks' && j.version === 1 && j.detector === 'mediapipe-face-mesh' &&
        j.image.name === 'rendered_head.png' && j.image.width === 800 && j.image.height === 800 && j.points.length === 468 &&
        Math.abs(j.points[1][0] - moved[0]) < 0.01, JSON.stringify(saved.download) + ' ' + JSON.stringify(j).slice(0, 160));
  await page.click('#clicker-close');
  await missingDetector(s, png);
  // Leave the page's photos as they were for the flows after this one.
  await page.evaluate(() => {
    for (const li of Array.from(document.querySelectorAll('#photo-list li'))) {
      const n = li.querySelector('.photo-name').textContent;
      if (['rendered_head.png', 'flat_grey.png', 'two_heads.png'].includes(n)) li.querySelector('.photo-remove').click();
    }
  });
}

// A site without the detector (its loader a 404): the photo is kept and
// its row says the face points could not be found, and why. The page is not
// watched: the 404 is logged as a console error on purpose.
async function missingDetector(s, png) {
  const { server, origin } = await s.serve({ broken: { '/vendor/face_mesh/face_mesh.js': '404' } });
  const page = await (await s.context()).newPage();
  const uncaught = [];
  page.on('pageerror', (e) => uncaught.push(e.message));
  try {
    await page.goto(origin + '/index.html?autofit=0');
    await waitForState(page, ['ready', 'error'], READY_TIMEOUT_MS);
    await page.setInputFiles('#file-input', { name: 'head.png', mimeType: 'image/png', buffer: png });
    await settled(page);
    const found = await detections(page);
    const row = found['head.png'];
    check('without the detector\'s files: the photo is kept, its row says the face points were not found and why',
          row.state === 'failed' && /face points not found: the face detector .* is missing/.test(row.row || '') &&
          uncaught.length === 0 && (await page.evaluate(() => document.body.dataset.state)) !== 'error',
          `"${row.row}"` + (uncaught.length ? '; uncaught: ' + uncaught.join(' | ') : ''));
  } finally {
    await page.close();
    server.closeAll();
  }
}

export const flow = { name: 'landmarks', title: 'face landmarks found in the page (MediaPipe Face Mesh from our origin), mapped onto the generic head', run };
runAlone(import.meta.url, flow);
