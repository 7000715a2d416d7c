// Fits a scan with the page's wasm core (likeness_worker.wasm, single
// thread) under node, without a browser: the same embind calls web/worker.js
// makes. Prints the stages, the untangling's counts and the checks the page
// shows, so a difference between the page and `likeness fit` can be
// reproduced in seconds (James's 28 crossing pairs in Chromium were found
// this way: docs/journal.md "Hinges"). --control-out F writes the fitted control
// mesh (OBJ, scan frame) as the page exports it.
// Usage: node --no-experimental-fetch fit_node.mjs WEBDIR SCAN [--control-out F.obj]
import { createRequire } from 'node:module';
import fs from 'node:fs';
import path from 'node:path';

// (Not harness.mjs: it loads playwright, which needs node's fetch, and the
// emscripten module needs it off to read the .wasm from disk.)
const args = process.argv.slice(2);
const at = args.indexOf('--control-out');
const controlOut = at >= 0 ? args.splice(at, 2)[1] : '';
const [webdir, scan] = args;
if (!webdir || !scan) {
  console.error('usage: node --no-experimental-fetch fit_node.mjs WEBDIR SCAN [--control-out F.obj]');
  process.exit(2);
}
for (const f of [path.join(webdir, 'likeness_worker.js'), scan]) {
  if (!fs.existsSync(f)) {
    console.error(`${f}: no such file`);
    process.exit(2);
  }
}
const require = createRequire(import.meta.url);
const factory = require(path.join(path.resolve(webdir), 'likeness_worker.js'));
const core = await factory({ print: (s) => console.log(s), printErr: (s) => console.error(s) });
const bytes = fs.readFileSync(scan);
const ptr = core._malloc(Math.max(1, bytes.length));
core.HEAPU8.set(bytes, ptr);
const r = core.fit_head_job(path.basename(scan), ptr, bytes.length, {}, undefined);
core._free(ptr);
if (!r.ok) {
  console.log(`fit failed: ${r.message}`);
  process.exit(1);
}
console.log(`${r.points} points (${r.fittedPoints} fitted); fit ${Math.round(r.fitMs)} ms`);
for (const s of r.stages) {
  console.log(`  ${s.name.padEnd(18)} ${s.meanPct.toFixed(4).padStart(8)} % ${s.maxPct.toFixed(3).padStart(7)} % ` +
              `${Math.round(s.ms).toString().padStart(6)} ms`);
}
for (const n of r.notes) console.log(`  note: ${n}`);
const u = r.untangle;
console.log(`untangling: smooth-surface pairs ${u.pairsBefore} -> eroded ${u.pairsEroded} -> ${u.pairsAfter} ` +
            `(${u.restoreSteps} restore steps)`);
const q = core.fit_quality_job();
if (!q.ok) {
  console.log(`checks failed: ${q.message}`);
  process.exit(1);
}
const c = q.crossings;
console.log(`checks: level ${q.level}, ${q.flipped} turned over, ${q.degenerate} degenerate, pairs ${c.total} ` +
            `(lips ${c.lips}, ears ${c.ears}, eye sockets ${c.eyeSockets}, rest ${c.rest}), smooth ${q.smoothCrossings.total}, ` +
            `control ${q.controlCrossings}`);
if (controlOut) {
  const e = core.export_head(0, 'obj');
  if (!e.ok) {
    console.log(`export failed: ${e.message}`);
    process.exit(1);
  }
  fs.writeFileSync(controlOut, Buffer.from(e.bytes));
  console.log(`wrote ${controlOut}`);
}
