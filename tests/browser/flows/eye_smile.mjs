// Eye and smile photos (tarini2002 Sec. 4) on the fitted head: the teeth
// wear the generic teeth texture after a fit; a photo set to "Eye (iris)"
// dresses both eyeballs with its synthesized iris; a photo that is no eye,
// as Eye, gives a clear error and keeps the other photos' clicks; eye photos
// are not used for the skin; a smile photo (made by the native CLI; skipped
// without it) set to "Smile (teeth)" replaces the teeth texture; removing
// them gives the generic textures back; the GLB export carries the photos'
// iris and teeth textures, and the generic ones again once they are removed.
import crypto from 'node:crypto';
import fs from 'node:fs';
import { createRequire } from 'node:module';
import { bannerText, check, closeChromium, JOB_TIMEOUT_MS, launchChromium, makeEyePng, makePhotoPng, makePng, note,
         READY_TIMEOUT_MS, runAlone, settled, shot, syntheticSmile, waitForState } from '../harness.mjs';
import { fittedHead } from './fit.mjs';

// "Head (GLB)" clicked: a hash of each textured material's image bytes in
// the downloaded GLB, by material name ({eye, teeth, ...}), and the status.
async function glbImages(page) {
  const downloadP = page.waitForEvent('download', { timeout: 120000 });
  await page.click('#btn-export-glb');
  const glb = fs.readFileSync(await (await downloadP).path());
  await settled(page);
  const jsonLength = glb.readUInt32LE(12);
  const gltf = JSON.parse(glb.toString('utf8', 20, 20 + jsonLength));
  const bin = glb.subarray(20 + jsonLength + 8);
  const out = {};
  for (const m of gltf.materials || []) {
    const t = m.pbrMetallicRoughness && m.pbrMetallicRoughness.baseColorTexture;
    if (!t) continue;
    const view = gltf.bufferViews[gltf.images[gltf.textures[t.index].source].bufferView];
    out[m.name] = crypto.createHash('sha1').update(bin.subarray(view.byteOffset || 0, (view.byteOffset || 0) + view.byteLength)).digest('hex').slice(0, 12);
  }
  return { glb, images: out, status: await page.evaluate(() => document.getElementById('status').textContent) };
}

// Issue 39's "save, clear storage, open: equal" with the eye and smile
// photos' textures: "Save project" with them shown, then the file opened in
// a browser with an empty profile (no IndexedDB, no photos): the eyes and
// teeth are the photos' again, on screen and in the GLB, byte for byte, and
// the photo rows come back from the file with their roles.
async function savedAndOpened(s, page, photoGlb, withSmile) {
  const downloadP = page.waitForEvent('download', { timeout: JOB_TIMEOUT_MS });
  await page.click('#btn-save-project');
  const download = await downloadP;
  const bytes = fs.readFileSync(await download.path());
  await settled(page);
  const shown = await page.evaluate(() => window.likeness.componentTextures);
  const photosSaved = await page.evaluate(() => window.likeness.photos.map((p) => p.name + ':' + (p.role || 'face') + ':' + p.file.size).join(' '));
  const { origin } = await s.serve();
  const context = s.watchRequests(await launchChromium('eye-smile-open', { width: 1280, height: 800 }));
  try {
    const fresh = s.watch(await context.newPage());
    await fresh.goto(origin + '/index.html');
    await waitForState(fresh, ['ready', 'error'], READY_TIMEOUT_MS);
    // Nothing kept in this profile: no head to restore, no photos.
    const empty = await fresh.evaluate(() => !window.likeness.fit && window.likeness.photos.length === 0 &&
      !(window.likeness.keep && window.likeness.keep.heads && window.likeness.keep.heads.length));
    await fresh.setInputFiles('#project-input', { name: download.suggestedFilename(), mimeType: 'model/gltf-binary', buffer: bytes });
    await settled(fresh);
    const opened = await fresh.evaluate(() => ({ tex: window.likeness.componentTextures,
      photos: window.likeness.photos.map((p) => p.name + ':' + (p.role || 'face') + ':' + p.file.size).join(' '),
      status: document.getElementById('status').textContent, state: document.body.dataset.state }));
    check('a project saved with eye' + (withSmile ? ' and smile' : '') + ' photos, opened in an empty browser profile, shows their iris' +
          (withSmile ? ' and teeth' : '') + ' again, and the photos come back with their roles (project file version 3)',
          empty && opened.state === 'done' && opened.photos === photosSaved && /:eye:/.test(opened.photos) && opened.tex.eyes === shown.eyes &&
          opened.tex.teeth === shown.teeth && opened.tex.teethTextured && /eyes from eye_close\.png/.test(opened.status),
          `saved ${bytes.length} bytes showing ${JSON.stringify(shown)}; opened ${JSON.stringify(opened)}`);
    const openedGlb = await glbImages(fresh);
    check('...and its "Head (GLB)" carries the same eye and teeth images, byte for byte, as before the save',
          JSON.stringify(openedGlb.images) === JSON.stringify(photoGlb.images) && !!openedGlb.images.eye,
          `before ${JSON.stringify(photoGlb.images)}; opened ${JSON.stringify(openedGlb.images)}`);
    await shot(fresh, 'web_project_eye_smile.png');
  } finally {
    await closeChromium(context);
  }
}

