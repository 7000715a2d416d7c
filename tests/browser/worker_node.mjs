// Node test of likeness_worker.wasm, the module web/worker.js runs: the same
// embind calls the page makes, without a browser. Checks
//   - exact counts and bounding boxes on small generated files (PLY point
//     cloud, OBJ quads fan-triangulated, XYZ with normals);
//   - the real scans and photos in ../shared/data (counts and sizes from
//     SOURCES.md; a photo cut in half is refused), skipped when absent;
//   - Fran's fit: each stage's reported distances equal a brute-force
//     recomputation from the returned mesh (skipped when absent);
//   - every prefix of a binary and an ascii PLY, and byte-flipped copies,
//     come back as {ok:false, message} or a valid result: never an abort
//     (an abort kills the page's worker);
//   - a project file made by `likeness fit --project` opens, saves to the
//     same bytes, and its cuts and byte flips give messages, never an abort;
//     the muscle layer's 77 shapes bake on it (face_shapes_job);
//   - the live muscle path (expression_frame_job) on a level-3 head: timed,
//     neutral exactly the rest, the head left at rest.
// Usage: node --no-experimental-fetch worker_node.mjs WEBDIR
import { createRequire } from 'node:module';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { execFileSync } from 'node:child_process';
import { fileURLToPath } from 'node:url';
import { likenessBin } from './fixtures.mjs';

const WEBDIR = path.resolve(process.argv[2] || '');
const HERE = path.dirname(fileURLToPath(import.meta.url));
const SHARED = path.resolve(HERE, '../../../shared/data');
const require = createRequire(import.meta.url);

let failures = 0, passes = 0;
function check(name, ok, detail = '') {
  if (ok) passes++; else failures++;
  console.log(`${ok ? 'PASS' : 'FAIL'}  worker: ${name}${detail ? '  (' + detail + ')' : ''}`);
}

const factory = require(path.join(WEBDIR, 'likeness_worker.js'));
let aborted = null;
const core = await factory({ print: () => {}, printErr: () => {}, onAbort: (w) => { aborted = String(w); } });

function parse(name, bytes) {
  const ptr = core._malloc(Math.max(1, bytes.length));
  core.HEAPU8.set(bytes, ptr);
  try {
    return core.parse_geometry(name, ptr, bytes.length, undefined);
  } finally {
    core._free(ptr);
  }
}

// --- exact small cases -------------------------------------------------------
{
  const pts = [[0, 0, 0], [1, 2, 3], [-1, 0.5, 2]];
  const ply = ['ply', 'format ascii 1.0', 'element vertex 3', 'property float x', 'property float y',
    'property float z', 'property uchar red', 'property uchar green', 'property uchar blue', 'end_header',
    ...pts.map((p) => p.join(' ') + ' 255 0 128')].join('\n') + '\n';
  const r = parse('three.ply', Buffer.from(ply));
  check('ascii PLY point cloud', r.ok && r.kind === 'points' && r.vertexCount === 3 && r.indices.length === 0 &&
        r.positions.length === 9 && r.positions[4] === 2 && r.colors.length === 9 &&
        Math.abs(r.colors[0] - 1) < 1e-6 && r.colors[1] === 0,
        JSON.stringify({ ok: r.ok, kind: r.kind, n: r.vertexCount, msg: r.message }));
  check('bounding box', r.ok && String(r.bboxMin) === '-1,0,0' && String(r.bboxMax) === '1,2,3',
        `${r.bboxMin} .. ${r.bboxMax}`);
}
{
  const obj = ['v 0 0 0', 'v 1 0 0', 'v 1 1 0', 'v 0 1 0', 'f 1 2 3 4'].join('\n');
  const r = parse('quad.obj', Buffer.from(obj));
  const n = r.ok ? Array.from(r.normals) : [];
  check('OBJ quad -> 2 triangles with +z normals', r.ok && r.kind === 'mesh' && r.triangleCount === 2 &&
        r.indices.length === 6 && n.length === 12 && n.every((x, i) => Math.abs(x - (i % 3 === 2 ? 1 : 0)) < 1e-6),
        JSON.stringify({ ok: r.ok, f: r.triangleCount, msg: r.message }));
}
{
  const r = parse('cloud.xyz', Buffer.from('# two points\n0 0 0 0 0 1\n1 1 1 0 1 0\n'));
  check('XYZ with normals', r.ok && r.vertexCount === 2 && r.normals.length === 6 && r.normals[4] === 1,
        JSON.stringify({ ok: r.ok, n: r.vertexCount, msg: r.message }));
}
{
  const r = parse('empty.xyz', Buffer.alloc(0));
  check('empty input is an error, not a crash', !r.ok && r.message.length > 0, r.message);
}

