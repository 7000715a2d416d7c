// Phones (issue 39): the page in a phone's browser (390x844, touch, a
// mobile viewport) lays out in one column with nothing wider than the
// screen, and shows "Take photos" (a camera input, `capture`), which the
// desktop page hides. Photos are then taken one at a time the way a phone
// gives them (each a JPEG named image.jpg): the renders of a synthetic person
// (`likeness synth-photos`, seed 2, 9 cameras; views 04 front, 03 and 05
// about 22 deg to either side, 02 and 06 about 45 deg), turned into JPEGs by
// the browser, each with its lens in EXIF as phones write it. After each photo the guide says which views are still
// missing; no photo replaces another; Auto-run waits for enough views (5
// photos with a face, every view) and then makes the head by itself; a
// photo taken while that job runs (another front one) waits and is added
// after it, not dropped.
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { execFileSync } from 'node:child_process';
import { check, closeChromium, launchChromium, likenessBin, note, READY_TIMEOUT_MS, runAlone, SHOT_DIR, waitForState } from '../harness.mjs';

const ORDER = ['view_04', 'view_03', 'view_05', 'view_02', 'view_06'];
const LATE = 'view_04';   // another front photo, taken while the head is being made

// A phone's JPEG carries its lens in EXIF: FocalLengthIn35mmFilm. The
// synthetic cameras' 1250 px on 1200x1600 is 1250 / 2000 * 43.27 = 27.0 mm
// (the 35-mm frame's diagonal is 43.27 mm), which reads back as 1248 px.
const FOCAL_35MM = 27, TRUE_FOCAL_PX = 1250;

// jpeg with an APP1 Exif segment after its SOI: a big-endian TIFF block
// whose IFD0 points to an Exif IFD holding FocalLengthIn35mmFilm (0xA405).
function withExif(jpeg, focal35) {
  const tiff = Buffer.alloc(44);
  tiff.write('MM', 0, 'latin1');
  tiff.writeUInt16BE(42, 2);
  tiff.writeUInt32BE(8, 4);                       // IFD0
  tiff.writeUInt16BE(1, 8);                       // one entry: ExifIFDPointer
  tiff.writeUInt16BE(0x8769, 10); tiff.writeUInt16BE(4, 12); tiff.writeUInt32BE(1, 14); tiff.writeUInt32BE(26, 18);
  tiff.writeUInt32BE(0, 22);                      // no next IFD
  tiff.writeUInt16BE(1, 26);                      // Exif IFD: FocalLengthIn35mmFilm, SHORT
  tiff.writeUInt16BE(0xA405, 28); tiff.writeUInt16BE(3, 30); tiff.writeUInt32BE(1, 32); tiff.writeUInt16BE(focal35, 36);
  tiff.writeUInt32BE(0, 40);
  const head = Buffer.from([0xFF, 0xE1, 0, 0]);
  head.writeUInt16BE(2 + 6 + tiff.length, 2);
  return Buffer.concat([jpeg.subarray(0, 2), head, Buffer.from('Exif\0\0', 'latin1'), tiff, jpeg.subarray(2)]);
}


// The guide and the photos once every photo's face points are in and no
// job of checking photos runs.
async function guideAfter(page, count) {
  await page.waitForFunction((n) => window.likeness.photos.length >= n && window.likeness.photos.every((p) =>
    p.detect && !['waiting', 'running'].includes(p.detect.state)), count, { timeout: 180000 });
  return page.evaluate(() => ({
    names: window.likeness.photos.map((p) => p.name),
    views: Array.from(document.querySelectorAll('#view-list li')).map((li) => ({ text: li.textContent, have: li.classList.contains('have') })),
    hint: document.getElementById('view-hint').textContent,
    guide: window.likeness.viewGuide,
    head: window.likeness.photosHead,
    state: document.body.dataset.state,
  }));
}

