// Last of the fit flows, since it ends the fitted head: Cancel mid-fit goes
// back to "done" without an error, and the head shown before stays (the
// stopped worker took it with it; keep.js puts its kept copy into the new
// worker, so it still exports); a flat plane is refused as not a head with
// a visible message, and the page keeps working.
import { bannerText, check, cubeObj, JOB_TIMEOUT_MS, planePly, runAlone, setFile, settled } from '../harness.mjs';
import { fittedHead } from './fit.mjs';

async function run(s) {
  const { page, fit, skip } = await fittedHead(s);
  if (skip) return;
  // Cancel mid-fit: back to "done" without an error; the head from before
  // stays and exports.
  if (fit) {
    await page.click('#btn-fit');
    await page.waitForFunction(() => document.querySelector('#stages li.active'), null, { timeout: JOB_TIMEOUT_MS });
    await page.click('#btn-cancel');
    await settled(page);
    const after = await page.evaluate(() => ({ state: document.body.dataset.state,
      tags: Array.from(document.querySelectorAll('#stages li')).slice(1, 5).map((li) => li.querySelector('.stage-tag').textContent),
      exportOff: document.getElementById('btn-export-obj').disabled, fit: !!window.likeness.fit }));
    check('Cancel stops a running fit without an error; the head from before stays', after.state === 'done' &&
          (await bannerText(page)) === '' && after.tags.every((t) => t === 'cancelled') && !after.exportOff && after.fit,
          JSON.stringify(after));
  }
  // A flat plane: NotAHead, shown as an error; the page keeps working.
  await page.check('#auto-fit');
  const sPlane = await setFile(page, 'plane.ply', planePly());
  const msgPlane = await bannerText(page);
  check('a flat plane is refused as not a head, with a visible message', sPlane === 'error' && /not look like a head/.test(msgPlane),
        `state ${sPlane}; "${msgPlane}"`);
  await page.uncheck('#auto-fit');
  const sAfter = await setFile(page, 'cube.obj', cubeObj());
  check('... and the page still works afterwards', sAfter === 'done', `state ${sAfter}`);
}

export const flow = { name: 'fit-cancel', title: 'Cancel mid-fit; a plane refused as not a head', run };
runAlone(import.meta.url, flow);
