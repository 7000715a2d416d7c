// The fitted head's checks (folds, self-intersections, the face's distance
// to the scan) as the page shows them: for the synthetic scan they must
// equal `likeness fit`'s report.json for the same bytes, and the panel's
// text must show each number; "Distance to scan" draws the finest level in
// its distance colours with a colour key. Then a real scan, Fran (face-only,
// turned; skipped when ../shared/data is absent): it fits, the page shows
// its checks and what the fit decided, the view looks at her face, and a
// second fit with the map on shows its own map.
import fs from 'node:fs';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { bannerText, canvasImage, check, JOB_TIMEOUT_MS, note, runAlone, setFile, settled, SHOT_DIR, state } from '../harness.mjs';
import { nativeFit } from '../synth_scan.mjs';
import { checksRunEarly, fittedHead } from './fit.mjs';

// The fitted head's checks on the page, once the worker has sent them (their
// start is checksRunEarly's): the worker's numbers must equal `likeness
// fit`'s report.json quality for the same scan bytes, and the panel's text
// must show each of them.
// exact: false only reports the native numbers beside the page's: the wasm
// fit of a real scan is not bit-identical to the native one (different libm
// and vector code; on fran_cut.vtk the alignment already ends 1.377 vs 1.360 %
// of the diagonal), so its crossing counts differ too; the synthetic scan's
// must be equal.
async function checksShown(page, label, bytes, name, webdir, exact = true) {
  await page.waitForFunction(() => window.likeness.fit && window.likeness.fit.quality, null, { timeout: JOB_TIMEOUT_MS });
  const shown = await page.evaluate(() => ({ q: window.likeness.fit.quality, text: document.getElementById('fit-quality').innerText }));
  const native = nativeFit(webdir, bytes, name);
  if (native.skip) {
    note('the checks are not compared with the native CLI: ' + native.skip);
    return shown.q;
  }
  const q = shown.q, n = native.quality || {};
  const pairs = (c) => c ? [c.total, c.lips, c.ears, c.eyeSockets !== undefined ? c.eyeSockets : c.eye_sockets, c.rest].join('/') : 'none';
  const page4 = [q.level, q.triangles, q.flipped, q.degenerate, pairs(q.crossings), pairs(q.smoothCrossings), q.controlCrossings].join(' ');
  const cli4 = [n.level, n.triangles, n.flipped, n.degenerate, pairs(n.self_intersecting_pairs), pairs(n.smooth_surface_pairs),
                n.control_mesh_pairs].join(' ');
  const fmt = (x) => Number(x).toLocaleString('en');
  const c = q.crossings || {}, sm = q.smoothCrossings || {};
  const inText = [`level ${q.level} (${fmt(q.triangles)} triangles)`,
    c.total ? `${fmt(c.total)} self-intersecting triangle pairs (lips ${fmt(c.lips)}, ears ${fmt(c.ears)}, eye sockets ${fmt(c.eyeSockets)}, elsewhere ${fmt(c.rest)})`
            : 'No self-intersections',
    sm.total ? `${fmt(sm.total)} pairs (lips ${fmt(sm.lips)}, ears ${fmt(sm.ears)}, eye sockets ${fmt(sm.eyeSockets)}, elsewhere ${fmt(sm.rest)})` : 'no self-intersections',
    q.flipped + q.degenerate ? `${fmt(q.flipped)} triangles turned over by the scan's detail, ${fmt(q.degenerate)} degenerate` : 'No folds',
    q.controlCrossings ? `crosses itself in ${fmt(q.controlCrossings)} triangle pairs` : 'does not cross itself'];
  const missing = inText.filter((t) => !shown.text.includes(t));
  if (!exact) {
    check(`${label}: the page shows every number of the worker's checks`, q.ok && missing.length === 0,
          `page ${page4}; checked in ${Math.round(q.checkMs)} ms` + (missing.length ? '; text lacks: ' + missing.join(' | ') : ''));
    note(`${label}: likeness fit (native) gives ${cli4}; the wasm fit differs slightly, so its counts do too`);
    // A scan that came as a mesh is also measured the other way round (the
    // face of the finest level to the scan's triangles), as likeness fit does.
    if (native.faceToScan) {
      const d = q.faceToScan, nd = native.faceToScan;
      const sentence = d ? `lies ${d.meanMm.toFixed(2)} mm from it on average` : '(no faceToScan)';
      check(`${label}: the face's distance to the scan's own triangles is shown, near the native CLI's`,
            !!d && d.to === 'triangles' && shown.text.includes(sentence) && d.vertices > 1000 && Math.abs(d.meanMm - 1e3 * nd.mean_m) < 0.25 * 1e3 * nd.mean_m,
            d ? `page: ${sentence}, p99 ${d.p99Mm.toFixed(2)} mm, ${d.vertices} vertices; likeness fit: ${(1e3 * nd.mean_m).toFixed(3)} mm`
              : 'the worker sent no faceToScan');
    }
    // Real scans may fit without a crossing (Fran has 0 pairs since e952a99),
    // so the wording for a head that crosses itself is checked on made-up counts.
    const made = { ...q, flipped: 3, degenerate: 1, controlCrossings: 2,
                   crossings: { total: 1234, lips: 1, ears: 33, eyeSockets: 45, rest: 1155 },
                   smoothCrossings: { total: 7, lips: 0, ears: 7, eyeSockets: 0, rest: 0 } };
    const madeText = await page.evaluate((m) => {
      window.likeness.showQuality(m);
      const text = document.getElementById('fit-quality').innerText;
      window.likeness.showQuality(window.likeness.fit.quality);
      return text;
    }, made);
    const expected = ['1,234 self-intersecting triangle pairs (lips 1, ears 33, eye sockets 45, elsewhere 1,155)',
      'The lips cross each other', 'At the ears', 'In the eye sockets: behind the lids', 'Elsewhere: small overlaps',
      '7 pairs (lips 0, ears 7, eye sockets 0, elsewhere 0)', 'the eye sockets 45',
      '3 triangles turned over by the scan\'s detail, 1 degenerate', 'crosses itself in 2 triangle pairs', 'Worth a look'];
    const lacking = expected.filter((t) => !madeText.includes(t));
    check(`${label}: a head that crosses itself is named so, with its counts by region`, lacking.length === 0,
          lacking.length ? 'text lacks: ' + lacking.join(' | ') : `${expected.length} phrases shown`);
    return q;
  }
  // The other direction, on a point cloud: the face to the scan's points'
  // local patches, as likeness fit prints it. The wasm fit is not bit for bit
  // the native one (libm): within 5 % (measured 2 %), as the stages' distances.
  if (native.faceToScan) {
    const d = q.faceToScan, nd = native.faceToScan;
    const sentence = d ? `points (a small surface fitted to each vertex's 16 nearest), where it was scanned: the face of level ${q.level} lies ${d.meanMm.toFixed(2)} mm from it on average` : '(no faceToScan)';
    check(`${label}: the face's distance to the scan's points is shown, near the native CLI's`,
          !!d && d.to === 'points' && nd.to === 'points' && shown.text.includes(sentence) &&
          Math.abs(d.vertices - nd.vertices) <= 0.01 * nd.vertices && Math.abs(d.meanMm - 1e3 * nd.mean_m) <= 0.05 * 1e3 * nd.mean_m,
          d ? `page: ${d.meanMm.toFixed(4)} mm over ${d.vertices} vertices, p99 ${d.p99Mm.toFixed(2)} mm, max ${d.maxMm.toFixed(2)} mm; ` +
              `likeness fit: ${(1e3 * nd.mean_m).toFixed(4)} mm over ${nd.vertices}`
            : 'the worker sent no faceToScan');
  }
  check(`${label}: the checks the page shows equal the native CLI's for the same scan`,
        q.ok && page4 === cli4 && missing.length === 0,
        `page ${page4} vs likeness fit ${cli4} (level, triangles, turned over, degenerate, pairs total/lips/ears/eye sockets/rest, smooth, control); ` +
        `checked in ${Math.round(q.checkMs)} ms` + (missing.length ? '; text lacks: ' + missing.join(' | ') : ''));
  return q;
}