// --- real scans ---------------------------------------------------------------
const real = [
  ['head_scans/fran_cyberware/fran_cut.vtk', 2205, 4224],
  ['head_scans/james_menpo3d/james.obj', 6393, 12228],
];
for (const [rel, nv, nf] of real) {
  const file = path.join(SHARED, rel);
  if (!fs.existsSync(file)) { console.log(`skip  worker: ${rel} absent (../shared/data is not in the repo)`); continue; }
  const t = performance.now();
  const r = parse(path.basename(rel), fs.readFileSync(file));
  check(`${path.basename(rel)}: ${nv} vertices, ${nf} triangles`, r.ok && r.vertexCount === nv && r.triangleCount === nf,
        `${r.ok ? r.vertexCount + ' / ' + r.triangleCount : r.message}; ${(performance.now() - t).toFixed(0)} ms`);
}

// --- photos -------------------------------------------------------------------
for (const [rel, w, h] of [['head_scans/james_menpo3d/james.jpg', 2400, 1600],
                           ['eye_photos/Iris_-_left_eye_of_a_girl.jpg', 440, 265]]) {
  const file = path.join(SHARED, rel);
  if (!fs.existsSync(file)) { console.log(`skip  worker: ${rel} absent (../shared/data is not in the repo)`); continue; }
  const bytes = fs.readFileSync(file);
  const ptr = core._malloc(bytes.length);
  core.HEAPU8.set(bytes, ptr);
  const t = performance.now();
  // null: the file's bytes, decoded by the core (the page's fallback where
  // the browser's decoders are missing); inspect_image is the page's check.
  const r = core.check_image(path.basename(rel), ptr, bytes.length, null);
  const cut = core.check_image('cut.jpg', ptr, Math.floor(bytes.length / 2), null);
  const seen = core.inspect_image(path.basename(rel), ptr, bytes.length);
  core._free(ptr);
  check(`${path.basename(rel)}: ${w}x${h}, and its first half is refused`, r.ok && r.width === w && r.height === h && !cut.ok &&
        seen.ok && seen.width === w && seen.height === h && seen.format === 'JPEG',
        `${r.ok ? r.width + 'x' + r.height : r.message}; ${(performance.now() - t).toFixed(0)} ms; half: ${cut.message}`);
}

// --- broken bytes never abort ---------------------------------------------------
function binaryPly(n) {
  const header = Buffer.from(['ply', 'format binary_little_endian 1.0', `element vertex ${n}`, 'property float x',
    'property float y', 'property float z', 'element face 1', 'property list uchar int vertex_indices',
    'end_header', ''].join('\n'));
  const body = Buffer.alloc(n * 12 + 13);
  for (let i = 0; i < n * 3; i++) body.writeFloatLE(Math.sin(i), i * 4);
  body.writeUInt8(3, n * 12);
  for (let k = 0; k < 3; k++) body.writeInt32LE(k, n * 12 + 1 + 4 * k);
  return Buffer.concat([header, body]);
}
let seed = 12345;
const rand = () => (seed = (seed * 1103515245 + 12345) >>> 0) / 4294967296;
for (const [name, full] of [['bin.ply', binaryPly(40)], ['ascii.ply', Buffer.from(['ply', 'format ascii 1.0',
  'element vertex 4', 'property float x', 'property float y', 'property float z', 'element face 2',
  'property list uchar int vertex_indices', 'end_header', '0 0 0', '1 0 0', '1 1 0', '0 1 0', '3 0 1 2', '3 0 2 3', ''].join('\n'))]]) {
  const whole = parse(name, full);
  let errors = 0, oks = 0, bad = 0;
  for (let cut = 0; cut < full.length; cut++) {
    const r = parse(name, full.subarray(0, cut));
    if (aborted) break;
    if (r.ok) oks++; else if (r.message) errors++; else bad++;
  }
  for (let trial = 0; trial < 300 && !aborted; trial++) {
    const copy = Buffer.from(full);
    for (let k = 0; k < 3; k++) copy[Math.floor(rand() * copy.length)] = Math.floor(rand() * 256);
    const r = parse(name, copy);
    if (r.ok) oks++; else if (r.message) errors++; else bad++;
  }
  check(`${name}: every prefix and 300 corrupted copies give a result or a message`,
        whole.ok && !aborted && bad === 0 && errors > 0,
        aborted ? 'ABORTED: ' + aborted : `${errors} errors with messages, ${oks} parsed, whole file ok=${whole.ok}`);
}

