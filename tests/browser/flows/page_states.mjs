// No error strands the page (issue 39): a text file renamed .ply, then
// Dismiss or "Try the sample", used to leave the page "working" for good
// (every button off, Cancel dead, the head no longer exportable). Here,
// after each failure (a bad scan, a bad photo, a failed texture, a
// cancelled fit) the page is usable again, the head shown before is still
// there and exports, and Cancel ends whatever runs. The sample is served by
// the test (page.route), so it does not depend on scripts/demo.
import fs from 'node:fs';
import { bannerText, check, JOB_TIMEOUT_MS, makePng, runAlone, settled, state, torusPly } from '../harness.mjs';
import { fittedHead } from './fit.mjs';

const NOT_A_SCAN = Buffer.from('Shopping list\neggs\nmilk\nThis is not a scan, only named like one.\n');

// What a user can do now: the inputs, Cancel, and the head's exports.
function usable(page) {
  return page.evaluate(() => {
    const on = (id) => !document.getElementById(id).disabled;
    return { state: document.body.dataset.state, files: on('file-input'), sample: on('btn-sample'),
             cancelShown: !document.getElementById('btn-cancel').hidden, exportPly: on('btn-export-ply'),
             save: on('btn-save-project'), fit: !!window.likeness.fit };
  });
}

// The head exports: a PLY download with the finest level's vertex count.
async function exportsHead(page) {
  const levels = await page.evaluate(() => window.likeness.fit && window.likeness.fit.meshes.levels.map((m) => m.vertexCount));
  if (!levels) return { ok: false, why: 'no head' };
  await page.selectOption('#level', String(levels.length));
  const downloadP = page.waitForEvent('download', { timeout: JOB_TIMEOUT_MS });
  await page.click('#btn-export-ply');
  const bytes = fs.readFileSync(await (await downloadP).path());
  const ok = new RegExp('element vertex ' + levels[levels.length - 1] + '\\b').test(bytes.toString('latin1', 0, 400));
  return { ok, bytes, why: `${bytes.length} bytes, level ${levels.length} of ${levels[levels.length - 1]} vertices` };
}

const idleWithHead = (u) => ['done', 'ready'].includes(u.state) && u.files && u.sample && !u.cancelShown && u.exportPly && u.save && u.fit;

