// Animation of the fitted head (the worker's local update, one pose per
// frame): frames advance and the head moves, unchecking Animate stops it.
// Then adaptive detail while animating, with a budget no frame can meet.
import fs from 'node:fs';
import { bannerText, canvasImage, check, differingFraction, JOB_TIMEOUT_MS, runAlone, shot } from '../harness.mjs';
import { fittedHead } from './fit.mjs';

// Adaptive detail while animating, with a budget no frame can meet (1 ms):
// the page steps down to the ladder's last step (level 1 at half the
// drawing-buffer resolution) and says so, export still writes the chosen
// level, stopping brings back the chosen level at full resolution (same
// image as before the animation), and "Full detail while animating" turns it
// off, also mid-animation.
async function adaptiveDetail(page, rest, fit, downloads) {
  const fullWidth = await page.evaluate(() => document.getElementById('canvas').width);
  // Read after two animation frames: the viewer sizes the drawing buffer in its next frame.
  const adaptive = () => page.evaluate(async () => {
    await new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r)));
    const a = window.likeness.animation, ad = a.adaptive;
    return { step: ad.step, last: ad.ladder.length - 1, level: ad.level, scale: ad.scale, running: a.running,
             width: document.getElementById('canvas').width, text: document.getElementById('anim-stats').textContent,
             select: document.getElementById('level').value, status: document.getElementById('status').textContent.trim() };
  });
  await page.evaluate(() => { window.likeness.animation.adaptive.budgetMs = 1; });
  await page.check('#animate');
  await page.waitForFunction(() => { const ad = window.likeness.animation.adaptive;
    return ad.ladder.length && ad.step === ad.ladder.length - 1 && /level 1 while moving/.test(document.getElementById('anim-stats').textContent); },
  null, { timeout: 30000 }).catch(() => {});
  await page.waitForTimeout(500);
  const down = await adaptive();
  check('with a budget no frame meets, the animation steps down to level 1 at half resolution and says so',
        down.running && down.step === down.last && down.level === 1 && down.scale === 0.5 &&
        Math.abs(down.width - fullWidth / 2) <= 1 && /level 1 while moving · 50 % resolution/.test(down.text) && down.select === '3',
        `step ${down.step}/${down.last}, level ${down.level}, scale ${down.scale}, canvas ${fullWidth} -> ${down.width}, "${down.text}", select ${down.select}`);
  // Export while moving on level 1: the file is the chosen level 3.
  const before = downloads.length;
  const handed = await page.evaluate(() => window.likeness.downloads.length);  // before the click: the export may be quick
  await page.click('#btn-export-ply');
  await page.waitForFunction((n) => window.likeness.downloads.length > n, handed, { timeout: JOB_TIMEOUT_MS });
  await page.waitForTimeout(300);
  const ply = downloads.length > before ? fs.readFileSync(await downloads[downloads.length - 1].path()) : null;
  check('... export while stepped down still writes the chosen level', !!ply &&
        new RegExp('element vertex ' + fit.levels[2] + '\\b').test(ply.toString('latin1', 0, 400)),
        ply ? /element vertex \d+/.exec(ply.toString('latin1', 0, 400))[0] + ' for level 3 ' + fit.levels[2] : 'no download');
  await page.uncheck('#animate');
  await page.waitForTimeout(1500);  // the rest pose comes back from the worker
  const stopped = await adaptive();
  const restAgain = await canvasImage(page);
  const restDiff = differingFraction(rest, restAgain);
  check('stopping restores the chosen level at full resolution (the rest image as before)', !stopped.running &&
        stopped.level === null && stopped.scale === 1 && stopped.width === fullWidth &&
        stopped.status.includes('level 3 (' + fit.levels[2].toLocaleString('en') + ' vertices') && restDiff < 0.002,
        `canvas ${stopped.width}, "${stopped.status}", ${(100 * restDiff).toFixed(3)}% of pixels differ from before`);
  // Stopped in the middle of a step: the first level change is decided, its
  // pose is still in the worker; Animate goes off in the same task. The late
  // pose must not land, and the chosen level comes back at full resolution.
  await page.check('#full-detail');  // forgets where the last run settled: start at full detail
  await page.uncheck('#full-detail');
  await page.check('#animate');
  const midStep = await page.evaluate(() => new Promise((resolve) => {
    const ad = window.likeness.animation.adaptive;
    const t0 = performance.now();
    const poll = () => {
      if (ad.step >= 1 || performance.now() - t0 > 30000) {
        const step = ad.step, level = ad.level;
        const box = document.getElementById('animate');
        box.checked = false;
        box.dispatchEvent(new Event('change'));
        resolve({ step, level });
      } else setTimeout(poll, 0);
    };
    poll();
  }));
  await page.waitForTimeout(2000);
  const afterMid = await adaptive();
  const midImage = await canvasImage(page);
  const midDiff = differingFraction(rest, midImage);
  check('stopping right after a step down leaves nothing half-done (level 3, full resolution, rest image)',
        midStep.step === 1 && midStep.level === 2 && !afterMid.running && afterMid.width === fullWidth && afterMid.level === null &&
        afterMid.status.includes('level 3 (' + fit.levels[2].toLocaleString('en') + ' vertices') && midDiff < 0.002 &&
        (await bannerText(page)) === '',
        `stopped at step ${midStep.step} (level ${midStep.level}); canvas ${afterMid.width}, "${afterMid.status}", ` +
        `${(100 * midDiff).toFixed(3)}% of pixels differ from the rest image`);
  // The toggle: turned on mid-animation it puts full detail back at once and keeps it.
  await page.check('#animate');
  await page.waitForFunction(() => window.likeness.animation.adaptive.step > 0, null, { timeout: 30000 }).catch(() => {});
  const stepped = await adaptive();
  await page.check('#full-detail');
  const atOnce = await adaptive();
  await page.waitForTimeout(3000);
  const later = await adaptive();
  check('"Full detail while animating" turns the adaptation off (at once, and it stays off)',
        stepped.step > 0 && atOnce.step === 0 && atOnce.width === fullWidth && atOnce.level === 3 &&
        later.running && later.step === 0 && later.width === fullWidth && later.level === 3 && /full detail/.test(later.text) &&
        !/while moving|resolution/.test(later.text),
        `step ${stepped.step} -> ${atOnce.step}, 3 s later step ${later.step}, canvas ${later.width}, "${later.text}"`);
  await page.uncheck('#animate');
  await page.uncheck('#full-detail');
  await page.evaluate(() => { window.likeness.animation.adaptive.budgetMs = 1000 / 15; });
  await page.waitForTimeout(1000);
}

