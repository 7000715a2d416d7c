// What one parallel_for costs in the threaded wasm core beyond its items:
// likeness_worker_mt's parallel_loops_ms(loops, items, parallel) runs `loops`
// loops of `items` small items on parallel_for or as plain loops; the
// difference per loop is starting and joining the pool's threads (in
// Emscripten 3.1.6 a message to a pool worker and a futex join). A seed-1
// fit runs about 30 such loops (fit_timing.mjs counts them). Then what a job
// on the alignment's parked helper thread costs (helper_jobs_ms).
// A measurement, not a test.
// Usage: node --no-experimental-fetch parallel_overhead_node.mjs WEBDIR
import { createRequire } from 'node:module';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';

const WEBDIR = path.resolve(process.argv[2] || '');
const require = createRequire(import.meta.url);
const core = await require(path.join(WEBDIR, 'likeness_worker_mt.js'))({ print: () => {}, printErr: () => {} });
if (!core.parallel_loops_ms) {
  console.log('this build has no parallel_loops_ms (built before the micro-benchmark)');
  process.exit(2);
}
const loadavg = fs.readFileSync('/proc/loadavg', 'utf8').split(' ').slice(0, 3).join(' ');
console.log(`threaded wasm core: ${core.parallel_workers()} threads per loop on ${os.cpus().length} cores ` +
            `(load average ${loadavg}); us per loop, median of 3`);
const median = (f) => { const t = [f(), f(), f()]; t.sort((a, b) => a - b); return t[1]; };
core.parallel_loops_ms(50, 2048, true);  // warm-up: the code tiers up
for (const items of [256, 2048, 16384]) {
  const loops = Math.max(50, Math.round(400000 / items));
  const us = (ms) => (1e3 * ms / loops).toFixed(1);
  const serial = median(() => core.parallel_loops_ms(loops, items, false));
  const parallel = median(() => core.parallel_loops_ms(loops, items, true));
  console.log(`${loops} loops of ${items} items: plain ${us(serial)}, parallel_for ${us(parallel)} (${(parallel >= serial ? "+" : "") + us(parallel - serial)} vs plain)`);
}
if (core.helper_jobs_ms) {
  // The alignment's parked helper (common/helper_thread.h): jobs in a row,
  // each split in two halves, against both halves on one thread.
  core.helper_jobs_ms(200, 512, true);
  for (const items of [64, 512, 2048]) {
    const jobs = 1000;
    const us = (ms) => (1e3 * ms / jobs).toFixed(1);
    const serial = median(() => core.helper_jobs_ms(jobs, items, false));
    const helper = median(() => core.helper_jobs_ms(jobs, items, true));
    console.log(`${jobs} jobs of ${items} items: one thread ${us(serial)}, parked helper ${us(helper)} us per job`);
  }
}
core.PThread.terminateAllThreads();
