// Screenshots of the web app for the docs (not a test): serves WEBDIR on
// 127.0.0.1, opens the page in Debian's Chromium and writes
//   OUTDIR/web_start.png          the page once ready (the generic head)
//   OUTDIR/web_wireframe.png      the same with its edges (--wireframe)
//   OUTDIR/web_<stem>.png         after loading each FILE given
//   OUTDIR/web_landmarks_<stem>.png  with --landmarks PHOTO: the photo open
//                                 with the face points the page found on it
// Usage: node screenshots.mjs WEBDIR OUTDIR [FILE ...] [--point-size N] [--wireframe] [--query "max_mb=N&..."]
//        [--landmarks PHOTO]
import { closeChromium, launchChromium, serveDir, takeFlag, takeOption } from './harness.mjs';
import fs from 'node:fs';
import path from 'node:path';

const args = process.argv.slice(2);
const wireframe = takeFlag(args, '--wireframe');
const queryValue = takeOption(args, '--query', null);
const query = queryValue === null ? '' : '?' + queryValue;
const pointSize = takeOption(args, '--point-size', null);
const landmarksPhoto = takeOption(args, '--landmarks', null);
const [webdir, outdir, ...files] = args;
if (!webdir || !outdir) {
  console.error('usage: node screenshots.mjs WEBDIR OUTDIR [FILE ...] [--point-size N] [--wireframe] [--query "max_mb=N&..."]');
  process.exit(2);
}
const root = path.resolve(webdir);
const server = await serveDir(root);
const context = await launchChromium('shots', { width: 1280, height: 800 });
try {
  const page = context.pages()[0] || await context.newPage();
  await page.goto(`http://127.0.0.1:${server.address().port}/index.html${query}`);
  await page.waitForFunction(() => ['ready', 'error'].includes(document.body.dataset.state), null, { timeout: 180000 });
  fs.mkdirSync(outdir, { recursive: true });
  const settle = () => page.evaluate(() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r))));
  await settle();
  await page.screenshot({ path: path.join(outdir, 'web_start.png') });
  console.log('wrote', path.join(outdir, 'web_start.png'));
  if (wireframe) {
    await page.check('#wireframe');
    await page.evaluate(() => document.activeElement.blur());
    await settle();
    await page.screenshot({ path: path.join(outdir, 'web_wireframe.png') });
    console.log('wrote', path.join(outdir, 'web_wireframe.png'));
    await page.uncheck('#wireframe');
    await page.evaluate(() => document.activeElement.blur());
  }
  if (pointSize) { await page.fill('#point-size', String(pointSize)); await page.evaluate(() => document.activeElement.blur()); }
  for (const f of files) {
    await page.setInputFiles('#file-input', f);
    await page.waitForFunction(() => document.body.dataset.state !== 'working', null, { timeout: 120000 });
    await settle();
    const out = path.join(outdir, 'web_' + path.basename(f).replace(/\.[^.]*$/, '') + '.png');
    await page.screenshot({ path: out });
    console.log('wrote', out, '(' + (await page.textContent('#status')).trim() + ')' + (await page.evaluate(() => window.likeness.lastError ? ' error: ' + window.likeness.lastError : '')));
  }
  if (landmarksPhoto) {
    await page.setInputFiles('#file-input', landmarksPhoto);
    await page.waitForFunction(() => window.likeness.photos.length && window.likeness.photos.every((p) =>
      p.detect && !['waiting', 'running'].includes(p.detect.state)), null, { timeout: 180000 });
    const name = path.basename(landmarksPhoto);
    await page.locator('#photo-list li', { hasText: name }).click();
    await settle();
    const out = path.join(outdir, 'web_landmarks_' + name.replace(/\.[^.]*$/, '') + '.png');
    await page.screenshot({ path: out });
    console.log('wrote', out, '(' + (await page.textContent('#clicker-prompt')).trim() + ')');
  }
} finally {
  await closeChromium(context, server);
}