async function run(s) {
  // 1. The report's path on a fresh page: a bad scan, then "Try the sample".
  const fresh = await s.newPage('?autofit=0');
  await fresh.route('**/sample/scan.ply', (r) => r.fulfill({ status: 200, contentType: 'application/octet-stream', body: torusPly(3000) }));
  await fresh.route('**/sample/texture.json', (r) => r.fulfill({ status: 200, contentType: 'application/json', body: '{"photos": []}' }));
  await fresh.setInputFiles('#file-input', { name: 'notes.ply', mimeType: 'application/octet-stream', buffer: NOT_A_SCAN });
  await settled(fresh);
  const bad = await bannerText(fresh);
  check('a text file renamed .ply is refused with a message naming it', (await state(fresh)) === 'error' && /notes\.ply/.test(bad), bad);
  await fresh.click('#btn-sample');
  await settled(fresh);
  const afterSample = await fresh.evaluate(() => ({ state: document.body.dataset.state, model: window.likeness.model && window.likeness.model.name,
                                                    files: !document.getElementById('file-input').disabled }));
  check('... then "Try the sample" loads the sample and the page is usable (not stuck in "working")',
        afterSample.state === 'done' && afterSample.model === 'sample_scan.ply' && afterSample.files, JSON.stringify(afterSample));
  // A status message that wraps to a second line leaves the view's size as it was.
  const wrap = await fresh.evaluate(async () => {
    const status = document.getElementById('status'), canvas = document.getElementById('canvas'), was = status.textContent;
    const frame = () => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r)));
    const lines = () => Math.round(status.getBoundingClientRect().height / parseFloat(getComputedStyle(status).lineHeight) * 10) / 10;
    const one = { view: canvas.getBoundingClientRect().height, text: lines() };
    let long = was;
    // Grow the message until it takes two lines (its own words, repeated).
    // (Its natural height: the two lines' box taken off while measuring.)
    const natural = () => { status.style.minHeight = '0'; status.style.height = 'auto';
                            const n = lines(); status.style.minHeight = status.style.height = ''; return n; };
    while (natural() < 2 && long.length < 2000) { long += ' ' + was; status.textContent = long; }
    const twoLines = natural();
    await frame();
    const two = { view: canvas.getBoundingClientRect().height, text: twoLines };
    // Twice as long again: it scrolls within the two lines, all of it there.
    status.textContent = long + ' ' + long;
    await frame();
    const four = { view: canvas.getBoundingClientRect().height, text: lines(), natural: natural(),
                   scrolls: status.scrollHeight > status.clientHeight + 1, focusable: status.tabIndex === 0 };
    status.textContent = was;
    await frame();
    return { one, two, four };
  });
  check('a status message of two lines leaves the view its size', wrap.two.text === 2 && Math.abs(wrap.two.view - wrap.one.view) < 0.5,
        JSON.stringify(wrap));
  check('... and one of four lines too: it scrolls within two lines, reachable by the keyboard',
        Math.abs(wrap.four.view - wrap.one.view) < 0.5 && wrap.four.natural >= 3 && wrap.four.scrolls && wrap.four.focusable,
        JSON.stringify(wrap.four));
  await fresh.setInputFiles('#file-input', { name: 'notes.ply', mimeType: 'application/octet-stream', buffer: NOT_A_SCAN });
  await settled(fresh);
  await fresh.click('#error-dismiss');
  const afterDismiss = await fresh.evaluate(() => ({ state: document.body.dataset.state, sample: !document.getElementById('btn-sample').disabled,
                                                     model: window.likeness.model && window.likeness.model.name }));
  check('... and a bad scan then Dismiss goes back to what was shown, every input on',
        afterDismiss.state === 'done' && afterDismiss.sample && afterDismiss.model === 'sample_scan.ply', JSON.stringify(afterDismiss));
  // Cancel while the sample is still downloading (no worker job runs yet:
  // the old Cancel had nothing to stop): the page is back at once, and the
  // late download is dropped.
  let release;
  const held = new Promise((r) => { release = r; });
  await fresh.unroute('**/sample/scan.ply');
  await fresh.route('**/sample/scan.ply', async (r) => {
    await held;
    await r.fulfill({ status: 200, contentType: 'application/octet-stream', body: torusPly(5000) });
  });
  await fresh.click('#btn-sample');
  await fresh.waitForFunction(() => document.body.dataset.state === 'working', null, { timeout: 10000 });
  await fresh.click('#btn-cancel');
  const sCancelled = await state(fresh);
  release();
  await fresh.waitForTimeout(1500);
  const late = await fresh.evaluate(() => ({ state: document.body.dataset.state, model: window.likeness.model && window.likeness.model.name,
                                             vertices: window.likeness.model && window.likeness.model.vertexCount }));
  check('Cancel while the sample downloads ends that job at once; the late download changes nothing',
        sCancelled === 'done' && late.state === 'done' && late.vertices === 3000, `state ${sCancelled} at Cancel; then ${JSON.stringify(late)}`);
  await fresh.close();

  // 2. With a fitted head: each failure leaves it shown and exportable.
  const { page, fit, skip } = await fittedHead(s);
  if (skip || !fit) return;
  await settled(page);
  await page.uncheck('#auto-fit');
  for (const [what, files] of [
    ['a bad scan', [{ name: 'notes.ply', mimeType: 'application/octet-stream', buffer: NOT_A_SCAN }]],
    ['a bad photo', [{ name: 'broken.png', mimeType: 'image/png', buffer: Buffer.from('PNG? no, plain text') }]],
  ]) {
    await page.setInputFiles('#file-input', files);
    await settled(page);
    const msg = await bannerText(page);
    await page.click('#error-dismiss');
    const u = await usable(page);
    const ex = await exportsHead(page);
    check(`after ${what} and Dismiss: the page is usable and the head is still there and exports`,
          msg !== '' && idleWithHead(u) && ex.ok, `"${msg}"; ${JSON.stringify(u)}; ${ex.why}`);
  }

  // A failed texture: a photo whose six points are one point (no camera fits them).
  for (let k = 0; k < 12 && await page.locator('#photo-list .photo-remove').count(); k++) await page.locator('#photo-list .photo-remove').first().click();
  await page.setInputFiles('#file-input', [{ name: 'same.png', mimeType: 'image/png', buffer: makePng(64, 48) },
    { name: 'same.txt', mimeType: 'text/plain', buffer: Buffer.from('10 10 0 0 0\n'.repeat(6)) }]);
  await settled(page);
  await page.click('#btn-texture');
  await settled(page);
  const texMsg = await bannerText(page);
  const texState = await state(page);
  await page.click('#error-dismiss').catch(() => {});
  const uTex = await usable(page);
  const exTex = await exportsHead(page);
  check('after a failed texture: the page is usable and the head is still there and exports',
        texState === 'error' && /Texture/.test(texMsg) && idleWithHead(uTex) && exTex.ok, `"${texMsg}"; ${JSON.stringify(uTex)}; ${exTex.why}`);
  for (let k = 0; k < 12 && await page.locator('#photo-list .photo-remove').count(); k++) await page.locator('#photo-list .photo-remove').first().click();

  // Cancel ends a job at once, whatever it is doing.
  await page.click('#btn-fit');
  await page.waitForFunction(() => document.querySelector('#stages li.active'), null, { timeout: JOB_TIMEOUT_MS });
  const t0 = Date.now();
  await page.click('#btn-cancel');
  const sCancel = await state(page);
  const msCancel = Date.now() - t0;
  check('Cancel during a fit ends the job at once (the state leaves "working")', sCancel !== 'working' && (await bannerText(page)) === '',
        `state ${sCancel} ${msCancel} ms after the click`);
  // The stopped worker took the head with it; keep.js puts the kept copy
  // into the new one, so the head shown still exports, the same bytes.
  const uCancel = await usable(page);
  const exCancel = await exportsHead(page);
  check('... and the head shown before the cancelled fit is still there and exports the same file',
        idleWithHead(uCancel) && exCancel.ok && exCancel.bytes.equals(exTex.bytes),
        `${JSON.stringify(uCancel)}; ${exCancel.why}; same bytes as before the fit: ${exCancel.bytes && exCancel.bytes.equals(exTex.bytes)}`);
}

export const flow = { name: 'page-states', title: 'No failure strands the page; the head stays; Cancel ends any job', run };
runAlone(import.meta.url, flow);