async function run(s) {
  const { page, synth, fit } = await fittedHead(s);
  if (!fit) return;
  await checksShown(page, 'synthetic scan', synth.bytes, 'synthetic_head.ply', s.webdir);
  // The checks' distance map: "Distance to scan" turns on with them and
  // draws the finest level in its colours; another level says it has none.
  {
    const enabled = await page.evaluate(() => !document.getElementById('show-distance').disabled);
    await page.uncheck('#show-points');
    const plain = await canvasImage(page);
    await page.check('#show-points');
    await page.check('#show-distance');  // turns the scan points off: they would hide the colours
    await page.evaluate(() => document.activeElement.blur());
    const pointsOff = await page.evaluate(() => !document.getElementById('show-points').checked);
    const legendOn = await page.evaluate(() => !document.getElementById('distance-legend').hidden);
    const mapped = await canvasImage(page);
    const mapStatus = await page.evaluate(() => document.getElementById('status').textContent);
    // Blue-grey (unmeasured: the scalp, the neck) is a colour the skin never has.
    const blueGrey = (img) => {
      let n = 0;
      for (let i = 0; i < img.data.length; i += 4)
        if (img.data[i + 2] > img.data[i] + 30 && img.data[i + 2] > 90) n++;
      return n;
    };
    const before = blueGrey(plain), after = blueGrey(mapped);
    check('the checks turn on "Distance to scan": level 3 drawn in its distance colours, blue-grey where not measured, with its colour key',
          enabled && pointsOff && legendOn && /coloured by its distance to the scan/.test(mapStatus) && after > 5000 && after > 20 * (before + 1),
          `enabled ${enabled}, scan points turned off ${pointsOff}, key shown ${legendOn}; blue-grey pixels ${before} -> ${after}; status: ${mapStatus}`);
    if (SHOT_DIR) await page.screenshot({ path: path.join(SHOT_DIR, 'web_distance_map.png') });
    await page.selectOption('#level', '2');
    const level2Status = await page.evaluate(() => document.getElementById('status').textContent);
    const legendOnLevel2 = await page.evaluate(() => !document.getElementById('distance-legend').hidden);
    check('on another level the page says the distance map is of the finest (and hides the colour key)',
          /the distance map is of level 3/.test(level2Status) && !legendOnLevel2, `${level2Status}; key shown ${legendOnLevel2}`);
    await page.selectOption('#level', '3');
    await page.uncheck('#show-distance');
    const legendAfter = await page.evaluate(() => !document.getElementById('distance-legend').hidden);
    check('turning "Distance to scan" off hides the colour key', !legendAfter, `key shown ${legendAfter}`);
    await page.check('#show-points');
    await page.evaluate(() => document.activeElement.blur());
  }
  // A real scan whose fitted head does cross itself (Fran: face-only,
  // eye rims and brow): the page must show non-zero counts in full.
  const fran = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '../../../../shared/data/head_scans/fran_cyberware/fran_cut.vtk');
  if (fs.existsSync(fran)) {
    const pageFran = await s.newPage('?autofit=0');
    try {
      const franBytes = fs.readFileSync(fran);
      const sFran = await setFile(pageFran, 'fran_cut.vtk', franBytes);
      await pageFran.click('#btn-fit');
      await settled(pageFran);
      if (check('the real scan fran_cut.vtk fits in the page', sFran === 'done' && (await state(pageFran)) === 'done',
                'state ' + (await state(pageFran)) + ' ' + await bannerText(pageFran))) {
        await checksRunEarly(pageFran, 'fran_cut.vtk');
        await checksShown(pageFran, 'fran_cut.vtk', franBytes, 'fran_cut.vtk', s.webdir, false);
        // Fran faces about (0.74, 0, -0.68), not +z: the fit turns her and
        // says so, and that she is a face-only capture, as the CLI does.
        const notes = await pageFran.evaluate(() => [...document.querySelectorAll('#fit-notes li')].map((li) => li.textContent));
        check('the page shows what the fit decided about the real scan (turned, face-only)',
              notes.some((n) => /seems to face/.test(n)) && notes.some((n) => /face-only scan/.test(n)) &&
              !(await pageFran.isHidden('#fit-notes')), JSON.stringify(notes).slice(0, 300));
        // The view then looks at her face from its three-quarter side
        // (cos 35 deg cos 8 deg = 0.81 along her facing), not from the
        // world's, which sees her cheek (-0.04), and "Reset view" keeps it.
        const facingDot = () => pageFran.evaluate(() => {
          const d = window.likeness.viewer.view_direction(), f = window.likeness.fit.headFacing;
          return (d[0] * f[0] + d[1] * f[1] + d[2] * f[2]) / Math.hypot(...f);
        });
        const dotFit = await facingDot();
        await pageFran.evaluate(() => window.likeness.viewer.orbit(800, 0));
        const dotTurned = await facingDot();
        await pageFran.click('#btn-reset');
        const dotReset = await facingDot();
        check('after the fit the view looks at the turned scan\'s face; Reset view goes back to it',
              dotFit > 0.78 && dotReset > 0.78 && dotTurned < 0.6,
              `view . facing: after the fit ${dotFit.toFixed(3)}, turned ${dotTurned.toFixed(3)}, reset ${dotReset.toFixed(3)}`);
        if (SHOT_DIR) {  // the Pipeline card with the checks (docs/images/web_fit_checks.png)
          // The side panel scrolls within the window: a tall window
          // shows the whole card (an element screenshot of its hidden
          // part came out black).
          const size = pageFran.viewportSize();
          await pageFran.setViewportSize({ width: size.width, height: 2400 });
          await pageFran.locator('.card', { has: pageFran.locator('#stages') })
            .screenshot({ path: path.join(SHOT_DIR, 'web_fit_checks.png') });
          await pageFran.setViewportSize(size);
        }
        // Fitting again with "Distance to scan" on: the new fit shows
        // before its checks are in (no map yet), then with its map.
        await pageFran.check('#show-distance');
        await pageFran.click('#btn-fit');
        await settled(pageFran);
        const again = await state(pageFran);
        let mapAgain = '';
        if (again === 'done') {
          await pageFran.waitForFunction(() => window.likeness.fit && window.likeness.fit.quality, null, { timeout: JOB_TIMEOUT_MS });
          mapAgain = await pageFran.evaluate(() => document.getElementById('status').textContent);
        }
        check('a second fit with "Distance to scan" on reaches "done", then shows its own map',
              again === 'done' && /coloured by its distance to the scan/.test(mapAgain),
              `state ${again}; status: ${mapAgain || await bannerText(pageFran)}`);
      }
    } finally {
      await pageFran.close();
    }
  } else {
    note('the checks on a real scan are skipped: ../shared/data/head_scans/fran_cyberware/fran_cut.vtk absent');
  }
}

export const flow = { name: 'fit-checks', title: 'the fitted head\'s checks and distance map; the real scan Fran', run };
runAlone(import.meta.url, flow);
