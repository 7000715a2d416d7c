// Geometry shared by the face-landmark map (make_landmark_map.mjs), its check
// (landmark_map_node.mjs) and the browser flow (flows/landmarks.mjs): OBJ
// triangle meshes, the cameras `likeness render --camera-out` writes (a GL
// lookAt + perspective; pixel origin top-left), rays from pixels, ray-triangle
// hits and closest points on a mesh.
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { execFileSync } from 'node:child_process';

export function readObj(file) {
  const pos = [], tri = [];
  for (const line of fs.readFileSync(file, 'utf8').split('\n')) {
    if (line.startsWith('v ')) pos.push(line.trim().split(/\s+/).slice(1, 4).map(Number));
    else if (line.startsWith('f ')) {
      const idx = line.trim().split(/\s+/).slice(1).map((t) => parseInt(t, 10) - 1);
      for (let k = 1; k + 1 < idx.length; k++) tri.push([idx[0], idx[k], idx[k + 1]]);
    }
  }
  return { pos, tri };
}

const sub = (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
const norm = (a) => { const l = Math.hypot(a[0], a[1], a[2]); return [a[0] / l, a[1] / l, a[2] / l]; };
export const vec = { sub, dot, cross, norm };

// The camera's frame: forward f, right r, up u (world up +y, as glm::lookAt).
export function cameraFrame(cam) {
  const f = norm(sub(cam.target, cam.eye));
  const r = norm(cross(f, [0, 1, 0]));
  const u = cross(r, f);
  const t = Math.tan((cam.fov_y_deg * Math.PI) / 360);
  return { f, r, u, t, aspect: cam.width / cam.height };
}

// Pixel [x, y] (origin top-left) of world point p, and its depth along f.
export function project(cam, p) {
  const F = cameraFrame(cam);
  const d = sub(p, cam.eye);
  const z = dot(d, F.f);
  const xn = dot(d, F.r) / (z * F.t * F.aspect), yn = dot(d, F.u) / (z * F.t);
  return { x: ((xn + 1) / 2) * cam.width, y: ((1 - yn) / 2) * cam.height, z };
}

// The same through the camera's stored GL matrices (column-major): a check
// that cameraFrame reads the file as the renderer meant it.
export function projectWithMatrices(cam, p) {
  const mul = (m, v) => [0, 1, 2, 3].map((r) => m[r] * v[0] + m[4 + r] * v[1] + m[8 + r] * v[2] + m[12 + r] * v[3]);
  const c = mul(cam.projection, mul(cam.view, [p[0], p[1], p[2], 1]));
  return { x: ((c[0] / c[3] + 1) / 2) * cam.width, y: ((1 - c[1] / c[3]) / 2) * cam.height };
}

// The ray through pixel [x, y]: {origin, dir} (dir unit).
export function pixelRay(cam, x, y) {
  const F = cameraFrame(cam);
  const xn = (2 * x) / cam.width - 1, yn = 1 - (2 * y) / cam.height;
  const dir = norm([0, 1, 2].map((k) => F.f[k] + xn * F.t * F.aspect * F.r[k] + yn * F.t * F.u[k]));
  return { origin: cam.eye, dir };
}

// Per camera, the triangles binned by the pixels they cover (cells of
// `cell` px), so a ray tests only the triangles of its cell.
export function binTriangles(mesh, cam, cell = 8) {
  const proj = mesh.pos.map((p) => project(cam, p));
  const nx = Math.ceil(cam.width / cell), ny = Math.ceil(cam.height / cell);
  const bins = new Map();
  for (const [ti, t] of mesh.tri.entries()) {
    const ps = t.map((i) => proj[i]);
    if (ps.some((q) => q.z <= 0)) continue;
    const x0 = Math.max(0, Math.floor(Math.min(...ps.map((q) => q.x)) / cell));
    const x1 = Math.min(nx - 1, Math.floor(Math.max(...ps.map((q) => q.x)) / cell));
    const y0 = Math.max(0, Math.floor(Math.min(...ps.map((q) => q.y)) / cell));
    const y1 = Math.min(ny - 1, Math.floor(Math.max(...ps.map((q) => q.y)) / cell));
    for (let y = y0; y <= y1; y++) for (let x = x0; x <= x1; x++) {
      const key = y * nx + x;
      if (!bins.has(key)) bins.set(key, []);
      bins.get(key).push(ti);
    }
  }
  return { cell, nx, bins };
}

// First hit of the ray through pixel [x, y] on the mesh: {point, normal
// (unit, the triangle's, facing the camera or not), t} or null.
export function castPixel(mesh, cam, binned, x, y) {
  const { origin, dir } = pixelRay(cam, x, y);
  const key = Math.floor(y / binned.cell) * binned.nx + Math.floor(x / binned.cell);
  let best = null;
  for (const ti of binned.bins.get(key) || []) {
    const [a, b, c] = mesh.tri[ti].map((i) => mesh.pos[i]);
    const e1 = sub(b, a), e2 = sub(c, a), pv = cross(dir, e2), det = dot(e1, pv);
    if (Math.abs(det) < 1e-14) continue;
    const tv = sub(origin, a), u = dot(tv, pv) / det;
    if (u < 0 || u > 1) continue;
    const qv = cross(tv, e1), v = dot(dir, qv) / det;
    if (v < 0 || u + v > 1) continue;
    const t = dot(e2, qv) / det;
    if (t > 0 && (!best || t < best.t)) best = { t, normal: norm(cross(e1, e2)) };
  }
  if (!best) return null;
  best.point = [0, 1, 2].map((k) => origin[k] + best.t * dir[k]);
  return best;
}

function closestOnTriangle(p, a, b, c) {
  // Ericson, Real-Time Collision Detection, 5.1.5.
  const ab = sub(b, a), ac = sub(c, a), ap = sub(p, a);
  const d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const bp = sub(p, b), d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) { const v = d1 / (d1 - d3); return [0, 1, 2].map((k) => a[k] + v * ab[k]); }
  const cp = sub(p, c), d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) { const w = d2 / (d2 - d6); return [0, 1, 2].map((k) => a[k] + w * ac[k]); }
  const va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) {
    const w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return [0, 1, 2].map((k) => b[k] + w * (c[k] - b[k]));
  }
  const denom = 1 / (va + vb + vc), v = vb * denom, w = vc * denom;
  return [0, 1, 2].map((k) => a[k] + ab[k] * v + ac[k] * w);
}

