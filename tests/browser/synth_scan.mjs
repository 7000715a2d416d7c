// A synthetic head scan made by the native CLI, for the browser and Node
// tests. No Playwright here: worker_threads_node.mjs runs under
// --no-experimental-fetch, where playwright-core does not load.
import { execFileSync } from 'node:child_process';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { likenessBin } from './fixtures.mjs';

// `points` points of synthetic head `seed`, made by `likeness synth-scan`
// (env LK_LIKENESS_BIN, else WEBDIR/../bin/likeness): { bytes } or { skip: why }.
export function syntheticScan(webdir, seed, points = 60000) {
  const bin = likenessBin(webdir);
  if (!bin) return { skip: 'no native likeness binary (set LK_LIKENESS_BIN)' };
  const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'likeness-synth-'));
  try {
    execFileSync(bin, ['synth-scan', '--seed', String(seed), '--points', String(points), '--out', dir], { stdio: 'pipe' });
    return { bytes: fs.readFileSync(path.join(dir, 'scan.ply')) };
  } catch (e) {
    return { skip: 'likeness synth-scan failed: ' + String(e.message).split('\n')[0] };
  } finally {
    fs.rmSync(dir, { recursive: true, force: true });
  }
}

// The native CLI's fit of the same scan bytes (`likeness fit`): its
// report.json stages [{name, mean_pct, ...}], quality (the finest level's
// checks) and faceToScan (face_to_scan: to triangles or points, metres), or { skip: why }. The Node tests compare the wasm core's stage
// distances with it: a compiler that miscompiles the core for wasm (it
// happened: docs/journal.md) shows there; the browser test compares the checks
// the page shows. name: the scan's file name (its extension picks the format).
export function nativeFit(webdir, bytes, name = 'scan.ply') {
  const bin = likenessBin(webdir);
  if (!bin) return { skip: 'no native likeness binary (set LK_LIKENESS_BIN)' };
  const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'likeness-fit-'));
  try {
    fs.writeFileSync(path.join(dir, name), bytes);
    execFileSync(bin, ['fit', '--scan', path.join(dir, name), '--out', path.join(dir, 'out')], { stdio: 'pipe' });
    const report = JSON.parse(fs.readFileSync(path.join(dir, 'out', 'report.json'), 'utf8'));
    return { stages: report.stages, quality: report.quality || null, faceToScan: report.face_to_scan || null };
  } catch (e) {
    return { skip: 'likeness fit failed: ' + String(e.message).split('\n')[0] };
  } finally {
    fs.rmSync(dir, { recursive: true, force: true });
  }
}