async function eyeAndSmilePhotos(s, page, webdir) {
  const before = await page.evaluate(() => ({ tex: window.likeness.componentTextures, n: window.likeness.components,
    teeth: window.likeness.componentsData && window.likeness.componentsData.teethTexture,
    teethMs: window.likeness.componentsData && window.likeness.componentsData.teethTextureMs,
    clicks: window.likeness.photos.map((p) => [p.name, p.clicks.size]) }));
  const tt = before.teeth;
  check('the teeth wear the generic teeth texture after a fit (RGBA, transparent voids)', before.tex.teethTextured &&
        before.tex.teeth === 'generic' && before.tex.eyes === 'generic' && before.n === 5 && !!tt && tt.channels === 4 &&
        (() => { let clear = 0, solid = 0; for (let i = 3; i < tt.pixels.length; i += 4) { if (tt.pixels[i] === 0) clear++; else if (tt.pixels[i] === 255) solid++; }
                 return clear > 0 && solid > 0.3 * tt.pixels.length / 4; })(),
        JSON.stringify(before.tex) + (tt ? ` ${tt.width}x${tt.height}x${tt.channels}, made in ${Math.round(before.teethMs)} ms in the worker` : ' no teeth texture'));
  const genericGlb = await glbImages(page);
  // A good synthetic eye, then a grey card, both dropped as photos.
  await page.setInputFiles('#file-input', [
    { name: 'eye_close.png', mimeType: 'image/png', buffer: makeEyePng() },
    { name: 'grey_card.png', mimeType: 'image/png', buffer: makePhotoPng(200, 150, () => [128, 128, 128]) }]);
  await settled(page);
  const roleSelect = (name) => page.locator('#photo-list li', { hasText: name }).locator('select.photo-role');
  const t0 = Date.now();
  await roleSelect('eye_close.png').selectOption('eye');
  await settled(page);
  const eye = await page.evaluate(() => ({ photo: window.likeness.eyePhoto && { circle: window.likeness.eyePhoto.circle, ms: window.likeness.eyePhoto.ms,
    w: window.likeness.eyePhoto.texture.width }, tex: window.likeness.componentTextures, n: window.likeness.components,
    state: document.body.dataset.state, faces: window.likeness.photos.filter((p) => (p.role || 'face') === 'face').map((p) => p.name) }));
  const c = eye.photo && eye.photo.circle;
  check('an eye photo set to "Eye (iris)" puts its iris on both eyeballs without errors', eye.state === 'done' && (await bannerText(page)) === '' &&
        !!c && Math.hypot(c.x - 121.3, c.y - 98.7) < 3 && Math.abs(c.radius - 40) < 3 && eye.tex.eyes === 'photo:eye_close.png' &&
        eye.tex.teethTextured && eye.n === 5 && !eye.faces.includes('eye_close.png'),
        c ? `centre (${c.x.toFixed(1)}, ${c.y.toFixed(1)}) r ${c.radius.toFixed(1)} (truth (121.3, 98.7) r 40), iris job ${Math.round(eye.photo.ms)} ms in the worker, ` +
            `${Date.now() - t0} ms wall; ${JSON.stringify(eye.tex)}` : `state ${eye.state}: ${await bannerText(page)}`);
  await roleSelect('grey_card.png').selectOption('eye');
  await settled(page);
  const bad = await bannerText(page);
  const after = await page.evaluate(() => ({ tex: window.likeness.componentTextures, state: document.body.dataset.state,
    clicks: window.likeness.photos.filter((p) => p.name !== 'grey_card.png' && p.name !== 'eye_close.png').map((p) => [p.name, p.clicks.size]) }));
  check('a non-eye image as "Eye (iris)" gives a clear error; the eyes and the clicks stay', after.state === 'error' &&
        /grey_card\.png/.test(bad) && /iris|eye/i.test(bad) && after.tex.eyes === 'photo:eye_close.png' &&
        JSON.stringify(after.clicks) === JSON.stringify(before.clicks), `"${bad}"; ${JSON.stringify(after)}`);
  await shot(page, 'web_eye_photo.png');
  // A smile photo as "Smile (teeth)" replaces the generic teeth texture.
  const smile = syntheticSmile(webdir);
  const names = ['grey_card.png', 'eye_close.png'];
  if (smile) {
    await page.setInputFiles('#file-input', { name: 'smile.png', mimeType: 'image/png', buffer: smile });
    await settled(page);
    await roleSelect('smile.png').selectOption('smile');
    await settled(page);
    const teeth = await page.evaluate(() => ({ tex: window.likeness.componentTextures, state: document.body.dataset.state,
      ms: window.likeness.smilePhoto && window.likeness.smilePhoto.ms,
      differs: (() => {
        const a = window.likeness.smilePhoto && window.likeness.smilePhoto.texture.pixels, b = window.likeness.componentsData.teethTexture.pixels;
        if (!a || a.length !== b.length) return -1;
        let n = 0;
        for (let i = 0; i < a.length; i++) if (Math.abs(a[i] - b[i]) > 8) n++;
        return n / a.length;
      })() }));
    check('a smile photo set to "Smile (teeth)" replaces the teeth texture', teeth.state === 'done' && teeth.tex.teeth === 'photo:smile.png' &&
          teeth.tex.teethTextured && teeth.differs > 0.01, `${JSON.stringify(teeth.tex)}, teeth job ${Math.round(teeth.ms)} ms in the worker, ` +
          `${(100 * teeth.differs).toFixed(1)}% of bytes differ from the generic texture; ${await bannerText(page)}`);
    names.push('smile.png');
  } else {
    note('the smile photo is not exercised: no native likeness binary (set LK_LIKENESS_BIN)');
  }
  // The GLB carries the photos' irises (and teeth), not the generic ones.
  const photoGlb = await glbImages(page);
  check('"Head (GLB)" exports the iris' + (smile ? ' and teeth' : '') + ' made from the photos in place of the generic textures',
        !!genericGlb.images.eye && !!photoGlb.images.eye && photoGlb.images.eye !== genericGlb.images.eye &&
        (!smile || (!!photoGlb.images.teeth && photoGlb.images.teeth !== genericGlb.images.teeth)) &&
        /irises from eye_close\.png/.test(photoGlb.status),
        `generic ${JSON.stringify(genericGlb.images)}; with the photos ${JSON.stringify(photoGlb.images)}; "${photoGlb.status}"`);
  await savedAndOpened(s, page, photoGlb, !!smile);
  const v = await createRequire(import.meta.url)('gltf-validator').validateBytes(new Uint8Array(photoGlb.glb), { maxIssues: 50 });
  check('...and the Khronos glTF-Validator finds no error and no warning in it', v.issues.numErrors === 0 && v.issues.numWarnings === 0,
        `${v.issues.numErrors} errors, ${v.issues.numWarnings} warnings: ` +
        v.issues.messages.slice(0, 5).map((m) => m.code + ' ' + (m.pointer || '')).join(', '));
  // The test's photos leave; the eyes and teeth go back to the generic textures.
  for (const name of names) await page.locator('#photo-list li', { hasText: name }).locator('.photo-remove').click();
  const reset = await page.evaluate(() => window.likeness.componentTextures);
  const resetGlb = await glbImages(page);
  check('removing the eye and smile photos gives the generic textures back, in the view and in the GLB',
        reset.eyes === 'generic' && reset.teeth === 'generic' && JSON.stringify(resetGlb.images) === JSON.stringify(genericGlb.images),
        JSON.stringify(reset) + ' ' + JSON.stringify(resetGlb.images));
}

async function run(s) {
  const { page, fit } = await fittedHead(s);
  if (!fit) return;
  // A face photo with clicks, which a failed eye photo must leave alone: the
  // texture flow's head_front.png in the whole run; alone, one made here.
  if (!(await page.evaluate(() => window.likeness.photos.some((p) => p.clicks.size > 0)))) {
    await page.setInputFiles('#file-input', { name: 'clicked_face.png', mimeType: 'image/png', buffer: makePng(64, 48) });
    await settled(page);
    await page.evaluate(() => {
      const photo = window.likeness.photos.find((p) => p.name === 'clicked_face.png');
      for (const [k, l] of window.likeness.fit.landmarks.slice(0, 3).entries()) photo.clicks.set(l.id, { u: 10 + 10 * k, v: 20 });
    });
  }
  await eyeAndSmilePhotos(s, page, s.webdir);
}

export const flow = { name: 'eye-smile', title: 'eye and smile photos: the iris and teeth textures', run };
runAlone(import.meta.url, flow);