// --- the fit's jobs on bad input: messages, never aborts ------------------------
{
  const noFit = [core.animate_frame(0.5, 3), core.export_head(3, 'obj'), core.face_shapes_job(2)];
  check('animate/export before any fit say so', noFit.every((r) => !r.ok && /no fitted head/.test(r.message)),
        noFit.map((r) => r.message).join(' | '));
  const lines = [];
  for (let i = 0; i < 60; i++) for (let j = 0; j < 60; j++) lines.push(`${i * 0.005} ${j * 0.005} 0`);
  const plane = Buffer.from(['ply', 'format ascii 1.0', `element vertex ${lines.length}`, 'property float x',
    'property float y', 'property float z', 'end_header', ...lines].join('\n') + '\n');
  const ptr = core._malloc(plane.length);
  core.HEAPU8.set(plane, ptr);
  const stages = [];
  const r = core.fit_head_job('plane.ply', ptr, plane.length, {}, (stage) => { stages.push(stage); });
  core._free(ptr);
  check('a flat plane is refused as NotAHead', !aborted && !r.ok && r.code === 'not a head' && /plane\.ply/.test(r.message),
        `${r.code}: ${r.message}`);
  const bad = core.fit_head_job('x.ply', 0, 0, { levels: 9 }, undefined);
  check('bad input to fit_head_job is a message', !bad.ok && bad.message.length > 0, bad.message);
}

// --- the Texture stage's jobs without a head, and points files -------------------
{
  const noHead = [core.texture_job([], {}, undefined), core.export_textured(3, 'x')];
  check('texture/export textured before any fit say so', noHead.every((r) => !r.ok && /fit a head first|no fitted head/.test(r.message)),
        noHead.map((r) => r.message).join(' | '));
  const good = core.parse_points('# u v X Y Z\n10 20 0.1 0.2 0.3\n\n30.5 40 -1 -2 -3 # a comment\n');
  check('a points file parses to u v X Y Z', good.ok && Array.from(good.points).join(' ') === '10 20 0.1 0.2 0.3 30.5 40 -1 -2 -3',
        good.ok ? Array.from(good.points).join(' ') : good.message);
  const bad = core.parse_points('10 20 0.1 0.2\n');
  check('a short points line is a message naming the line', !bad.ok && /line 1/.test(bad.message), bad.message);
}

