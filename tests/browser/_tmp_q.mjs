import { closeChromium, launchChromium, serveDir } from './harness.mjs';
import path from 'node:path';
const [webdir, scan] = process.argv.slice(2);
const server = await serveDir(path.resolve(webdir), { isolation: true });
const context = await launchChromium('q', { width: 1280, height: 1000 });
try {
  const page = context.pages()[0] || await context.newPage();
  await page.goto(`http://127.0.0.1:${server.address().port}/index.html?autofit=0`);
  await page.waitForFunction(() => document.body.dataset.state === 'ready', null, { timeout: 180000 });
  await page.setInputFiles('#file-input', path.resolve(scan));
  await page.waitForFunction(() => ['done', 'error'].includes(document.body.dataset.state) && window.likeness.model, null, { timeout: 180000 });
  for (let i = 0; i < 2; i++) {
    await page.click('#btn-fit');
    await page.waitForFunction(() => document.body.dataset.state !== 'working', null, { timeout: 600000 });
    await page.waitForFunction(() => !window.likeness.fit || window.likeness.fit.quality, null, { timeout: 180000 });
    const f = await page.evaluate(() => ({ q: window.likeness.fit.quality, ms: window.likeness.fit.fitMs, st: window.likeness.fit.stages }));
    console.log(`fit ${Math.round(f.ms)} ms; stages ${f.st.map((s) => s.name + ' ' + s.meanPct.toFixed(4) + '% ' + Math.round(s.ms)).join(', ')}`);
    console.log('crossings', JSON.stringify(f.q.crossings), 'smooth', JSON.stringify(f.q.smoothCrossings));
  }
} finally { await closeChromium(context, server); }
