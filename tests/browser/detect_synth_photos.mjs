// The real detector's points on synthetic photo sessions with a known truth
// (issue 37): `likeness synth-photos --seed N --cameras C` renders a
// synthetic person from phone-like cameras (the person and the cameras are
// deterministic for the seed); the page's own detector code
// (web/js/landmarks.js with @mediapipe/face_mesh from vendor/, served from
// this script's own origin, no other request allowed) finds the face points
// on each render in Chromium; each photo's points are written in the page's
// export format (landmarksJson, what "Save points" downloads):
//   OUT/seedN/view_XX.json   (only views where a face was found)
//   OUT/session.json         {"cameras": C, "seeds": [...]}: the bench re-makes
//                            each seed's person and cameras from these
//   OUT/groups.json          the detector's own landmark groups (FACE_OVAL,
//                            LIPS, eyes, brows), for per-group reports
// so `likeness photos --points OUT/seedN/*.json` and
// `likeness bench --only photos --photos-detected OUT` score the head made
// from real-detector points against the synthetic truth, natively.
//
// Usage: node tests/browser/detect_synth_photos.mjs [--likeness BIN]
//        [--out DIR] [--seeds 1,2,3] [--cameras 8] [--work DIR]
// The committed set tests/photos/data/detected was made with the defaults.
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { execFileSync } from 'node:child_process';
import { fileURLToPath } from 'node:url';
import { closeChromium, launchChromium, serveDir, takeOption } from './harness.mjs';

const ROOT = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '../..');
const args = process.argv.slice(2);
const bin = takeOption(args, '--likeness', path.join(ROOT, 'build/bin/likeness'));
const out = takeOption(args, '--out', path.join(ROOT, 'tests/photos/data/detected'));
const seeds = takeOption(args, '--seeds', '1,2,3,4,5').split(',').map(Number);
const cameras = Number(takeOption(args, '--cameras', '8'));
const work = takeOption(args, '--work', fs.mkdtempSync(path.join(os.tmpdir(), 'likeness-detect-synth-')));
if (args.length) throw new Error('unknown arguments: ' + args.join(' '));
if (seeds.some((s) => !Number.isInteger(s) || s < 0) || !(cameras >= 2 && cameras <= 64))
  throw new Error('--seeds takes integers (1,2,3), --cameras 2..64');
const FM = path.join(ROOT, 'vendor/node_modules/@mediapipe/face_mesh');
if (!fs.existsSync(bin)) throw new Error(bin + ' is missing: build the native tree (scripts/build --native-only)');
if (!fs.existsSync(path.join(FM, 'face_mesh.js'))) throw new Error(FM + ' is missing: run scripts/setup');

// The site: the page's detector module and the detector's files.
const site = path.join(work, 'site');
fs.mkdirSync(path.join(site, 'js'), { recursive: true });
fs.mkdirSync(path.join(site, 'vendor'), { recursive: true });
fs.copyFileSync(path.join(ROOT, 'web/js/landmarks.js'), path.join(site, 'js/landmarks.js'));
fs.cpSync(FM, path.join(site, 'vendor/face_mesh'), { recursive: true });
fs.writeFileSync(path.join(site, 'index.html'), `<!doctype html><meta charset="utf-8"><title>detect synth photos</title>
<script type="module">
import { detectLandmarks, landmarksJson } from './js/landmarks.js';
window.detect = async (url, name) => {
  const img = new Image();
  img.src = url;
  await img.decode();
  const r = await detectLandmarks(img, img.naturalWidth, img.naturalHeight);
  return { faces: r.faces, json: r.points ? landmarksJson(name, img.naturalWidth, img.naturalHeight, r.points) : null };
};
window.ready = true;
</script>`);

// The renders (the session's own placeholder-map points are not used).
const sessions = [];
for (const seed of seeds) {
  const dir = path.join(site, `seed${seed}`);
  execFileSync(bin, ['synth-photos', '--out', dir, '--seed', String(seed), '--cameras', String(cameras)], { encoding: 'utf8' });
  const views = fs.readdirSync(dir).filter((f) => /^view_\d+\.png$/.test(f)).sort();
  sessions.push({ seed, views });
}

const server = await serveDir(site, { isolation: false });
const origin = `http://127.0.0.1:${server.address().port}`;
const context = await launchChromium('detect-synth', { width: 900, height: 700 });
const foreign = [];
context.on('request', (r) => { if (!r.url().startsWith(origin + '/')) foreign.push(r.url()); });
const page = await context.newPage();
await page.goto(origin + '/index.html');
await page.waitForFunction(() => window.ready);
fs.mkdirSync(out, { recursive: true });
for (const { seed, views } of sessions) {
  const dst = path.join(out, `seed${seed}`);
  fs.rmSync(dst, { recursive: true, force: true });
  fs.mkdirSync(dst, { recursive: true });
  const found = [];
  for (const v of views) {
    const r = await page.evaluate(([u, n]) => window.detect(u, n), [`seed${seed}/${v}`, v]);
    if (!r.json) continue;
    found.push(`${v} (${r.faces} face${r.faces > 1 ? 's' : ''})`);
    // One point per line: small diffs when regenerated.
    fs.writeFileSync(path.join(dst, v.replace(/\.png$/, '.json')),
      JSON.stringify({ ...r.json, points: [] }).replace('"points":[]', '"points":[\n' +
        r.json.points.map((p) => JSON.stringify(p)).join(',\n') + '\n]') + '\n');
  }
  console.log(`seed ${seed}: a face on ${found.length} of ${views.length} views: ${found.join(', ')}`);
}
// The detector's own landmark groups (its index pairs, as sets; defined once it has loaded).
const groups = await page.evaluate(() => Object.fromEntries(['FACE_OVAL', 'LIPS', 'LEFT_EYE', 'RIGHT_EYE', 'LEFT_EYEBROW', 'RIGHT_EYEBROW']
  .map((g) => [g, Array.from(new Set(window['FACEMESH_' + g].flat())).sort((a, b) => a - b)])));
fs.writeFileSync(path.join(out, 'session.json'), JSON.stringify({ cameras, seeds }) + '\n');
fs.writeFileSync(path.join(out, 'groups.json'), '{\n' + Object.entries(groups).map(([g, v]) => `"${g}":${JSON.stringify(v)}`).join(',\n') + '\n}\n');
await closeChromium(context, server);
if (foreign.length) throw new Error('requests left the origin: ' + foreign.join(', '));
console.log('wrote ' + out + ' (work folder ' + work + ')');