// The page's layout on the phone: widths, and the tap targets' sizes.
const layout = (page) => page.evaluate(() => {
  const visible = (el) => { const r = el.getBoundingClientRect(); return r.width > 0 && r.height > 0 && getComputedStyle(el).visibility !== 'hidden'; };
  // A checkbox is tapped through its label too (the label is the target);
  // a slider's track is its own.
  const targets = Array.from(document.querySelectorAll('button, label.button, select, input[type=checkbox], input[type=range]')).filter(visible);
  const sizes = targets.map((el) => {
    const box = el.type === 'checkbox' && el.closest('label') ? el.closest('label') : el;
    const r = box.getBoundingClientRect();
    return { id: el.id || el.textContent.trim().slice(0, 20), w: r.width, h: r.height };
  });
  const cam = document.getElementById('camera-input');
  const take = document.getElementById('btn-take-photos');
  const canvas = document.getElementById('canvas').getBoundingClientRect();
  const bar = document.querySelector('.toolbar').getBoundingClientRect();
  return {
    toolbar: { top: bar.top, bottom: bar.bottom }, canvasBottom: canvas.bottom,
    scrollWidth: document.scrollingElement.scrollWidth, innerWidth: window.innerWidth,
    coarse: matchMedia('(pointer: coarse)').matches,
    take: visible(take), capture: cam.getAttribute('capture'), accept: cam.getAttribute('accept'),
    canvas: { top: canvas.top, height: canvas.height, width: canvas.width },
    small: sizes.filter((t) => t.w < 44 || t.h < 44), smallestH: Math.min(...sizes.map((t) => t.h)), targets: sizes.length,
  };
});

// A desktop with a mouse only (the run's shared browser has a touch screen).
async function desktopHidesCamera(origin) {
  const context = await launchChromium('desktop', { width: 1280, height: 800 });
  try {
    const page = await context.newPage();
    await page.goto(origin + '/index.html');
    await waitForState(page, ['ready', 'error'], READY_TIMEOUT_MS);
    const hidden = await page.evaluate(() => getComputedStyle(document.getElementById('take-photos')).display);
    check('on a desktop with a mouse (a fine pointer) "Take photos" is not shown', hidden === 'none', `display ${hidden}`);
  } finally {
    await closeChromium(context);
  }
}

