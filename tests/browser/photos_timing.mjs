// Times the page's photos-to-textured-head flow (issue 37: ten 12-megapixel
// photos to a textured level-3 head in under 20 s) in Chromium (SwiftShader,
// this machine) and prints each stage. Not a test: a measurement (the
// machine is shared; compare runs made in the same minute).
//
// The photos: `likeness synth-photos --seed 2 --cameras 10` renders, scaled
// up in the browser to WxH JPEGs (default 3000x4000, quality 0.92), or with
// --kira the ten real photos of ../shared/data/multiview_faces (skipped with
// a message where it is absent). They are dropped at once on a fresh page
// with Auto-run on; the page finds each photo's face points, makes the head
// and textures it with no click.
//
// Printed per run: each photo's check in the worker, its detection image
// (decode + downscale) and its detection; drop -> every photo's points;
// the head (worker, wall); the texture (core, worker, wall); drop ->
// textured head. --save FILE writes the face points found (photo -> points),
// --compare FILE prints, per photo, whether a face was found in both and the
// mean and largest distance between the points (photo pixels).
// --detector cpu|gpu forces the detector's inference (the page's ?detector=);
// --query adds URL parameters (e.g. threads=1).
//
// Usage: node photos_timing.mjs WEBDIR [--kira] [--size 3000x4000] [--runs N]
//        [--detector cpu|gpu] [--save FILE] [--compare FILE] [--query K=V&...]
import { closeChromium, launchChromium, likenessBin, serveDir, takeFlag, takeOption } from './harness.mjs';
import { execFileSync } from 'node:child_process';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { fileURLToPath } from 'node:url';

const args = process.argv.slice(2);
const kira = takeFlag(args, '--kira');
const [W, H] = takeOption(args, '--size', '3000x4000').split('x').map(Number);
const runs = Math.max(1, Number(takeOption(args, '--runs', 1)) || 1);
const detector = takeOption(args, '--detector', '');
const saveFile = takeOption(args, '--save', '');
const compareFile = takeOption(args, '--compare', '');
const extraQuery = takeOption(args, '--query', '');
const [webdir] = args;
if (!webdir || !(W > 0 && H > 0)) {
  console.error('usage: node photos_timing.mjs WEBDIR [--kira] [--size 3000x4000] [--runs N] [--detector cpu|gpu] [--save FILE] [--compare FILE]');
  process.exit(2);
}
const root = path.resolve(webdir);
const SHARED = process.env.LK_SHARED_DATA || path.resolve(path.dirname(fileURLToPath(import.meta.url)), '../../../shared/data');
const KIRA = path.join(SHARED, 'multiview_faces', 'keentools_kira');
const TIMEOUT_MS = 900000;
const s1 = (ms) => (ms / 1000).toFixed(2);
const range = (xs) => xs.length ? `${s1(Math.min(...xs))}-${s1(Math.max(...xs))}` : '-';

// [{name, mimeType, buffer}] of the photos to drop, or null (skipped, said why).
async function makePhotos(context, server) {
  if (kira) {
    if (!fs.existsSync(KIRA)) {
      console.log(`photos-timing: skipped, ${KIRA} is absent (../shared/data is not in the repo)`);
      return null;
    }
    return fs.readdirSync(KIRA).filter((f) => /\.jpe?g$/i.test(f)).sort()
      .map((f) => ({ name: f, mimeType: 'image/jpeg', buffer: fs.readFileSync(path.join(KIRA, f)) }));
  }
  const bin = likenessBin(root);
  if (!bin) {
    console.log('photos-timing: skipped, no native likeness binary to make the renders (set LK_LIKENESS_BIN)');
    return null;
  }
  const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'likeness-photos-timing-'));
  try {
    execFileSync(bin, ['synth-photos', '--seed', '2', '--cameras', '10', '--out', dir]);
    const views = fs.readdirSync(dir).filter((f) => /^view_\d+\.png$/.test(f)).sort();
    // Scaled up in a page of the same origin (the browser's resampler and
    // JPEG encoder): a 12-megapixel phone photo's size and format.
    const page = await context.newPage();
    await page.goto(`http://127.0.0.1:${server.address().port}/index.html?no_sw=1&keep=0`);
    const out = [];
    for (const v of views) {
      const b64 = await page.evaluate(async ([png, w, h]) => {
        const bytes = Uint8Array.from(atob(png), (c) => c.charCodeAt(0));
        const bitmap = await createImageBitmap(new Blob([bytes], { type: 'image/png' }));
        const canvas = new OffscreenCanvas(w, h);
        const ctx = canvas.getContext('2d');
        ctx.imageSmoothingQuality = 'high';
        ctx.drawImage(bitmap, 0, 0, w, h);
        const jpeg = new Uint8Array(await (await canvas.convertToBlob({ type: 'image/jpeg', quality: 0.92 })).arrayBuffer());
        let s = '';
        for (let i = 0; i < jpeg.length; i += 0x8000) s += String.fromCharCode(...jpeg.subarray(i, i + 0x8000));
        return btoa(s);
      }, [fs.readFileSync(path.join(dir, v)).toString('base64'), W, H]);
      out.push({ name: v.replace(/\.png$/, '.jpg'), mimeType: 'image/jpeg', buffer: Buffer.from(b64, 'base64') });
    }
    await page.close();
    return out;
  } finally {
    fs.rmSync(dir, { recursive: true, force: true });
  }
}

