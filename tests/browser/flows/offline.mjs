// Offline after the first visit, and installable (issue 39). In a browser of
// its own that allows service workers, on a server of its own: the first
// visit registers sw.js, which keeps every file of offline.json and the
// header says "Works offline"; Chromium finds the page installable (no
// installability errors). Then the server is shut down and the browser put
// offline: a reload starts the page from its copy, with the same core, and
// a synthetic head scan (`likeness synth-scan`, 20k points; skipped with a
// note without the native CLI) is loaded and fitted with the network off;
// then a rendered head photo is dropped and the face detector (its model in
// the copy) finds its 468 face points, still offline.
import fs from 'node:fs';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { bannerText, check, closeChromium, likenessBin, launchChromium, note, READY_TIMEOUT_MS, runAlone, setFile, settled, shot,
         state, waitForState } from '../harness.mjs';
import { syntheticScan } from '../synth_scan.mjs';
import { renderedHeadPhoto } from '../landmark_geometry.mjs';

const ROOT = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '../../..');

async function run(s) {
  if (!fs.existsSync(path.join(s.webdir, 'offline.json'))) {
    check('offline.json is built beside the page (scripts/build runs scripts/offline_list.py)', false, s.webdir);
    return;
  }
  const { server, origin } = await s.serve();
  const context = s.watchRequests(await launchChromium('offline', { width: 1280, height: 800 }, { serviceWorkers: 'allow' }));
  try {
    const page = s.watch(await context.newPage());
    await page.goto(origin + '/index.html?autofit=0');
    const first = await waitForState(page, ['ready', 'error'], READY_TIMEOUT_MS);
    const t0 = Date.now();
    await page.waitForFunction(() => window.likeness.offline && (window.likeness.offline.ready || window.likeness.offline.failed),
                               null, { timeout: 120000 }).catch(() => {});
    const copy = await page.evaluate(() => Object.assign({}, window.likeness.offline,
      { badge: document.getElementById('offline-badge').textContent }));
    const listed = JSON.parse(fs.readFileSync(path.join(s.webdir, 'offline.json'), 'utf8')).files.length;
    check('the first visit keeps a copy of every listed file and says "Works offline"',
          first === 'ready' && copy.ready && copy.files === listed && copy.badge === 'Works offline',
          `${JSON.stringify(copy)} after ${Date.now() - t0} ms; ${listed} files listed`);

    const cdp = await context.newCDPSession(page);
    const inst = await cdp.send('Page.getInstallabilityErrors').catch((e) => ({ error: e.message }));
    check('Chromium finds the page installable as an app', Array.isArray(inst.installabilityErrors) &&
          inst.installabilityErrors.length === 0, JSON.stringify(inst));
    const variant = await page.evaluate(() => window.likeness.workerThreads && window.likeness.workerThreads.variant);

    // The network off: no server, and the browser offline.
    server.closeAll();
    server.closeAllConnections();
    await context.setOffline(true);
    const asked = server.requests.length;
    await page.reload();
    const offline = await waitForState(page, ['ready', 'error'], READY_TIMEOUT_MS).catch((e) => 'not ready: ' + e.message);
    await page.waitForFunction(() => window.likeness.offline && (window.likeness.offline.ready || window.likeness.offline.failed),
                               null, { timeout: 60000 }).catch(() => {});
    const after = await page.evaluate(() => ({ variant: window.likeness.workerThreads && window.likeness.workerThreads.variant,
                                               status: document.getElementById('status').textContent,
                                               badge: document.getElementById('offline-badge').textContent }));
    check('with the network off a reload starts the page from its copy, with the same core',
          offline === 'ready' && after.variant === variant && server.requests.length === asked &&
          /running from this browser's copy/.test(after.badge),
          `state ${offline}; core ${after.variant} (online: ${variant}); badge "${after.badge}"; "${after.status.trim()}"; ` +
          `${server.requests.length - asked} requests reached the server`);
    await shot(page, 'web_offline.png');

    const synth = syntheticScan(s.webdir, 3, 20000);
    if (synth.skip) {
      note('the offline fit is not exercised: ' + synth.skip);
      return;
    }
    const sLoad = await setFile(page, 'offline_head.ply', synth.bytes);
    const tFit = Date.now();
    await page.click('#btn-fit');
    await settled(page);
    const sFit = await state(page);
    const fit = await page.evaluate(() => window.likeness.fit && window.likeness.fit.meshes.levels.length);
    check('offline, a scan loads and "Fit head" reaches "done"', sLoad === 'done' && sFit === 'done' && fit > 0,
          `load ${sLoad}, fit ${sFit} after ${Date.now() - tFit} ms, ${fit} levels; ${await bannerText(page)}`);

    // The face detector's model comes from the copy too.
    const photo = renderedHeadPhoto(likenessBin(s.webdir), ROOT);
    if (!photo) return;  // (no CLI: the scan above was skipped already)
    await page.setInputFiles('#file-input', [{ name: 'offline_face.png', mimeType: 'image/png', buffer: photo }]);
    await settled(page);
    const tDetect = Date.now();
    await page.waitForFunction(() => window.likeness.photos.length > 0 && window.likeness.photos.every((p) =>
      p.detect && !['waiting', 'running'].includes(p.detect.state)), null, { timeout: 180000 }).catch(() => {});
    const detect = await page.evaluate(() => (window.likeness.photos.find((p) => p.name === 'offline_face.png') || {}).detect || null);
    check('offline, a dropped photo\'s face points are found by the detector from the copy',
          !!detect && detect.state === 'found' && detect.faces === 1 && (detect.points || []).length === 468 && server.requests.length === asked,
          `${JSON.stringify(detect && { state: detect.state, faces: detect.faces, points: (detect.points || []).length, message: detect.message })} ` +
          `after ${Date.now() - tDetect} ms; ${server.requests.length - asked} requests reached the server`);
  } finally {
    await context.setOffline(false).catch(() => {});
    await closeChromium(context);
  }
}

export const flow = { name: 'offline', title: 'offline after the first visit, and installable', run };
runAlone(import.meta.url, flow);