async function run(s) {
  const { page, fit } = await fittedHead(s);
  if (!fit) return;
  const downloads = [];
  const onDownload = (d) => downloads.push(d);
  page.on('download', onDownload);
  // Animation: frames advance and the head moves.
  const rest = await canvasImage(page);
  await page.check('#animate');
  await page.waitForTimeout(1500);
  const f1 = await page.evaluate(() => window.likeness.animation.frames);
  // The motion is periodic (2 s), so one screenshot may catch the rest
  // pose: keep the largest change over several samples across a period.
  let movedMost = -1;
  for (let i = 0; i < 6; ++i) {
    await page.waitForTimeout(400);
    const img = await canvasImage(page);
    const d = differingFraction(rest, img);
    movedMost = Math.max(movedMost, d);
  }
  const anim = await page.evaluate(() => Object.assign({}, window.likeness.animation, { text: document.getElementById('anim-stats').textContent }));
  await shot(page, 'web_fit_animate.png');
  check('the animation advances frames and moves the head', anim.frames > f1 && f1 > 0 && movedMost > 0.002 &&
        /fps · (.* · )?update/.test(anim.text), `frames ${f1} -> ${anim.frames}, "${anim.text}", ${(100 * movedMost).toFixed(2)}% changed at most`);
  await page.uncheck('#animate');
  await page.waitForTimeout(300);
  const f2 = await page.evaluate(() => window.likeness.animation.frames);
  await page.waitForTimeout(600);
  check('unchecking Animate stops it', (await page.evaluate(() => window.likeness.animation.frames)) === f2);
  await adaptiveDetail(page, rest, fit, downloads);
  page.off('download', onDownload);
}

export const flow = { name: 'animation', title: 'animation, and adaptive detail while animating', run };
runAlone(import.meta.url, flow);
