// Scans and bad input on the main page: a PLY point cloud is shown (green
// points); broken files (truncated, not a scan, 2^31 vertices, empty, and
// issue 36's OBJ index, PLY junk element, VTK count and NaN colour) give a
// visible error naming the file while the previous model stays; a worker
// dying mid-job is replaced; the viewer refuses malformed arrays; Cancel;
// a dropped file loads; an OBJ mesh after the errors; a PNG photo is checked
// and kept, a broken one is an error; the built-in sample when installed.
// Then a page started with small limits (?max_mb=1, display 5,000 points
// and 10 triangles): too large a file is refused, too large a cloud thinned,
// too large a mesh refused.
import fs from 'node:fs';
import path from 'node:path';
import { analyse, bannerText, canvasImage, check, cubeObj, differingFraction, hugeCountPly, JOB_TIMEOUT_MS, makePng, note,
         runAlone, setFile, settled, shot, state, torusPly, truncatedPly } from '../harness.mjs';

async function run(s) {
  const page = await s.page();
  await page.uncheck('#auto-fit');  // these are not heads: no automatic fit
  // A point cloud.
  const before = await canvasImage(page);
  const s1 = await setFile(page, 'torus.ply', torusPly(20000));
  const status1 = await page.textContent('#status');
  check('point cloud PLY leads to "done"', s1 === 'done', `state ${s1}; status "${status1.trim()}"`);
  check('status names the point count', /20,000 points/.test(status1));
  const points = await canvasImage(page);
  const pointStats = analyse(points);
  const pointDiff = differingFraction(before, points);
  check('canvas changes when the points are shown', pointDiff > 0.01, `${(100 * pointDiff).toFixed(1)}% of pixels changed`);
  check('green points are drawn', pointStats.greenFraction > 0.005, `${(100 * pointStats.greenFraction).toFixed(2)}% green pixels`);
  await shot(page, 'web_points.png');

  // Broken inputs: each gives "error" with a visible message naming the
  // file; the torus stays on screen.
  const broken = [
    ['truncated.ply', truncatedPly()],
    ['notes.txt', Buffer.from('These are my notes, not a scan.\nSecond line.\n')],
    ['huge_count.ply', hugeCountPly()],
    ['empty.ply', Buffer.alloc(0)],
    // Issue 36's classes 1-4, the reproducers of tests/io/test_untrusted_input.cpp's kind.
    ['index.obj', Buffer.from('v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -9223372036854775808\n')],
    ['junk.ply', Buffer.from('ply\nformat ascii 1.0\nelement junk 4611686018427387904\nelement vertex 3\n' +
                             'property float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n1 0 0\n0 1 0\n')],
    ['colors.vtk', Buffer.from('# vtk DataFile Version 3.0\nx\nASCII\nDATASET POLYDATA\nPOINTS 3 float\n' +
                               '0 0 0 1 0 0 0 1 0\nPOLYGONS 1 4\n3 0 1 2\nCELL_DATA 1000000000\nCOLOR_SCALARS c 3\n0 0 0\n')],
    ['nan.obj', Buffer.from('v 0 0 0 nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n')],
  ];
  for (const [name, bytes] of broken) {
    const t = Date.now();
    const sBad = await setFile(page, name, bytes);
    const msg = await bannerText(page);
    check(`${name} leads to "error" with a visible message`, sBad === 'error' && msg.includes(name),
          `state ${sBad} after ${Date.now() - t} ms; "${msg}"`);
    // Beside the file too: its row is marked and shows the reason in full.
    const row = await page.evaluate(() => {
      const li = document.querySelector('#file-list li:first-child');
      const reason = li && li.querySelector('.file-reason');
      return li ? { name: li.querySelector('.file-name').textContent, refused: li.classList.contains('refused'),
                    reason: reason ? reason.textContent : '', shown: !!(reason && reason.offsetHeight > 0) } : null;
    });
    check(`${name}: the reason is shown beside the file`,
          !!row && row.name === name && row.refused && row.shown && row.reason.length > 10 && msg.includes(row.reason.slice(0, 20)),
          JSON.stringify(row));
  }
  await shot(page, 'web_error.png');
  await page.evaluate(() => document.getElementById('file-list').scrollIntoView({ block: 'center' }));
  await shot(page, 'web_error_files.png');
  const afterErrors = await canvasImage(page);
  check('the previous model stays after errors', analyse(afterErrors).greenFraction > 0.5 * pointStats.greenFraction);

  // A worker that dies mid-job (here: a binding error from a malformed
  // message) fails that job with a message and is replaced.
  const crash = await page.evaluate(async () => {
    const old = window.likeness.worker;
    try {
      await window.likeness.runJob({ type: 'parse', name: 5, buffer: new ArrayBuffer(4) }, []);
      return { rejected: false };
    } catch (e) {
      return { rejected: true, message: e.message, replaced: window.likeness.worker !== old };
    }
  });
  check('a dying worker fails its job and is replaced', crash.rejected && crash.replaced && /restarted/.test(crash.message),
        JSON.stringify(crash));

  // The viewer's embind calls check what JS hands them.
  const bad = await page.evaluate(() => {
    const v = window.likeness.viewer, F = Float32Array, U = Uint32Array;
    return [
      v.show_mesh(new F([0, 0, 0]), new F(), new F(), new U([0, 1, 2])),
      v.show_mesh(new F([0, 0, 0, 1, 0, 0, 0, 1]), new F(), new F(), new U([0, 1, 2])),
      v.show_points(new F([0, NaN, 0]), new F(), new F()),
      v.show_points(new F([0, 0, 0]), new F([0, 0]), new F()),
      v.show_points(new F(), new F(), new F()),
    ];
  });
  check('the viewer refuses malformed arrays with messages', bad.every((m) => typeof m === 'string' && m.length > 0) &&
        /vertex 1 of 1/.test(bad[0]) && /multiple of 3/.test(bad[1]) && /NaN/.test(bad[2]) && /normals/.test(bad[3]),
        bad.join(' | '));
  check('... and keeps showing the previous model', analyse(await canvasImage(page)).greenFraction > 0.5 * pointStats.greenFraction);

  // Cancel: the running job is dropped (the worker is replaced), the page
  // goes back to what it showed, without an error.
  const cancelled = await page.evaluate(async () => {
    const old = window.likeness.worker;
    const job = window.likeness.runJob({ type: 'parse', name: 'x.ply', buffer: new ArrayBuffer(8) }, []);
    window.likeness.cancel();
    try { await job; return { rejected: false }; } catch (e) {
      return { rejected: true, cancelled: !!e.cancelled, replaced: window.likeness.worker !== old };
    }
  });
  check('cancel drops the running job and replaces the worker', cancelled.rejected && cancelled.cancelled && cancelled.replaced,
        JSON.stringify(cancelled));

  // Drag and drop: a file dropped on the drop zone loads like a chosen one.
  await page.evaluate((text) => {
    const dt = new DataTransfer();
    dt.items.add(new File([text], 'dropped.xyz'));
    const zone = document.getElementById('drop-zone');
    zone.dispatchEvent(new DragEvent('dragenter', { bubbles: true, cancelable: true, dataTransfer: dt }));
    zone.dispatchEvent(new DragEvent('drop', { bubbles: true, cancelable: true, dataTransfer: dt }));
  }, '0 0 0\n0.1 0 0\n0 0.1 0\n0 0 0.1\n');
  await settled(page);
  const statusDrop = await page.textContent('#status');
  check('a dropped XYZ file loads', (await state(page)) === 'done' && /dropped\.xyz: point cloud, 4 points/.test(statusDrop),
        `"${statusDrop.trim()}"`);

  // A good file after the errors.
  const s2 = await setFile(page, 'cube.obj', cubeObj());
  const status2 = await page.textContent('#status');
  check('a good OBJ loads after errors', s2 === 'done' && (await bannerText(page)) === '',
        `state ${s2}; status "${status2.trim()}"`);
  check('status names the cube\'s 8 vertices and 12 triangles', /8 vertices, 12 triangles/.test(status2));
  const cube = await canvasImage(page);
  check('the cube replaces the points', analyse(cube).greenFraction < 0.001 && analyse(cube).fgFraction > 0.03,
        `${(100 * analyse(cube).fgFraction).toFixed(1)}% foreground`);
  await shot(page, 'web_mesh.png');

  // Photos: decoded once in the worker, listed with their size; a broken
  // one is an error naming it.
  await page.setInputFiles('#file-input', [{ name: 'front.png', mimeType: 'image/png', buffer: makePng(6, 4) }]);
  await settled(page);
  const photoRow = await page.textContent('#file-list li:first-child');
  const photos = await page.evaluate(() => window.likeness.photos.map((p) => `${p.name} ${p.width}x${p.height}`));
  check('a PNG photo is checked and kept', /6×4 photo/.test(photoRow) && photos.join() === 'front.png 6x4' &&
        (await state(page)) === 'done', `"${photoRow}"; kept ${JSON.stringify(photos)}`);
  const sPhoto = await setFile(page, 'side.jpg', Buffer.concat([Buffer.from([0xff, 0xd8, 0xff, 0xe0]), Buffer.alloc(64, 7)]), 'image/jpeg');
  const msgPhoto = await bannerText(page);
  check('a broken photo leads to "error" naming it', sPhoto === 'error' && msgPhoto.includes('side.jpg'), `"${msgPhoto}"`);

  // The built-in sample, when scripts/demo has put it beside the page
  // (clicking it otherwise would log the 404 as a console error).
  if (fs.existsSync(path.join(s.webdir, 'sample', 'scan.ply'))) {
    await page.click('#btn-sample');
    await page.waitForFunction(() => document.body.dataset.state === 'error' ||
      (document.body.dataset.state === 'done' && window.likeness.model && window.likeness.model.name === 'sample_scan.ply'),
      null, { timeout: JOB_TIMEOUT_MS });
    const s5 = await state(page);
    check('"Try the sample" loads sample/scan.ply', s5 === 'done', `state ${s5}; status "${(await page.textContent('#status')).trim()}"`);
    await shot(page, 'web_sample.png');
  } else {
    note('"Try the sample" not exercised: no sample/scan.ply in WEBDIR (scripts/demo makes it)');
  }

  // The limits, on a page started with small ones: file size 1 MB,
  // display 5,000 points and 10 triangles.
  const page2 = await s.newPage('?max_mb=1&max_display_points=5000&max_display_triangles=10&autofit=0');
  const s3 = await setFile(page2, 'big.ply', Buffer.alloc(2 * 1024 * 1024, 32));
  const msg3 = await bannerText(page2);
  check('a file over the size limit is refused with a message', s3 === 'error' && /up to 1\.0 MB/.test(msg3), `"${msg3}"`);
  const s4 = await setFile(page2, 'torus.ply', torusPly(20000));
  const status4 = await page2.textContent('#status');
  check('... the page keeps working, and a large cloud is thinned for display', s4 === 'done' &&
        /20,000 points \(showing 1 in 4\)/.test(status4), `state ${s4}; "${status4.trim()}"`);
  const s5 = await setFile(page2, 'cube.obj', cubeObj());
  const msg5 = await bannerText(page2);
  check('a mesh over the display limit is refused with a message', s5 === 'error' && /up to 10\b/.test(msg5), `"${msg5}"`);
  await page2.close();
}

export const flow = { name: 'scan-load', title: 'scans, bad input, a dying worker, Cancel, drag and drop, photos, limits', run };
runAlone(import.meta.url, flow);
