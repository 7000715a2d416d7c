// "Follow my face" (issue 38) with Chromium's fake camera: a browser of its
// own launched with --use-fake-device-for-media-stream and
// --use-fake-ui-for-media-stream (the camera allowed without asking) playing
// a y4m made here from our own renders (`likeness render --expression`):
// the generic head at rest for NEUTRAL_S seconds, then with jawOpen. The
// head is a native fit of a synthetic scan opened as a project. Checked: the
// toggle is off at start; on, the camera opens (indicator shown), the
// detector finds the face, the neutral frames calibrate, the jaw stays shut
// during them, and the mouth opening in the video raises jawOpen's weight
// above 0.5 (and the head's jaw with it, on the GPU path); off, every track
// of the stream ends and the indicator goes. Then a browser whose camera is
// refused (no fake UI, permission denied) gets the clear message.
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { execFileSync } from 'node:child_process';
import { check, closeChromium, JOB_TIMEOUT_MS, launchChromium, likenessBin, note, READY_TIMEOUT_MS, runAlone, SHOT_DIR, waitForState } from '../harness.mjs';
import { decodePng } from '../fixtures.mjs';

// Long phases: the detector's start and the screenshots are slow under
// SwiftShader, and the fake camera loops the file.
const FPS = 5, NEUTRAL_S = 30, OPEN_S = 20, SIZE = 320;


// A YUV4MPEG2 (4:2:0, BT.601 full range) stream of the PNG frames, each
// repeated `counts[i]` times.
function y4m(pngs, counts) {
  const frames = pngs.map((file) => {
    const { width: w, height: h, data } = decodePng(fs.readFileSync(file));
    const y = Buffer.alloc(w * h), u = Buffer.alloc((w / 2) * (h / 2)), v = Buffer.alloc((w / 2) * (h / 2));
    const rgb = (i) => [data[4 * i], data[4 * i + 1], data[4 * i + 2]];
    for (let i = 0; i < w * h; i++) {
      const [r, g, b] = rgb(i);
      y[i] = Math.round(0.299 * r + 0.587 * g + 0.114 * b);
    }
    for (let j = 0; j < h / 2; j++)
      for (let i = 0; i < w / 2; i++) {
        let r = 0, g = 0, b = 0;
        for (const [dx, dy] of [[0, 0], [1, 0], [0, 1], [1, 1]]) {
          const c = rgb((2 * j + dy) * w + 2 * i + dx);
          r += c[0] / 4; g += c[1] / 4; b += c[2] / 4;
        }
        u[j * (w / 2) + i] = Math.max(0, Math.min(255, Math.round(128 - 0.168736 * r - 0.331264 * g + 0.5 * b)));
        v[j * (w / 2) + i] = Math.max(0, Math.min(255, Math.round(128 + 0.5 * r - 0.418688 * g - 0.081312 * b)));
      }
    return { w, h, bytes: Buffer.concat([Buffer.from('FRAME\n'), y, u, v]) };
  });
  const parts = [Buffer.from(`YUV4MPEG2 W${frames[0].w} H${frames[0].h} F${FPS}:1 Ip A1:1 C420jpeg\n`)];
  frames.forEach((f, i) => { for (let k = 0; k < counts[i]; k++) parts.push(f.bytes); });
  return Buffer.concat(parts);
}

const followState = (page) => page.evaluate(() => {
  const f = window.likeness.follow;
  return { raw: f.raw, on: f.on, state: f.state, frames: f.frames, faces: f.faces, jaw: f.raw.jawOpen || 0, smoothJaw: f.weights.jawOpen || 0,
           message: f.message, checked: document.getElementById('follow-face').checked,
           indicator: !document.getElementById('camera-on').hidden, tracks: f.tracks(),
           headJaw: window.likeness.expressions.weights.jawOpen || 0,
           slider: (document.getElementById('expr-w-jawOpen') || {}).value, stats: document.getElementById('expr-stats').textContent, path: window.likeness.expressions.stats.path || null };
});

async function openProject(page, file) {
  await page.setInputFiles('#project-input', { name: 'head.likeness.glb', mimeType: 'model/gltf-binary', buffer: fs.readFileSync(file) });
  await page.waitForFunction(() => !!window.likeness.fit && document.body.dataset.state === 'done', null, { timeout: JOB_TIMEOUT_MS });
}