// --- project files: saved and opened; cut and flipped ones give messages -------
{
  const noHead = core.save_project_job({}, {});
  check('save before any fit says so', !noHead.ok && /no fitted head/.test(noHead.message), noHead.message);
  const bin = likenessBin(WEBDIR);
  if (!bin) {
    console.log('skip  worker: project files: no native likeness to make one (set LK_LIKENESS_BIN)');
  } else {
    const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'likeness-project-'));
    try {
      const full = fittedProject(bin, dir, 3, 1);
      const open = openProject;
      const r = open(full);
      check('a project made by `likeness fit --project` opens in wasm as the fit returns it',
            r.ok && r.meshes.levels.length === 1 && r.stages.length === 4 && r.scan.vertexCount > 10000 && r.loadMs >= 0,
            r.ok ? `${full.length} bytes, level 1 ${r.meshes.levels[0].vertexCount} vertices, ${Math.round(r.loadMs)} ms` : r.message);
      // The muscle layer's shapes baked on the opened head (level 1).
      const fs1 = core.face_shapes_job(1);
      const byName = fs1.ok ? Object.fromEntries(fs1.shapes.map((x) => [x.name, x])) : {};
      const largest = (x) => { let m = 0; for (let i = 0; i + 2 < x.offsets.length; i += 3) m = Math.max(m, Math.hypot(x.offsets[i], x.offsets[i + 1], x.offsets[i + 2])); return m; };
      check('face_shapes_job bakes the 77 shapes on the opened head, jawOpen moving by over 1 cm, neutral by nothing',
            fs1.ok && fs1.shapes.length === 77 && fs1.shapes.every((x) => x.indices.length * 3 === x.offsets.length) &&
            byName.jawOpen && largest(byName.jawOpen) > 0.01 && byName.neutral && byName.neutral.indices.length === 0 &&
            byName.eyeBlinkLeft && byName.eyeBlinkLeft.indices.length > 0 && core.face_shapes_job(9).ok === false,
            fs1.ok ? `level ${fs1.level}, ${fs1.vertexCount} vertices, jawOpen ${(1000 * largest(byName.jawOpen || { offsets: [] })).toFixed(1)} mm, ${Math.round(fs1.bakeMs)} ms` : fs1.message);
      // The clips Talk plays (core/anim/clips.h) come with the shapes, and
      // the shapes with tongue out carry the tongue's push per vertex.
      const talk = fs1.ok && (fs1.clips || []).find((c) => c.name === 'Talk');
      const keysOk = talk && talk.times.length > 2 && talk.values.length === talk.times.length * talk.shapes.length &&
        talk.slopes.length === talk.values.length && talk.shapes.every((n) => byName[n]);
      const pushed = (x) => !!(x && x.tongueOffsets && x.tongueOffsets.length > 0 && x.tongueOffsets.some((v) => v !== 0));
      check('face_shapes_job hands over the clips (Talk, Blink, Gaze) and the tongue\'s push for tongueOut and viseme_TH only',
            !!keysOk && (fs1.clips || []).map((c) => c.name).join(' ') === 'Talk Blink Gaze' && pushed(byName.tongueOut) &&
            pushed(byName.viseme_TH) && Object.values(byName).filter((x) => x.tongueOffsets).length === 2,
            talk ? `Talk: ${talk.times.length} keys, ${talk.shapes.length} shapes, ${talk.times[talk.times.length - 1]} s` : 'no Talk clip');
      // jawOpen's rigid jaw motion (for the lower teeth): applied to the rest
      // place of the vertex jawOpen moves most (under the lip, whole on the
      // jaw), it gives that vertex's offset; shapes that leave the jaw have none.
      const jawCheck = (() => {
        const x = byName.jawOpen, m = x && x.jawMatrix, rest = r.meshes.levels[0].positions;
        if (!m || !rest) return null;
        let k = 0, best = -1;
        for (let j = 0; j < x.indices.length; j++) {
          const len = Math.hypot(x.offsets[3 * j], x.offsets[3 * j + 1], x.offsets[3 * j + 2]);
          if (len > best) { best = len; k = j; }
        }
        const v = x.indices[k], p = [rest[3 * v], rest[3 * v + 1], rest[3 * v + 2]];
        const err = Math.hypot(...[0, 1, 2].map((c) => m[c] * p[0] + m[4 + c] * p[1] + m[8 + c] * p[2] + m[12 + c] - p[c] - x.offsets[3 * k + c]));
        return { err, len: best };
      })();
      check('...jawOpen carries the jaw\'s motion, which moves its chin vertex by its offset; neutral and smile carry none',
            !!jawCheck && jawCheck.err < 0.05 * jawCheck.len && !byName.neutral.jawMatrix && !(byName.smile || {}).jawMatrix,
            jawCheck ? `error ${(1000 * jawCheck.err).toFixed(3)} mm of ${(1000 * jawCheck.len).toFixed(1)} mm` : 'no jawMatrix');
      const saved = core.save_project_job({}, {});
      check('...and saves to the same bytes', saved.ok && Buffer.compare(Buffer.from(saved.bytes), full) === 0,
            saved.ok ? `${saved.bytes.length} bytes` : saved.message);
      // The eyes' and teeth's textures the page hands over (image objects,
      // as the eye and smile jobs make them) come back from the file as
      // they went in; saved without them again, the file is the first.
      {
        const image = (w, h, c, seed) => ({ width: w, height: h, channels: c,
          pixels: Uint8Array.from({ length: w * h * c }, (_, i) => (i * 37 + seed * 101) & 255) });
        const eye = image(24, 16, 3, 1), teeth = image(20, 10, 4, 2);
        const withParts = core.save_project_job({ eyeTexture: eye, eyeSource: 'eye close.jpg', teethTexture: teeth, teethSource: 'smile.png' }, {});
        const back = withParts.ok ? open(Buffer.from(withParts.bytes)) : withParts;
        const same = (a, b) => !!a && a.width === b.width && a.height === b.height && a.channels === b.channels &&
          Buffer.compare(Buffer.from(a.pixels), Buffer.from(b.pixels)) === 0;
        const p = back.ok ? back.parts : {};
        const plain = core.save_project_job({}, {});
        const badImage = core.save_project_job({ eyeTexture: { width: 4, height: 4, channels: 3, pixels: new Uint8Array(5) } }, {});
        check('...with the eye and smile textures the page gives, opened again: the same pixels and photo names; without them, the same bytes as before',
              back.ok && same(p.eyeTexture, eye) && same(p.teethTexture, teeth) && p.eyeSource === 'eye close.jpg' &&
              p.teethSource === 'smile.png' && plain.ok && Buffer.compare(Buffer.from(plain.bytes), full) === 0 &&
              !badImage.ok && /eye texture/.test(badImage.message),
              back.ok ? `${withParts.bytes.length} bytes with the parts; a bad image: ${badImage.message}` : back.message);
        // The native CLI reads the page's parts: project info lists them,
        // export puts them on the eyes and teeth (not the generic ones).
        if (withParts.ok) {
          const file = path.join(dir, 'parts.likeness.glb');
          fs.writeFileSync(file, Buffer.from(withParts.bytes));
          const info = execFileSync(bin, ['project', 'info', file], { encoding: 'utf8' });
          const exported = execFileSync(bin, ['export', '--head', file, '--out', path.join(dir, 'parts.glb'), '--level', '1', '--no-animations'],
                                        { encoding: 'utf8' });
          check('...and the native CLI reads them: project info lists them, export dresses the eyes and teeth with them',
                /eyes: 24x16 texture from the photo eye close\.jpg/.test(info) && /teeth: 20x10 texture from the photo smile\.png/.test(info) &&
                /eye texture: the project's, from the photo eye close\.jpg \(24x16\)/.test(exported) &&
                /teeth texture: the project's, from the photo smile\.png \(20x10\)/.test(exported),
                (info + exported).split('\n').filter((l) => /eye|teeth/.test(l)).join(' | '));
        }
      }
      let refused = 0, bad = 0, same = 0;
      let rnd = 36;
      const next = () => (rnd = (rnd * 1103515245 + 12345) >>> 0) / 4294967296;
      for (let k = 0; k < 300 && !aborted; k++) {
        const x = open(full.subarray(0, k < 64 ? k : Math.floor(next() * full.length)));
        if (x.ok) bad++; else if (x.message) refused++; else bad++;
      }
      for (let k = 0; k < 200 && !aborted; k++) {
        const copy = Buffer.from(full);
        const at = Math.floor(next() * copy.length);
        copy[at] ^= 1 + Math.floor(next() * 255);
        const x = open(copy);
        if (x.ok) same++; else if (x.message) refused++; else bad++;
      }
      check('cut and byte-flipped project files give messages, never an abort', !aborted && bad === 0 && refused >= 450,
            aborted ? 'ABORTED: ' + aborted : `${refused} refused with a message, ${same} flips accepted, ${bad} without a message`);
    } catch (e) {
      check('a project file made natively opens in wasm', false, String(e.message).split('\n')[0]);
    } finally {
      fs.rmSync(dir, { recursive: true, force: true });
    }
    liveExpressions(bin);
  }
}

