// Start-up failures: the worker's core cannot start (its wasm a 404, never
// arriving, corrupt; its script never arriving), each on its own server.
// Every one must end in a clear message (or the single-threaded core, where
// that helps) within seconds, never a page stuck in "loading"; a core that
// cannot restart later keeps the user's files. ?core_stall_ms /
// ?worker_start_ms shorten the watches. And a browser without WebGL: a
// clear message, every control off.
import { bannerText, check, closeChromium, cubeObj, launchChromium, READY_TIMEOUT_MS, runAlone, setFile, torusPly,
         waitForState } from '../harness.mjs';

async function run(s) {
  const context = await s.context();
  const cases = [
    { what: 'the threaded core\'s wasm is a 404', isolation: true, broken: { '/likeness_worker_mt.wasm': '404' },
      want: 'ready', why: /likeness_worker_mt\.wasm: the server answered HTTP 404/ },
    { what: 'the threaded core\'s wasm never arrives', isolation: true, broken: { '/likeness_worker_mt.wasm': 'hang' },
      query: '&core_stall_ms=3000', want: 'ready', why: /likeness_worker_mt\.wasm: no answer from the server for 3 s/ },
    { what: 'the core\'s wasm is corrupt (no threads)', isolation: false, broken: { '/likeness_worker.wasm': 'corrupt' },
      want: 'error', why: /likeness_worker\.wasm is not a valid WebAssembly module/ },
    { what: 'both cores\' wasm are 404s', isolation: true,
      broken: { '/likeness_worker_mt.wasm': '404', '/likeness_worker.wasm': '404' },
      want: 'error', why: /likeness_worker\.wasm: the server answered HTTP 404.*multi-threaded core did not start either.*likeness_worker_mt\.wasm: the server answered HTTP 404/ },
    { what: 'the core\'s wasm never arrives (no threads)', isolation: false, broken: { '/likeness_worker.wasm': 'hang' },
      query: '&core_stall_ms=3000', want: 'error', why: /likeness_worker\.wasm: no answer from the server for 3 s/ },
    { what: 'the core\'s script never arrives', isolation: false, broken: { '/likeness_worker.js': 'hang' },
      query: '&worker_start_ms=4000', want: 'error', why: /did not answer for 4 s while starting \(script likeness_worker\.js\)/ },
    { what: 'the worker\'s start-up script is a 404', isolation: false, broken: { '/worker_start.js': '404' },
      want: 'error', why: /worker_start\.js did not load/ },
    { what: 'a module of the page is a 404', isolation: true, broken: { '/js/fit.js': '404' },
      want: 'error', why: /some of its scripts \(js\/\) did not load/ },
  ];
  for (const c of cases) {
    const { server, origin } = await s.serve({ isolation: c.isolation, broken: c.broken });
    const page = await context.newPage();
    const uncaught = [];
    page.on('pageerror', (e) => uncaught.push(e.message));
    try {
      const t0 = Date.now();
      await page.goto(origin + '/index.html?autofit=0' + (c.query || ''));
      const sStart = await waitForState(page, ['ready', 'error'], READY_TIMEOUT_MS);
      const info = await page.evaluate(() => ({ worker: window.likeness && window.likeness.workerThreads, status: document.getElementById('status').textContent,
                                                banner: document.getElementById('error-banner').hidden ? '' : document.getElementById('error-text').textContent }));
      const text = c.want === 'ready' ? (info.worker && info.worker.fallback) || '' : info.banner;
      check(`start-up: ${c.what}: ${c.want === 'ready' ? 'one thread, and the page says why' : 'a clear message, no hang'}`,
            sStart === c.want && c.why.test(text) && uncaught.length === 0 &&
            (c.want === 'ready' ? info.worker.variant === 'single' && /could not start/.test(info.status) : /could not start/i.test(text)),
            `state ${sStart} after ${Date.now() - t0} ms; "${text}"` + (uncaught.length ? '; uncaught: ' + uncaught.join(' | ') : ''));
    } finally {
      await page.close();
      server.closeAll();
    }
  }

  // A worker restarted later (Cancel, a crash) whose core cannot start: the
  // loaded scan stays, the page says so, and the next action starts a core
  // again once the server is back.
  const broken = {};
  const { server, origin } = await s.serve({ isolation: false, broken });
  const page = await context.newPage();
  try {
    await page.goto(origin + '/index.html?autofit=0&core_stall_ms=3000');
    await waitForState(page, ['ready', 'error'], READY_TIMEOUT_MS);
    const sLoad = await setFile(page, 'torus.ply', torusPly(5000));
    broken['/likeness_worker.wasm'] = 'hang';
    await page.evaluate(() => {
      window.likeness.runJob({ type: 'parse', name: 'x.ply', buffer: new ArrayBuffer(8) }, []).catch(() => {});
      window.likeness.cancel();
    });
    await page.waitForFunction(() => !document.getElementById('error-banner').hidden, null, { timeout: 60000 });
    const after = await page.evaluate(() => ({ banner: document.getElementById('error-text').textContent,
                                               model: window.likeness.model && window.likeness.model.name,
                                               scan: !!window.likeness.scan, state: document.body.dataset.state }));
    check('start-up: a restarted core that cannot start says so and keeps the loaded scan',
          sLoad === 'done' && /could not be started again: likeness_worker\.wasm: no answer/.test(after.banner) &&
          /scan and photos are kept/.test(after.banner) && after.model === 'torus.ply' && after.scan,
          JSON.stringify(after));
    delete broken['/likeness_worker.wasm'];
    await page.click('#error-dismiss');
    const sCube = await setFile(page, 'cube.obj', cubeObj());
    const status = await page.textContent('#status');
    check('... and once the server is back, the next file starts a core and loads', sCube === 'done' &&
          /8 vertices, 12 triangles/.test(status), `state ${sCube}; "${status.trim()}"`);
  } finally {
    await page.close();
    server.closeAll();
  }

  // Without WebGL: a clear message in the page and every control off.
  let ctx = null;
  try {
    ctx = await launchChromium('nowebgl', { width: 1280, height: 800 }, { args: ['--disable-webgl'] });
    const page = ctx.pages()[0] || await ctx.newPage();
    await page.goto(s.origin + '/index.html');
    const sNoGl = await waitForState(page, ['ready', 'error'], READY_TIMEOUT_MS);
    const msg = await bannerText(page);
    const enabled = await page.evaluate(() => ['file-input', 'btn-sample', 'btn-reset', 'btn-generic', 'point-size']
      .filter((id) => !document.getElementById(id).disabled));
    check('without WebGL: "error" with a visible message, controls off', sNoGl === 'error' && /WebGL 2/.test(msg) &&
          enabled.length === 0, `"${msg.slice(0, 90)}…"; enabled: [${enabled}]`);
  } catch (e) {
    check('without WebGL: the page reports it', false, e && e.message ? e.message.split('\n')[0] : String(e));
  } finally {
    if (ctx) await closeChromium(ctx);
  }
}

export const flow = { name: 'startup-failures', title: 'the core cannot start; a browser without WebGL', run };
runAlone(import.meta.url, flow);
