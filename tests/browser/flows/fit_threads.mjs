// The fit on one thread gives the threaded fit bit for bit: the same folder
// served without the isolation headers (the single-threaded core), and
// served with them but with the threaded core's pool workers unable to start
// (their script refused, or never sent): the page falls back to one thread,
// says so, and fits the same.
import { bannerText, check, fitFingerprint, READY_TIMEOUT_MS, runAlone, setFile, settled, state,
         waitForState } from '../harness.mjs';
import { fittedHead } from './fit.mjs';

async function run(s) {
  const { page, synth, fit } = await fittedHead(s);
  if (!fit) return;
  const isolated = await page.evaluate(() => ({ worker: window.likeness.workerThreads }));
  // The same fit on one thread (a page served WITHOUT the isolation
  // headers, as many hosts do: the fallback core) must give the same
  // numbers and the same meshes, bit for bit (parallel_for's results
  // do not depend on the thread count).
  const threadedFit = await fitFingerprint(page);
  const { server: plain, origin: plainOrigin } = await s.serve({ isolation: false });
  const pagePlain = await s.newPage('?autofit=0', { origin: plainOrigin });
  try {
    const sPlain = await state(pagePlain);
    const plainWorker = await pagePlain.evaluate(() => ({ coi: window.crossOriginIsolated, worker: window.likeness.workerThreads }));
    check('served without COOP/COEP: the page starts with the single-threaded core', sPlain === 'ready' &&
          plainWorker.coi === false && plainWorker.worker && plainWorker.worker.variant === 'single' &&
          plainWorker.worker.threads === 1, `state ${sPlain}, ${JSON.stringify(plainWorker)}`);
    const sPlainLoad = await setFile(pagePlain, 'synthetic_head.ply', synth.bytes);
    await pagePlain.click('#btn-fit');
    await settled(pagePlain);
    const plainFit = sPlainLoad === 'done' && (await state(pagePlain)) === 'done' ? await fitFingerprint(pagePlain) : null;
    check('... its fit reaches "done" with the same stage numbers and meshes as the threaded fit',
          !!plainFit && plainFit.report === threadedFit.report && plainFit.meshes === threadedFit.meshes,
          plainFit ? `${isolated.worker.threads} threads ${Math.round(threadedFit.fitMs)} ms, 1 thread ${Math.round(plainFit.fitMs)} ms; ` +
                     `report ${plainFit.report === threadedFit.report ? 'equal' : 'DIFFERS: ' + plainFit.report + ' vs ' + threadedFit.report}; ` +
                     `meshes ${plainFit.meshes === threadedFit.meshes ? 'equal (' + threadedFit.meshes + ')' : 'DIFFER'}`
                   : 'state ' + (await state(pagePlain)) + ': ' + await bannerText(pagePlain));
  } finally {
    await pagePlain.close();
    plain.close();
  }
  // A cross-origin isolated page whose threaded core cannot start its
  // pthread pool (the pool workers' script is refused with a 404, or
  // never arrives, as in a browser that blocks or stalls nested
  // workers): the page must not hang but fall back to the single-
  // threaded core, say so, and fit as before. (Emscripten 3.1.6 alone
  // waits for the pool forever: without worker.js's watch the page
  // stays "loading".) thread_start_ms=3000: the stalled pool is given
  // up after 3 s instead of 10.
  for (const [how, what] of [['404', 'its pool workers\' script fails to load'], ['hang', 'its pool workers never start']]) {
    const { server: broken, origin: brokenOrigin } = await s.serve({ broken: { '/likeness_worker_mt.worker.js': how } });
    const pageBroken = await (await s.context()).newPage();
    const uncaught = [];
    pageBroken.on('pageerror', (e) => uncaught.push(e.message));  // (the refused script's console errors are expected)
    try {
      const tStart = Date.now();
      await pageBroken.goto(brokenOrigin + '/index.html?autofit=0&thread_start_ms=3000');
      const sBroken = await waitForState(pageBroken, ['ready', 'error'], READY_TIMEOUT_MS);
      const info = await pageBroken.evaluate(() => ({ coi: window.crossOriginIsolated, worker: window.likeness.workerThreads,
                                                      status: document.getElementById('status').textContent }));
      check(`threaded core cannot start (${what}): the page falls back to one thread and says so`,
            sBroken === 'ready' && info.coi === true && info.worker && info.worker.variant === 'single' &&
            info.worker.threads === 1 && !!info.worker.fallback && /could not start/.test(info.status) &&
            uncaught.length === 0,
            `state ${sBroken} after ${Date.now() - tStart} ms; worker ${JSON.stringify(info.worker)}; "${info.status.trim()}"` +
            (uncaught.length ? '; uncaught: ' + uncaught.join(' | ') : ''));
      if (how === '404' && sBroken === 'ready') {
        const sLoad = await setFile(pageBroken, 'synthetic_head.ply', synth.bytes);
        await pageBroken.click('#btn-fit');
        await settled(pageBroken);
        const brokenFit = sLoad === 'done' && (await state(pageBroken)) === 'done' ? await fitFingerprint(pageBroken) : null;
        const total = await pageBroken.textContent('#fit-total');
        check('... its fit reaches "done", equals the threaded fit and its summary names the fallback',
              !!brokenFit && brokenFit.report === threadedFit.report && brokenFit.meshes === threadedFit.meshes &&
              /1 thread \(threads could not start here\)/.test(total),
              brokenFit ? `"${total.trim()}"; report ${brokenFit.report === threadedFit.report ? 'equal' : 'DIFFERS'}; ` +
                          `meshes ${brokenFit.meshes === threadedFit.meshes ? 'equal' : 'DIFFER'}`
                        : 'state ' + (await state(pageBroken)) + ': ' + await bannerText(pageBroken));
      }
    } finally {
      await pageBroken.close();
      broken.closeAll();
    }
  }
}

export const flow = { name: 'fit-threads', title: 'one thread fits the same: no isolation headers, a pool that cannot start', run };
runAlone(import.meta.url, flow);