async function run(s) {
  const bin = likenessBin(s.webdir);
  if (!bin) {
    note('follow-face: skipped, no native likeness binary to make the head and the video (set LK_LIKENESS_BIN)');
    return;
  }
  const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'likeness-follow-'));
  for (const e of ['neutral', 'jawOpen'])
    execFileSync(bin, ['render', '--expression', e, '--view', 'front', '--face', '--size', String(SIZE), '--out', path.join(dir, e + '.png')]);
  const video = path.join(dir, 'face.y4m');
  fs.writeFileSync(video, y4m([path.join(dir, 'neutral.png'), path.join(dir, 'jawOpen.png')], [NEUTRAL_S * FPS, OPEN_S * FPS]));
  execFileSync(bin, ['synth-scan', '--seed', '2', '--points', '60000', '--out', path.join(dir, 'scan')]);
  execFileSync(bin, ['fit', '--scan', path.join(dir, 'scan', 'scan.ply'), '--out', path.join(dir, 'fit'), '--levels', '2']);
  const project = path.join(dir, 'fit', 'head.likeness.glb');

  const { origin } = await s.serve();
  const context = await launchChromium('follow', { width: 1280, height: 800 }, {
    args: ['--use-fake-device-for-media-stream', '--use-fake-ui-for-media-stream', `--use-file-for-fake-video-capture=${video}`],
  });
  s.watchRequests(context);
  try {
    const page = s.watch(await context.newPage());
    await page.goto(origin + '/index.html');
    check('the page starts (fake camera browser)', (await waitForState(page, ['ready', 'error'], READY_TIMEOUT_MS)) === 'ready');
    await openProject(page, project);
    await page.uncheck('#show-points');  // the face, not the scan's points over it
    await page.click('#expressions summary');
    await page.selectOption('#expr-group', 'jaw');  // jawOpen's slider follows too
    const off = await followState(page);
    check('Follow my face is off at start, the camera closed', !off.checked && !off.on && !off.indicator && off.tracks.length === 0,
          JSON.stringify(off));

    const tOn = Date.now();
    await page.check('#follow-face');
    await page.waitForFunction(() => ['calibrating', 'following', 'no-face', 'error'].includes(window.likeness.follow.state), null,
                               { timeout: JOB_TIMEOUT_MS });
    const opened = await followState(page);
    check('toggled on, the camera opens and the indicator shows', opened.on && opened.indicator &&
          opened.tracks.length === 1 && opened.tracks[0] === 'live', JSON.stringify(opened));
    // Calibrated on the neutral frames, then following.
    await page.waitForFunction(() => window.likeness.follow.state === 'following', null, { timeout: NEUTRAL_S * 1000 + 60000 });
    // The first frame after calibration, still neutral in the video: the jaw stays shut.
    const shut = await followState(page);
    const t0 = Date.now();
    check('the detector finds the face and calibrates on the neutral frames; the jaw stays shut then',
          shut.faces >= 8 && shut.jaw < 0.2,
          `${shut.faces} faces in ${shut.frames} frames, following ${((t0 - tOn) / 1000).toFixed(1)} s after the toggle; jawOpen ${shut.jaw.toFixed(3)}`);
    // The video's mouth opens (after NEUTRAL_S from its start): jawOpen rises.
    let peak = shut;
    while (Date.now() - t0 < (NEUTRAL_S + OPEN_S) * 1000 + 10000) {
      const f = await followState(page);
      if (f.jaw > peak.jaw) peak = f;
      if (f.jaw > 0.5 && f.headJaw > 0.3) break;
      await page.waitForTimeout(250);
    }
    if (SHOT_DIR) {
      // The panel first: the canvas' shot is slow under SwiftShader, and the video loops back to rest.
      await page.locator('#expr-controls').screenshot({ path: path.join(SHOT_DIR, 'page_follow_face_panel.png') });
      await page.locator('#canvas').screenshot({ path: path.join(SHOT_DIR, 'page_follow_face.png') });
    }
    check('the mouth opening in the video raises jawOpen above 0.5 and drives the head (GPU path); it does not read as a smile or a blink',
          peak.jaw > 0.5 && peak.headJaw > 0.3 && peak.path === 'gpu' && peak.raw.mouthSmileLeft < 0.3 && peak.raw.mouthSmileRight < 0.3 &&
          peak.raw.eyeBlinkLeft < 0.3 && peak.raw.eyeBlinkRight < 0.3,
          `jawOpen from the landmarks ${peak.jaw.toFixed(3)}, smoothed on the head ${peak.headJaw.toFixed(3)} (its slider ${peak.slider}), path ${peak.path}; ` +
          `${peak.faces} faces in ${peak.frames} frames; all the shapes then: ` +
          Object.entries(peak.raw).map(([k, v]) => k + ' ' + v.toFixed(2)).join(', '));

    await page.uncheck('#follow-face');
    await page.waitForTimeout(300);
    const stopped = await followState(page);
    const ended = await page.evaluate(() => window.likeness.follow.lastStream.getTracks().map((t) => t.readyState));
    check('toggled off, every track of the camera ends, the indicator goes and the head rests', !stopped.on &&
          stopped.state === 'off' && !stopped.indicator && ended.length > 0 && ended.every((r) => r === 'ended') && stopped.headJaw === 0,
          `${JSON.stringify(ended)}; ${stopped.message}`);
  } finally {
    await closeChromium(context);
  }

  // A browser that refuses the camera: a clear message, the toggle back off.
  const refused = await launchChromium('follow-refused', { width: 1280, height: 800 }, { args: ['--use-fake-device-for-media-stream'] });
  s.watchRequests(refused);
  try {
    await refused.clearPermissions();
    const page = s.watch(await refused.newPage());
    await page.goto(origin + '/index.html');
    await waitForState(page, ['ready', 'error'], READY_TIMEOUT_MS);
    await openProject(page, project);
    await page.click('#expressions summary');
    // Headless Chromium without the fake UI denies the prompt.
    await page.check('#follow-face');
    await page.waitForFunction(() => ['error', 'calibrating', 'following'].includes(window.likeness.follow.state), null, { timeout: 30000 });
    const f = await followState(page);
    check('a refused camera gives a clear message and the toggle goes back off', f.state === 'error' && !f.checked &&
          !f.indicator && /refused/.test(f.message), f.message);
  } finally {
    await closeChromium(refused);
    fs.rmSync(dir, { recursive: true, force: true });
  }
}

export const flow = { name: 'follow-face', title: 'Follow my face: the fake camera drives jawOpen', run };
runAlone(import.meta.url, flow);
