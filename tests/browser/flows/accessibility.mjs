// Accessibility (issue 39): axe-core (npm, injected from node_modules: no
// request) finds no serious or critical violation in each state a person
// meets: the page ready; an error (a broken scan); a scan loaded; working
// (a fit running); done (the fitted head, its checks); a photo open to mark
// landmarks (the clicker); an eye photo used, and one refused; a smile photo
// used; the textured head; the restore offer after a reload, and the
// restored (textured) head with the kept-heads list; the
// Expressions panel open. Ready and done (closed and open Expressions):
// Tab reaches every visible, enabled control, each with a visible focus. A page of its
// own (?autofit=0); the fit uses a 20k-point synthetic scan (skipped with
// a note without the native CLI).
import { createRequire } from 'node:module';
import { check, frontCamera, makeEyePng, makePhotoPng, makePng, note, runAlone, setFile, settled, syntheticSmile,
         waitForState } from '../harness.mjs';
import { syntheticScan } from '../synth_scan.mjs';

const AXE = createRequire(import.meta.url).resolve('axe-core/axe.min.js');

// Serious and critical violations of axe's WCAG 2.0/2.1 A and AA rules and
// best practices, as "rule (n): first targets".
async function violations(page) {
  if (!(await page.evaluate(() => typeof window.axe !== 'undefined'))) await page.addScriptTag({ path: AXE });
  return page.evaluate(async () => {
    const r = await window.axe.run(document, { resultTypes: ['violations'] });
    return r.violations.filter((v) => v.impact === 'serious' || v.impact === 'critical')
      .map((v) => `${v.id} (${v.nodes.length}): ${v.nodes.slice(0, 3).map((n) => n.target.join(' ')).join(', ')}`);
  });
}

async function checkState(page, label) {
  const found = await violations(page);
  check(`${label}: no serious or critical accessibility violation (axe-core)`, found.length === 0, found.join(' | '));
}

// Tab from the top through the page: every visible, enabled control is
// reached, and each shows where the focus is (an outline or a ring).
// Waits until the head kept in IndexedDB (keep.js, saved a moment after a
// change) has stopped saving, so its list is not redrawn under the Tab walk.
async function keepIdle(page) {
  let last = -1;
  for (let i = 0; i < 15; i++) {
    const n = await page.evaluate(() => (window.likeness.keep ? window.likeness.keep.saves : 0));
    if (n === last) return;
    last = n;
    await page.waitForTimeout(2000);
  }
}

async function keyboardReach(page, label) {
  await keepIdle(page);
  // Each control is told apart by a mark of its own (two kept heads of the
  // same minute have the same label); reported by its id or label.
  await page.evaluate(() => {
    document.querySelectorAll('[data-tab-check]').forEach((e) => e.removeAttribute('data-tab-check'));
    document.querySelectorAll('button, input, select, textarea, a[href], [tabindex]')
      .forEach((e, i) => e.setAttribute('data-tab-check', String(i)));
    if (document.activeElement) document.activeElement.blur();
    window.scrollTo(0, 0);
  });
  const describe = () => {
    const e = document.activeElement;
    if (!e || e === document.body) return null;
    const st = getComputedStyle(e);
    const ring = (st.outlineStyle !== 'none' && parseFloat(st.outlineWidth) > 0) || st.boxShadow !== 'none';
    return { key: e.getAttribute('data-tab-check') || e.id || e.getAttribute('aria-label'), ring,
             name: e.id || e.getAttribute('aria-label') || e.textContent.trim().slice(0, 30) };
  };
  const reached = new Map(), names = new Map();
  for (let i = 0; i < 300; i++) {
    await page.keyboard.press('Tab');
    const d = await page.evaluate(describe);
    if (!d) continue;
    if (reached.has(d.key)) break;  // round the page once
    reached.set(d.key, d.ring);
    names.set(d.key, d.name);
  }
  const controls = await page.evaluate(() => Array.from(document.querySelectorAll(
    'button, input, select, textarea, a[href], [tabindex]:not([tabindex="-1"])')).filter((e) => {
    if (e.disabled || e.closest('[hidden]') || e.tabIndex < 0) return false;
    // Inside a closed <details>: not shown (Chromium still gives it a box).
    if (e.closest('details:not([open])') && !e.closest('summary')) return false;
    const r = e.getBoundingClientRect();
    const st = getComputedStyle(e);
    // A visually hidden file input is reached through its label's focus ring.
    return (r.width > 0 && r.height > 0 && st.visibility !== 'hidden') || e.type === 'file';
  }).map((e) => ({ key: e.getAttribute('data-tab-check'), name: e.id || e.getAttribute('aria-label') || e.textContent.trim().slice(0, 30) })));
  const missing = controls.filter((c) => !reached.has(c.key)).map((c) => c.name);
  const noRing = [...reached].filter(([, ring]) => !ring).map(([k]) => names.get(k));
  check(`${label}: every control is reached by Tab and shows its focus`, missing.length === 0 && noRing.length === 0,
        `${reached.size} reached of ${controls.length}; missing: ${missing.join(', ') || 'none'}; no visible focus: ${noRing.join(', ') || 'none'}`);
}