// The project file bytes of `likeness fit --levels LEVELS` on a 20k-point
// synthetic scan of SEED, made natively in DIR.
function fittedProject(bin, dir, seed, levels) {
  execFileSync(bin, ['synth-scan', '--seed', String(seed), '--points', '20000', '--out', dir], { stdio: 'pipe' });
  execFileSync(bin, ['fit', '--scan', path.join(dir, 'scan.ply'), '--out', path.join(dir, 'fit'), '--levels', String(levels),
                     '--project', path.join(dir, 'p.likeness.glb')], { stdio: 'pipe' });
  return fs.readFileSync(path.join(dir, 'p.likeness.glb'));
}

// Project file bytes opened as the worker's kept head (load_project_job).
function openProject(bytes) {
  const ptr = core._malloc(Math.max(1, bytes.length));
  core.HEAPU8.set(bytes, ptr);
  try { return core.load_project_job('p.likeness.glb', ptr, bytes.length); } finally { core._free(ptr); }
}

// The live muscle path in wasm (expression_frame_job): a level-3 head fitted
// natively to synthetic person 1 (as `likeness bench --only anim`) opened
// here; a full expression change (smile <-> surprise) posed and updated to
// levels 2 and 3, timed (issue 38 asks under 8 ms in wasm for level 3);
// neutral gives the rest positions bit for bit, the head is left at rest
// (it saves to the same bytes), and an unknown name is a message.
function liveExpressions(bin) {
  const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'likeness-live-'));
  try {
    const bytes = fittedProject(bin, dir, 1, 3);
    const opened = openProject(bytes);
    if (!opened.ok) { check('a level-3 project opens for the live expressions', false, opened.message); return; }
    const median = (a) => a.slice().sort((x, y) => x - y)[a.length >> 1];
    const timing = {};
    let moved = true;
    for (const level of [2, 3]) {
      const ms = [];
      core.expression_frame_job({ smile: 1 }, level);  // the rig made once, outside the timing
      for (let k = 0; k < 21; k++) {
        const f = core.expression_frame_job(k % 2 ? { surprise: 1 } : { smile: 1 }, level);
        if (!f.ok) { check('expression_frame_job poses the head', false, f.message); return; }
        ms.push(f.poseMs);
        const rest = opened.meshes.levels[level - 1].positions;
        let differ = 0;
        for (let i = 0; i < rest.length; i++) if (f.positions[i] !== rest[i]) differ++;
        moved = moved && differ > 100;
      }
      timing[level] = median(ms);
    }
    const neutral = core.expression_frame_job({ neutral: 1 }, 3);
    const rest3 = opened.meshes.levels[2].positions;
    const same = neutral.ok && neutral.positions.length === rest3.length && neutral.positions.every((v, i) => v === rest3[i]);
    const saved = core.save_project_job({}, {});
    const bad = core.expression_frame_job({ notAShape: 1 }, 3);
    check('live expressions in wasm: smile and surprise move the head, neutral gives the rest positions bit for bit, ' +
          'the head stays at rest, an unknown name is a message',
          moved && same && saved.ok && Buffer.compare(Buffer.from(saved.bytes), bytes) === 0 && !bad.ok && /notAShape/.test(bad.message),
          `full expression change + local update: level 2 ${timing[2].toFixed(2)} ms, level 3 ${timing[3].toFixed(2)} ms (median of 21, ` +
          `single-threaded wasm in node; goal under 8 ms at level 3); ${bad.message}`);
  } catch (e) {
    check('live expressions in wasm', false, String(e.message).split('\n')[0]);
  } finally {
    fs.rmSync(dir, { recursive: true, force: true });
  }
}