const server = await serveDir(root);
const context = await launchChromium('photos-timing', { width: 1280, height: 900 });
const status = await measure().then(() => 0, (e) => { console.error(String(e && e.message ? e.message : e)); return 1; });
await closeChromium(context, server);
process.exit(status);

async function measure() {
  const photos = await makePhotos(context, server);
  if (!photos) return;
  const mb = photos.reduce((a, p) => a + p.buffer.length, 0) / 1e6;
  console.log(`photos: ${photos.length} ${kira ? 'real photos (Kira)' : `renders scaled to ${W}x${H} JPEGs`}, ${mb.toFixed(1)} MB`);
  let lastPoints = null;
  for (let run = 1; run <= runs; run++) {
    const page = await context.newPage();
    page.on('pageerror', (e) => console.log('page error:', e.message));
    const query = '?keep=0' + (detector ? '&detector=' + detector : '') + (extraQuery ? '&' + extraQuery : '');
    await page.goto(`http://127.0.0.1:${server.address().port}/index.html${query}`);
    await page.waitForFunction(() => document.body.dataset.state === 'ready', null, { timeout: 180000 });
    await page.evaluate(() => {
      document.getElementById('file-input').addEventListener('change', () => { window.__dropAt = performance.now(); }, true);
    });
    const t0 = Date.now();
    await page.setInputFiles('#file-input', photos);
    await page.waitForFunction(() => window.likeness.photosHead, null, { timeout: TIMEOUT_MS });
    await page.waitForFunction(() => !['working', 'loading'].includes(document.body.dataset.state), null, { timeout: TIMEOUT_MS });
    const wall = Date.now() - t0;
    const r = await page.evaluate(() => {
      const L = window.likeness;
      return {
        inference: L.detectorInference || '',
        photos: L.photos.map((p) => ({ name: p.name, size: p.width + 'x' + p.height, checkMs: p.checkMs || 0,
                                        decodeMs: p.detect && p.detect.decodeMs || 0, detectMs: p.detect && p.detect.detectMs || 0,
                                        doneAt: p.detect && p.detect.doneAt || 0, points: p.detect && p.detect.points,
                                        faces: p.detect && p.detect.faces || 0, used: !!(p.photosHead && p.photosHead.used) })),
        dropAt: window.__dropAt || 0,
        head: L.photosHead, level3: L.fit && L.fit.meshes.levels.length === 3 ? L.fit.meshes.levels[2].vertexCount : 0,
        texture: L.texture && { ms: L.texture.textureMs, workerMs: L.texture.workerMs || 0, wallMs: L.texture.wallMs,
                                photos: L.texture.photos, size: L.texture.skin.width, steps: L.texture.steps },
      };
    });
    const found = r.photos.filter((p) => p.points);
    const pointsAt = Math.max(...r.photos.map((p) => p.doneAt)) - r.dropAt;
    console.log(`run ${run}: detector inference ${r.inference || 'the solution\'s default'}; faces on ${found.length} of ${r.photos.length}`);
    console.log(`  per photo: check in the worker ${range(r.photos.map((p) => p.checkMs))} s, detection image ` +
                `${range(r.photos.map((p) => p.decodeMs))} s, detection ${range(r.photos.map((p) => p.detectMs))} s ` +
                `(first ${s1(r.photos[0].detectMs)} s, with the detector's loading)`);
    console.log(`  drop -> every photo's points: ${s1(pointsAt)} s`);
    console.log(`  head: ${r.head.ok ? `from ${r.head.used} of ${r.head.photos} photos` : 'refused: ' + r.head.message}, ` +
                `${s1(r.head.photosMs)} s in the core, ${s1(r.head.wallMs)} s wall; level 3 ${r.level3} vertices`);
    if (r.texture) {
      console.log(`  texture: ${r.texture.size}² texels from ${r.texture.photos} photos, ${s1(r.texture.ms)} s in the core, ` +
                  `${s1(r.texture.workerMs)} s in the worker (with the browser's decoding), ${s1(r.texture.wallMs)} s wall`);
      console.log('    ' + r.texture.steps.map((x) => `${x.name} ${Math.round(x.ms)}`).join(', ') + ' ms');
    } else console.log('  texture: none');
    console.log(`  drop -> textured head: ${s1(wall)} s`);
    lastPoints = Object.fromEntries(r.photos.map((p) => [p.name, p.points || null]));
    await page.close();
  }
  if (saveFile) fs.writeFileSync(saveFile, JSON.stringify(lastPoints));
  if (compareFile) {
    const ref = JSON.parse(fs.readFileSync(compareFile, 'utf8'));
    for (const [name, pts] of Object.entries(lastPoints)) {
      const q = ref[name];
      if (!pts || !q) { console.log(`  ${name}: face ${pts ? 'found' : 'not found'} now, ${q ? 'found' : 'not found'} in ${compareFile}`); continue; }
      let sum = 0, max = 0;
      pts.forEach((p, k) => { const d = Math.hypot(p[0] - q[k][0], p[1] - q[k][1]); sum += d; max = Math.max(max, d); });
      console.log(`  ${name}: points ${(sum / pts.length).toFixed(2)} px apart on average, ${max.toFixed(2)} px at most`);
    }
  }
}