// The closest point of the mesh to p: among the triangles around the `near`
// vertices nearest p (exact for a mesh whose triangles are small against
// the distance between its sheets). {point, distance}.
export function closestOnMesh(mesh, p, near = 16, around = null) {
  if (!around) {
    around = mesh.pos.map(() => []);
    for (const [ti, t] of mesh.tri.entries()) for (const i of t) around[i].push(ti);
  }
  const nearest = [];  // the `near` closest vertices, [d2, i], sorted
  for (const [i, q] of mesh.pos.entries()) {
    const d = (q[0] - p[0]) ** 2 + (q[1] - p[1]) ** 2 + (q[2] - p[2]) ** 2;
    if (nearest.length === near && d >= nearest[near - 1][0]) continue;
    let k = nearest.length;
    while (k > 0 && nearest[k - 1][0] > d) k--;
    nearest.splice(k, 0, [d, i]);
    if (nearest.length > near) nearest.pop();
  }
  let best = null;
  for (const [, i] of nearest) for (const ti of around[i]) {
    const [a, b, c] = mesh.tri[ti].map((k) => mesh.pos[k]);
    const q = closestOnTriangle(p, a, b, c);
    const d = Math.hypot(q[0] - p[0], q[1] - p[1], q[2] - p[2]);
    if (!best || d < best.distance) best = { point: q, distance: d };
  }
  return best;
}

export function trianglesAround(mesh) {
  const around = mesh.pos.map(() => []);
  for (const [ti, t] of mesh.tri.entries()) for (const i of t) around[i].push(ti);
  return around;
}

// The generic head as a photo of it shows it: its smooth surface (the
// control mesh subdivided three times by `likeness subdiv`) with the generic
// eyeballs in the sockets (`likeness components`), one OBJ at dir/head.obj.
// Without the eyeballs the eye openings are holes, and a ray through an
// eyelid landmark would land inside the back of the head.
export function headWithEyes(bin, root, dir) {
  const run = (...a) => execFileSync(bin, a, { encoding: 'utf8' });
  const control = path.join(root, 'core/head/data/generic_head.obj');
  run('subdiv', '--mesh', control, '--levels', '3', '--out', path.join(dir, 'head'));
  run('convert', '--in', path.join(dir, 'head_level3.ply'), '--out', path.join(dir, 'head_level3.obj'));
  run('components', '--head', control, '--out', dir);
  const parts = ['head_level3.obj', 'eye_left.obj', 'eye_right.obj'].map((f) => readObj(path.join(dir, f)));
  const lines = [];
  let base = 0;
  for (const part of parts) {
    for (const p of part.pos) lines.push(`v ${p[0]} ${p[1]} ${p[2]}`);
    for (const t of part.tri) lines.push(`f ${t[0] + base + 1} ${t[1] + base + 1} ${t[2] + base + 1}`);
    base += part.pos.length;
  }
  fs.writeFileSync(path.join(dir, 'head.obj'), lines.join('\n') + '\n');
  return path.join(dir, 'head.obj');
}

// The generic head with its eyes rendered by the native CLI `bin` as a
// size-px photo (yaw 10, pitch 5: a view none of the map's views used), or
// null without the CLI. For flows that need a face photo.
export function renderedHeadPhoto(bin, root, size = 640) {
  if (!bin) return null;
  const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'likeness-head-photo-'));
  try {
    const head = headWithEyes(bin, root, dir);
    execFileSync(bin, ['render', '--mesh', head, '--yaw', '10', '--pitch', '5', '--size', String(size), '--out', path.join(dir, 'head.png')]);
    return fs.readFileSync(path.join(dir, 'head.png'));
  } finally {
    fs.rmSync(dir, { recursive: true, force: true });
  }
}