async function run(s) {
  const bin = likenessBin(s.webdir);
  if (!bin) {
    note('phone: skipped, no native likeness binary to make the photo session (set LK_LIKENESS_BIN)');
    return;
  }
  const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'likeness-phone-'));
  const { server, origin } = await s.serve();
  await desktopHidesCamera(origin);
  const context = s.watchRequests(await launchChromium('phone', { width: 390, height: 844 }, { hasTouch: true, isMobile: true }));
  try {
    execFileSync(bin, ['synth-photos', '--seed', '2', '--cameras', '9', '--out', dir]);
    const page = s.watch(await context.newPage());
    await page.goto(origin + '/index.html');
    const first = await waitForState(page, ['ready', 'error'], READY_TIMEOUT_MS);
    const l = await layout(page);
    check('the phone page starts', first === 'ready', first);
    check('on a phone nothing is wider than the screen (no sideways scrolling)', l.scrollWidth <= l.innerWidth,
          `scroll width ${l.scrollWidth} px, screen ${l.innerWidth} px`);
    check('on a phone the 3D view fills the screen\'s width and is on the first screen',
          l.canvas.width >= 0.9 * l.innerWidth && l.canvas.top < 844 && l.canvas.height >= 300, JSON.stringify(l.canvas));
    check('on a phone the view controls sit under the 3D view, not over it', l.toolbar.top >= l.canvasBottom - 1 && l.toolbar.bottom <= 844,
          `view ${l.canvas.top.toFixed(0)}-${l.canvasBottom.toFixed(0)} px, controls ${l.toolbar.top.toFixed(0)}-${l.toolbar.bottom.toFixed(0)} px`);
    check('on a phone "Take photos" is shown, and opens the camera (a file input with capture, images)',
          l.coarse && l.take && l.capture === 'user' && l.accept === 'image/*', `coarse ${l.coarse}, shown ${l.take}, capture ${l.capture}, accept ${l.accept}`);
    check('on a phone every control is at least 44x44 px to tap (WCAG 2.2 asks 24 px at least)', l.small.length === 0,
          `${l.targets} controls, smallest height ${l.smallestH.toFixed(0)} px; too small: ${JSON.stringify(l.small)}`);
    if (SHOT_DIR) await page.screenshot({ path: path.join(SHOT_DIR, 'web_phone.png') });

    // A phone's camera gives JPEGs, each named image.jpg.
    const jpeg = async (name) => Buffer.from(await page.evaluate(async (b64) => {
      const bytes = Uint8Array.from(atob(b64), (c) => c.charCodeAt(0));
      const bitmap = await createImageBitmap(new Blob([bytes], { type: 'image/png' }));
      const canvas = new OffscreenCanvas(bitmap.width, bitmap.height);
      canvas.getContext('2d').drawImage(bitmap, 0, 0);
      const blob = await canvas.convertToBlob({ type: 'image/jpeg', quality: 0.92 });
      const out = new Uint8Array(await blob.arrayBuffer());
      let s = '';
      for (let i = 0; i < out.length; i += 0x8000) s += String.fromCharCode(...out.subarray(i, i + 0x8000));
      return btoa(s);
    }, fs.readFileSync(path.join(dir, name + '.png')).toString('base64')), 'base64');
    const take = async (name) => page.setInputFiles('#camera-input', { name: 'image.jpg', mimeType: 'image/jpeg',
                                                                       buffer: withExif(await jpeg(name), FOCAL_35MM) });

    const steps = [];
    for (const [k, name] of ORDER.entries()) {
      await take(name);
      steps.push(await guideAfter(page, k + 1));
    }
    const [one, , three, four] = steps;
    note('phone: the guide after each photo: ' + steps.map((g, k) => `${ORDER[k]}: ${JSON.stringify(g.guide.counts)} "${g.hint}"`).join(' | '));
    check('each photo taken gets a name of its own (the camera names them all image.jpg)',
          steps[4].names.join() === 'photo-01.jpg,photo-02.jpg,photo-03.jpg,photo-04.jpg,photo-05.jpg', steps[4].names.join());
    check('after the front photo the guide counts the front and names the next missing view',
          one.guide.counts.front === 1 && one.views.filter((v) => !v.have).length === 2 && /^Next: the (left|right) three-quarter view/.test(one.hint),
          `${JSON.stringify(one.views)} "${one.hint}"`);
    check('after one photo to each side no view is missing, and the guide asks for more photos (5 wanted)',
          three.guide.missing.length === 0 && three.views.every((v) => v.have) && /2 more photo/.test(three.hint) && !three.guide.enough,
          `${JSON.stringify(three.guide.counts)} "${three.hint}"`);
    check('while photos are being taken, Auto-run does not make a head before the views are enough',
          steps.slice(0, 4).every((g) => !g.head) && !four.guide.enough, steps.map((g) => !!g.head).join(','));

    // The fifth photo is enough: the head is being made. A photo taken now waits.
    await page.waitForFunction(() => window.likeness.photosHead || document.body.dataset.state === 'working', null, { timeout: 60000 });
    const during = await page.evaluate(() => document.body.dataset.state);
    await take(LATE);
    const waitingHint = await page.evaluate(() => document.getElementById('view-hint').textContent);
    if (during !== 'working') note('phone: the head was made before the late photo was taken (no job to wait for)');
    await page.waitForFunction(() => window.likeness.photos.length === 6 && window.likeness.photosHead &&
      window.likeness.photosHead.photos === 6 && !['working', 'loading'].includes(document.body.dataset.state), null, { timeout: 400000 });
    const end = await page.evaluate(() => ({ head: window.likeness.photosHead, names: window.likeness.photos.map((p) => p.name),
                                             hint: document.getElementById('view-hint').textContent, state: document.body.dataset.state }));
    check('with 5 photos and every view, the head is made by itself', end.head.trigger === 'auto' && end.head.ok && end.state === 'done',
          JSON.stringify(end.head));
    check('a photo taken while the head was being made waits, then is added (not dropped) and the head made again with it',
          end.names.length === 6 && end.names[5] === 'photo-06.jpg' && end.head.photos === 6 &&
          (during !== 'working' || /taken meanwhile/.test(waitingHint)), `during ${during}: "${waitingHint}"; ${end.names.join()}`);
    note(`phone: head from ${end.head.used} of ${end.head.photos} photos in ${(end.head.wallMs / 1000).toFixed(1)} s; guide: "${end.hint}"`);
    const exif = await page.evaluate(() => window.likeness.photos.map((p) => p.exifFocalPx));
    check('each taken photo\'s EXIF lens (27 mm in 35-mm terms) is read as its focal in pixels, and the head is made with it as the prior',
          exif.every((f) => Math.abs(f - 1248) < 1) && Math.abs(end.head.exifFocalPx - 1248) < 1,
          `EXIF ${exif.map(Math.round).join(', ')} px; prior ${Math.round(end.head.exifFocalPx)} px; the head's focal ` +
          `${Math.round(end.head.focalPx)} px (truth ${TRUE_FOCAL_PX} px)`);
    if (SHOT_DIR) {
      await page.evaluate(() => document.getElementById('photos-card').scrollIntoView());
      await page.screenshot({ path: path.join(SHOT_DIR, 'web_phone_take_photos.png') });
    }
  } finally {
    await closeChromium(context, server);
    fs.rmSync(dir, { recursive: true, force: true });
  }
}

export const flow = { name: 'phone', title: 'a phone: one column, Take photos and its guide around the head', run };
runAlone(import.meta.url, flow);
