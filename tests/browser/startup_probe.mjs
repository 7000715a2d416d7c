// By hand: where the page's start-up time goes. Loads WEBDIR's page RUNS
// times (a fresh page each, the same browser) and prints first paint, the
// page's own timings and when the big files were fetched.
//   node tests/browser/startup_probe.mjs WEBDIR [RUNS]
import { launchChromium, closeChromium, serveDir, waitForState } from './harness.mjs';
import path from 'node:path';

const webdir = path.resolve(process.argv[2] || 'build/web');
const runs = Number(process.argv[3]) || 3;
const server = await serveDir(webdir);
const origin = 'http://127.0.0.1:' + server.address().port;
const context = await launchChromium('probe', { width: 1280, height: 800 });
for (let i = 0; i < runs; i++) {
  const page = await context.newPage();
  await page.goto(origin + '/index.html');
  await waitForState(page, ['ready', 'error'], 120000);
  const r = await page.evaluate(() => {
    const paint = (performance.getEntriesByType('paint').find((e) => e.name === 'first-contentful-paint') || {}).startTime;
    const res = performance.getEntriesByType('resource')
      .filter((e) => /likeness_|main\.js|face_mesh|worker/.test(e.name))
      .map((e) => `${e.name.split('/').pop()} ${Math.round(e.startTime)}-${Math.round(e.responseEnd)}`);
    const nav = performance.getEntriesByType('navigation')[0];
    return { paint: Math.round(paint), dcl: Math.round(nav.domContentLoadedEventEnd), timings: window.likeness.timings,
             loadMs: Math.round(window.likeness.loadMs), startedAt: Math.round(window.likeness.startedAt), res,
             viewerSteps: window.likeness.viewer ? window.likeness.viewer.startup_times().map(([k, ms]) => k + ' ' + Math.round(ms)) : [] };
  });
  console.log(JSON.stringify(r));
  await page.close();
}
await closeChromium(context, server);