async function run(s) {
  const page = await s.newPage('?autofit=0');
  await checkState(page, 'ready');
  await keyboardReach(page, 'ready');
  await setFile(page, 'broken.ply', Buffer.from('ply\nformat ascii 1.0\nelement vertex 9\nend_header\n1 2\n'));
  await checkState(page, 'error (a broken scan, its reason beside the file)');
  const synth = syntheticScan(s.webdir, 4, 20000);
  if (synth.skip) {
    note('the fitted states are not checked: ' + synth.skip);
    await page.close();
    return;
  }
  await setFile(page, 'head.ply', synth.bytes);
  await checkState(page, 'a scan loaded');
  await page.click('#btn-fit');
  const during = await page.evaluate(() => document.body.dataset.state);
  if (during === 'working') await checkState(page, 'working (a fit running)');
  else note('the fit ended before the check of "working" could run');
  await settled(page);
  await page.waitForFunction(() => window.likeness.fit && window.likeness.fit.quality, null, { timeout: 60000 }).catch(() => {});
  await checkState(page, 'done (the fitted head and its checks)');
  await keyboardReach(page, 'done');
  // The Expressions panel open: its presets, Talk, group select and sliders.
  await page.click('#expressions summary');
  await page.waitForFunction(() => document.querySelectorAll('#expr-sliders input').length > 0, null, { timeout: 60000 }).catch(() => {});
  await checkState(page, 'done, Expressions open (presets, Talk, shape sliders)');
  await keyboardReach(page, 'done, Expressions open');
  await page.click('#expressions summary');
  await page.setInputFiles('#file-input', [{ name: 'front.png', mimeType: 'image/png', buffer: makePng(64, 48) }]);
  await settled(page);
  await page.evaluate(() => window.likeness.openClicker(0));
  await page.waitForSelector('#clicker:not([hidden])', { timeout: 10000 }).catch(() => {});
  await checkState(page, 'a photo open to mark landmarks');
  await page.click('#clicker-close');
  // An eye photo: its iris on the eyeballs; then a grey card as an eye: the
  // error beside it.
  await page.setInputFiles('#file-input', [{ name: 'eye_close.png', mimeType: 'image/png', buffer: makeEyePng() },
    { name: 'grey_card.png', mimeType: 'image/png', buffer: makePhotoPng(200, 150, () => [128, 128, 128]) }]);
  await settled(page);
  const roleSelect = (name) => page.locator('#photo-list li', { hasText: name }).locator('select.photo-role');
  await roleSelect('eye_close.png').selectOption('eye');
  await settled(page);
  await checkState(page, 'an eye photo used for the irises');
  await roleSelect('grey_card.png').selectOption('eye');
  await settled(page);
  await checkState(page, 'an eye photo refused (its error in the banner and beside it)');
  await page.click('#error-dismiss');
  // A smile photo (made by the native CLI) for the teeth.
  const smile = syntheticSmile(s.webdir);
  if (smile) {
    await page.setInputFiles('#file-input', { name: 'smile.png', mimeType: 'image/png', buffer: smile });
    await settled(page);
    await roleSelect('smile.png').selectOption('smile');
    await settled(page);
    await checkState(page, 'a smile photo used for the teeth');
  } else note('the smile photo state is not checked: no native likeness binary');
  // The textured head: a face photo with an exact points file (the other
  // face photo, without points, leaves first).
  await page.locator('#photo-list li', { hasText: 'front.png' }).locator('.photo-remove').click();
  const landmarks = await page.evaluate(() => window.likeness.fit.landmarks);
  const project = frontCamera(landmarks, 640, 480, 900);
  const line = (l) => { const [u, v] = project(l.position); return `${u.toFixed(2)} ${v.toFixed(2)} ${l.position.join(' ')}`; };
  await page.setInputFiles('#file-input', [
    { name: 'head_front.png', mimeType: 'image/png', buffer: makePhotoPng(640, 480, (x, y) => [180 + Math.round(40 * x / 640), 130, 110 + Math.round(30 * y / 480)]) },
    { name: 'head_front.txt', mimeType: 'text/plain', buffer: Buffer.from(landmarks.map(line).join('\n') + '\n') }]);
  await settled(page);
  await page.click('#btn-texture');
  await settled(page);
  const textured = await page.evaluate(() => !!window.likeness.texture && document.body.dataset.state === 'done');
  if (textured) await checkState(page, 'a textured head (eyes, teeth and skin from photos)');
  else check('the head is textured (to check that state)', false, await page.evaluate(() => document.getElementById('status').textContent));
  // The head is kept; after a reload the page offers it back.
  await page.waitForTimeout(1500);
  await page.reload();
  await waitForState(page, ['ready', 'error']);
  const offered = await page.waitForSelector('#restore-offer:not([hidden])', { timeout: 30000 }).then(() => true, () => false);
  if (offered) {
    await checkState(page, 'the restore offer after a reload');
    await page.click('#btn-restore');
    await page.waitForFunction(() => window.likeness.restored, null, { timeout: 120000 }).catch(() => {});
    await settled(page);
    await checkState(page, 'a restored head, with the list of kept heads');
    await keyboardReach(page, 'a restored head');
  } else check('the restore offer appears after a reload (to check it)', false);
  await page.close();
}

export const flow = { name: 'accessibility', title: 'axe-core on every state of the page', run };
runAlone(import.meta.url, flow);
