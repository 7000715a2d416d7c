// Node test of likeness_worker.wasm, the module web/worker.js runs: the same
// embind calls the page makes, without a browser. Checks
//   - exact counts and bounding boxes on small generated files (PLY point
//     cloud, OBJ quads fan-triangulated, XYZ with normals);
//   - the real scans and photos in ../shared/data (counts and sizes from
//     SOURCES.md; a photo cut in half is refused), skipped when absent;
//   - every prefix of a binary and an ascii PLY, and byte-flipped copies,
//     come back as {ok:false, message} or a valid result: never an abort
//     (an abort kills the page's worker).
// Usage: node --no-experimental-fetch worker_node.mjs WEBDIR
import { createRequire } from 'node:module';
import fs from 'node:fs';
import path from 'node:path';
import { fileURLToPath } from 'node:url';

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
  const r = core.check_image(path.basename(rel), ptr, bytes.length);
  const cut = core.check_image('cut.jpg', ptr, Math.floor(bytes.length / 2));
  core._free(ptr);
  check(`${path.basename(rel)}: ${w}x${h}, and its first half is refused`, r.ok && r.width === w && r.height === h && !cut.ok,
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
  const noFit = [core.animate_frame(0.5, 3), core.export_head(3, 'obj')];
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

console.log(`worker node test: ${passes}/${passes + failures} checks passed`);
process.exit(failures ? 1 : 0);
