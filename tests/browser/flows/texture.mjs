// The Texture stage end to end on the fitted synthetic head (tarini2002
// Sec. 3): the fit places the landmarks and the eyes, teeth and tongue (the
// lower teeth and tongue follow the jaw); a photo that is not an image, a
// points file with too few points, then a photo with an exact points file:
// calibration, the texture in the worker, the skin on the canvas; landmark
// clicks with undo and skip; the textured export.
import fs from 'node:fs';
import { bannerText, canvasImage, check, frontCamera, JOB_TIMEOUT_MS, makePhotoPng, makePng, runAlone, settled, shot,
         state } from '../harness.mjs';
import { fittedHead } from './fit.mjs';

// untextured: the canvas before (no texture on the head).
async function textureStage(page, untextured) {
  const landmarks = await page.evaluate(() => window.likeness.fit.landmarks);
  check('the fit places the texture landmarks', landmarks.length >= 12 &&
        landmarks.every((l) => l.label && l.position.length === 3 && l.position.every(Number.isFinite)),
        `${landmarks.length}: ${landmarks.map((l) => l.id).join(', ')}`);
  // Eyes, teeth and tongue come with the fit; the jaw's motion reaches the
  // lower teeth: identity at rest, a rotation of ~8 degrees fully open.
  const parts = await page.evaluate(async () => {
    const run = (amount) => window.likeness.runJob({ type: 'animate', amount, level: 3 }, []);
    const rest = await run(0), open = await run(1);
    await run(0);
    return { components: window.likeness.components, jaw: window.likeness.jawComponents,
             rest: Array.from(rest.jawMatrix || []), open: Array.from(open.jawMatrix || []) };
  });
  const identity = [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1];
  const maxDiff = (m) => Math.max(...m.map((x, i) => Math.abs(x - identity[i])));
  const angle = parts.open.length === 16 ? Math.acos(Math.min(1, (parts.open[0] + parts.open[5] + parts.open[10] - 1) / 2)) * 180 / Math.PI : 0;
  check('eyes, teeth and tongue are shown; the lower teeth and tongue follow the jaw', parts.components === 5 &&
        parts.jaw && parts.jaw.length === 2 && parts.rest.length === 16 && maxDiff(parts.rest) < 1e-5 && angle > 6 && angle < 10,
        `${parts.components} components, jaw-driven ${JSON.stringify(parts.jaw)}, rest off identity by ${parts.rest.length ? maxDiff(parts.rest).toExponential(1) : '?'}, open ${angle.toFixed(1)} deg`);
  if (landmarks.length < 12) return;
  const W = 640, H = 480;
  const project = frontCamera(landmarks, W, H, 900);
  // A saturated blue-violet photo: nothing like the untextured skin tone.
  const photo = makePhotoPng(W, H, (x, y) => [40 + Math.round(60 * x / W), 50, 230 - Math.round(40 * y / H)]);
  const line = (l) => { const [u, v] = project(l.position); return `${u.toFixed(2)} ${v.toFixed(2)} ${l.position.join(' ')}`; };

  // Not an image: an error naming it, and the page keeps working.
  await page.setInputFiles('#file-input', { name: 'holiday.jpg', mimeType: 'image/jpeg', buffer: Buffer.from('not a jpeg at all') });
  await settled(page);
  const notImage = await bannerText(page);
  check('a photo that is not an image gives an error banner', (await state(page)) === 'error' && /holiday\.jpg/.test(notImage),
        `"${notImage}"`);
  await page.click('#error-dismiss');

  // Only this test's photo: the others (the sample's, front.png) are removed
  // with their rows' buttons. (Alone, this flow drops a front.png of its own
  // to remove; in the whole run it is scan-load's again.)
  await page.setInputFiles('#file-input', { name: 'front.png', mimeType: 'image/png', buffer: makePng(6, 4) });
  await settled(page);
  for (let k = 0; k < 12; k++) {
    const others = page.locator('#photo-list li', { hasNotText: 'head_front.png' }).locator('.photo-remove');
    if (!(await others.count())) break;
    await others.first().click();
  }
  check('photos can be removed from the list', (await page.evaluate(() => window.likeness.photos.length)) === 0,
        await page.evaluate(() => window.likeness.photos.map((p) => p.name).join(', ') || 'none left'));

  // Four points: a clear message before anything runs.
  await page.setInputFiles('#file-input', [
    { name: 'head_front.png', mimeType: 'image/png', buffer: photo },
    { name: 'head_front.txt', mimeType: 'text/plain', buffer: Buffer.from(landmarks.slice(0, 4).map(line).join('\n') + '\n') }]);
  await settled(page);
  const listed = await page.textContent('#photo-list');
  check('the photo is listed with a thumbnail and its points file', /head_front\.png/.test(listed) && /4 points from head_front\.txt/.test(listed) &&
        (await page.locator('#photo-list img').count()) >= 1, listed.replace(/\s+/g, ' ').trim());
  await page.click('#btn-texture');
  await settled(page);
  const few = await bannerText(page);
  check('fewer than 6 points give a clear message', (await state(page)) === 'error' && /head_front\.png has 4 point/.test(few) &&
        /at least 6/.test(few), `"${few}"`);
  await page.click('#error-dismiss');

  // A whole points file (14 landmarks, exact projections): the texture.
  await page.setInputFiles('#file-input', { name: 'head_front.txt', mimeType: 'text/plain',
                                            buffer: Buffer.from('# u v X Y Z\n' + landmarks.map(line).join('\n') + '\n') });
  await settled(page);
  const progress = [];
  await page.exposeFunction('lkTextureProgress', (v) => progress.push(v)).catch(() => {});
  await page.evaluate(() => {
    const bar = document.querySelector('#stages li[data-stage="texture"] progress');
    new MutationObserver(() => window.lkTextureProgress(bar.value)).observe(bar, { attributes: true });
    const tag = document.querySelector('#stages li[data-stage="texture"] .stage-tag');
    new MutationObserver(() => window.lkTextureProgress(tag.textContent)).observe(tag, { childList: true, characterData: true, subtree: true });
  });
  const tTex = Date.now();
  await page.click('#btn-texture');
  await settled(page);
  const tex = await page.evaluate(() => ({
    state: document.body.dataset.state, texture: window.likeness.texture && { ms: window.likeness.texture.textureMs,
      steps: window.likeness.texture.steps.map((s) => s.name + ' ' + Math.round(s.ms)), size: window.likeness.texture.skin.width },
    tag: document.querySelector('#stages li[data-stage="texture"] .stage-tag').textContent,
    bar: document.querySelector('#stages li[data-stage="texture"] progress').value,
    calib: window.likeness.photos.find((p) => p.name === 'head_front.png').calib }));
  const percents = progress.filter((v) => typeof v === 'string' && /%$/.test(v));
  check('"Texture" reaches done with per-step progress', tex.state === 'done' && !!tex.texture && tex.bar === 1 && / ms$/.test(tex.tag) &&
        percents.length >= 3, tex.texture ? `${Date.now() - tTex} ms wall; ${Math.round(tex.texture.ms)} ms in the worker: ` +
        `${tex.texture.steps.join(', ')}; progress ${percents.slice(0, 8).join(' ')}` : `state ${tex.state}: ${await bannerText(page)}`);
  check('the photo calibrates from exact points (rms < 0.5 px, no outlier)', tex.calib && tex.calib.ok && tex.calib.rms < 0.5 &&
        !tex.calib.outlier.some(Boolean), tex.calib ? `rms ${tex.calib.rms.toFixed(3)} px, ${tex.calib.inliers} inliers` : 'no calibration');
  const textured = await canvasImage(page);
  let blue = 0, blueBefore = 0;
  const bluish = (img, i) => img.data[i + 2] > img.data[i] + 40 && img.data[i + 2] > img.data[i + 1] + 40;
  for (let i = 0; i < textured.data.length; i += 4) { if (bluish(textured, i)) blue++; if (bluish(untextured, i)) blueBefore++; }
  const n = textured.width * textured.height;
  check('the canvas shows the photo\'s colour on the head', blue / n > 0.03 && blue > 5 * blueBefore + 100,
        `${(100 * blue / n).toFixed(1)}% blue-violet pixels (untextured ${(100 * blueBefore / n).toFixed(2)}%)`);
  await shot(page, 'web_texture_result.png');

  // Clicking landmarks: undo and skip, clicks kept per photo.
  await page.evaluate(() => window.likeness.openClicker(window.likeness.photos.findIndex((p) => p.name === 'head_front.png')));
  await page.click('#clicker-clear');
  await page.waitForTimeout(100);
  const box = await page.locator('#clicker-canvas').boundingBox();
  const clickLandmark = async (l) => {
    const [u, v] = project(l.position);
    const scale = Math.min(box.width / W, box.height / H);
    await page.mouse.click(box.x + (box.width - W * scale) / 2 + u * scale, box.y + (box.height - H * scale) / 2 + v * scale);
  };
  for (const l of landmarks.slice(0, 9)) await clickLandmark(l);
  await page.click('#clicker-undo');
  await page.click('#clicker-skip');  // the 9th landmark, skipped instead
  for (const l of landmarks.slice(9)) await clickLandmark(l);
  const clicked = await page.evaluate(() => {
    const p = window.likeness.photos.find((x) => x.name === 'head_front.png');
    return { n: Array.from(p.clicks.values()).filter((c) => c !== 'skip').length,
             skipped: Array.from(p.clicks.values()).filter((c) => c === 'skip').length,
             prompt: document.getElementById('clicker-prompt').textContent,
             listed: document.getElementById('photo-list').textContent };
  });
  check('clicks, undo and skip build the photo\'s landmarks', clicked.n === landmarks.length - 1 && clicked.skipped === 1 &&
        new RegExp((landmarks.length - 1) + ' of ' + landmarks.length + ' landmarks clicked').test(clicked.listed),
        `${clicked.n} clicked, ${clicked.skipped} skipped; "${clicked.prompt}"`);
  await page.click('#btn-texture');
  await settled(page);
  const byClicks = await page.evaluate(() => ({ state: document.body.dataset.state,
    calib: window.likeness.photos.find((p) => p.name === 'head_front.png').calib,
    outliersShown: document.querySelectorAll('#clicker-list li.outlier').length }));
  // Clicks land on CSS pixels of a photo shown at about half size: ~1 px error.
  check('the clicked landmarks calibrate the photo (rms < 3 px) and texture it', byClicks.state === 'done' && byClicks.calib &&
        byClicks.calib.ok && byClicks.calib.rms < 3, byClicks.calib ? `rms ${byClicks.calib.rms.toFixed(2)} px, ` +
        `${byClicks.calib.inliers} inliers, ${byClicks.outliersShown} marked as outliers` : `state ${byClicks.state}`);
  await page.evaluate(() => window.likeness.openClicker(window.likeness.photos.findIndex((p) => p.name === 'head_front.png')));
  await shot(page, 'web_texture_clicks.png');
  await page.click('#clicker-close');

  // Textured export: OBJ with uvs, its MTL and the PNG.
  const before = await page.evaluate(() => window.likeness.downloads.length);
  const files = [];
  const onDownload = async (d) => files.push({ name: d.suggestedFilename(), bytes: fs.readFileSync(await d.path()) });
  page.on('download', onDownload);
  await page.click('#btn-export-textured');
  await page.waitForFunction((n) => window.likeness.downloads.length >= n + 3, before, { timeout: JOB_TIMEOUT_MS });
  await page.waitForTimeout(500);
  page.off('download', onDownload);
  const obj = files.find((f) => f.name.endsWith('.obj')), mtl = files.find((f) => f.name.endsWith('.mtl')),
        png = files.find((f) => f.name.endsWith('.png'));
  const objText = obj ? obj.bytes.toString('latin1') : '';
  const vts = (objText.match(/^vt /gm) || []).length, vs = (objText.match(/^v /gm) || []).length;
  check('"Textured" exports OBJ (with uvs) + MTL + PNG', !!obj && !!mtl && !!png && vs > 0 && vts === vs &&
        /mtllib .*\.mtl/.test(objText) && /map_Kd .*\.png/.test(mtl.bytes.toString()) && png.bytes.toString('latin1', 1, 4) === 'PNG',
        files.map((f) => `${f.name} ${f.bytes.length} B`).join(', ') + `; ${vs} v, ${vts} vt`);
}

async function run(s) {
  const { page, fit } = await fittedHead(s);
  if (!fit) return;
  await textureStage(page, await canvasImage(page));
}

export const flow = { name: 'texture', title: 'the Texture stage: points files, landmark clicks, textured export', run };
runAlone(import.meta.url, flow);