// --- the wasm fit measures what it fitted (last: the checks above need no fit) ---
// The fit reports each stage's mean and max distance from the scan points to
// that stage's surface. Recomputed here by brute force from the meshes the
// job returns (in the scan's frame) and the points parse_geometry reads, they
// must agree. Emscripten's clang 14 once miscompiled the loop that turns a
// scan to face +z (its SLP vectorizer, now off: CMakeLists.txt), moving one of
// Fran's points: the page reported max 20.1 % where the geometry says 6.9 %,
// and fitted her head to that point.
function closestOnTriangle(p, a, b, c) {  // squared distance (Ericson, 5.1.5)
  const sub = (u, v) => [u[0] - v[0], u[1] - v[1], u[2] - v[2]];
  const dot = (u, v) => u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
  const at = (o, u, s, w, t) => [o[0] + s * u[0] + t * w[0], o[1] + s * u[1] + t * w[1], o[2] + s * u[2] + t * w[2]];
  const d2 = (q) => { const e = sub(p, q); return dot(e, e); };
  const ab = sub(b, a), ac = sub(c, a), ap = sub(p, a);
  const d1 = dot(ab, ap), e2 = dot(ac, ap);
  if (d1 <= 0 && e2 <= 0) return d2(a);
  const bp = sub(p, b), d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return d2(b);
  const vc = d1 * d4 - d3 * e2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return d2(at(a, ab, d1 / (d1 - d3), ac, 0));
  const cp = sub(p, c), d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return d2(c);
  const vb = d5 * e2 - d1 * d6;
  if (vb <= 0 && e2 >= 0 && d6 <= 0) return d2(at(a, ab, 0, ac, e2 / (e2 - d6)));
  const va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) {
    const w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return d2(at(b, sub(c, b), w, ac, 0));
  }
  const den = 1 / (va + vb + vc);
  return d2(at(a, ab, vb * den, ac, vc * den));
}
function pointToMeshPct(points, mesh, diag) {
  const P = mesh.positions, I = mesh.indices, V = (i) => [P[3 * i], P[3 * i + 1], P[3 * i + 2]];
  const tris = [];
  for (let t = 0; t < I.length; t += 3) tris.push([V(I[t]), V(I[t + 1]), V(I[t + 2])]);
  let sum = 0, max = 0;
  for (let i = 0; i < points.length; i += 3) {
    const p = [points[i], points[i + 1], points[i + 2]];
    let best = Infinity;
    for (const [a, b, c] of tris) best = Math.min(best, closestOnTriangle(p, a, b, c));
    const d = Math.sqrt(best);
    sum += d;
    max = Math.max(max, d);
  }
  return { mean: 100 * sum / (points.length / 3) / diag, max: 100 * max / diag };
}
{
  const rel = 'head_scans/fran_cyberware/fran_cut.vtk';
  const file = path.join(SHARED, rel);
  if (!fs.existsSync(file)) {
    console.log(`skip  worker: the fit's stage distances on ${rel}: absent (../shared/data is not in the repo)`);
  } else {
    const bytes = fs.readFileSync(file);
    const scan = parse('fran_cut.vtk', bytes);
    const ptr = core._malloc(bytes.length);
    core.HEAPU8.set(bytes, ptr);
    const t = performance.now();
    const r = core.fit_head_job('fran_cut.vtk', ptr, bytes.length, { levels: 1 }, undefined);
    core._free(ptr);
    const fitMs = performance.now() - t;
    if (!r.ok || r.fittedPoints !== r.points) {
      check('Fran fits in wasm with every point above the neck', false, r.ok ? `${r.fittedPoints} of ${r.points}` : r.message);
    } else {
      const lo = scan.bboxMin, hi = scan.bboxMax;
      const diag = Math.hypot(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]);
      const surfaces = { initial_alignment: r.meshes.aligned, local_fitting: r.meshes.local, global_fitting: r.meshes.control };
      for (const [stage, mesh] of Object.entries(surfaces)) {
        const reported = r.stages.find((s) => s.name === stage);
        const got = pointToMeshPct(scan.positions, mesh, diag);
        const close = (x, y) => Math.abs(x - y) <= 1e-4 * Math.max(1, Math.abs(y));
        check(`Fran in wasm, ${stage}: the reported distances are those of the returned mesh`,
              reported && close(reported.meanPct, got.mean) && close(reported.maxPct, got.max),
              `reported mean/max ${reported?.meanPct.toFixed(4)} / ${reported?.maxPct.toFixed(4)} %, ` +
              `recomputed ${got.mean.toFixed(4)} / ${got.max.toFixed(4)} %; fit ${fitMs.toFixed(0)} ms`);
      }
    }
  }
}

console.log(`worker node test: ${passes}/${passes + failures} checks passed`);
process.exit(failures ? 1 : 0);
