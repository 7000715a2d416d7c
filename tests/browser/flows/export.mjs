// Export and downloads of the fitted head ("Head (GLB)" too, checked by the
// Khronos validator): "Head (OBJ)" gives the chosen
// level 3 and the control mesh with their vertex counts, "Head (PLY)" level
// 3, and "Distance map (PLY)" level 3 coloured by distance, whose coloured
// vertices are exactly those the checks measured.
import fs from 'node:fs';
import { createRequire } from 'node:module';
import { check, JOB_TIMEOUT_MS, runAlone } from '../harness.mjs';
import { fittedHead } from './fit.mjs';

async function run(s) {
  const { page, fit } = await fittedHead(s);
  if (!fit) return;
  // The downloads the page handed out before (other flows' exports).
  const handed = await page.evaluate(() => window.likeness.downloads.length);
  // Export: level 3 OBJ plus the control mesh, then a PLY.
  const downloads = [];
  const onDownload = (d) => downloads.push(d);
  page.on('download', onDownload);
  await page.click('#btn-export-obj');
  await page.waitForFunction((n) => window.likeness.downloads.length >= n + 2, handed, { timeout: JOB_TIMEOUT_MS });
  await page.click('#btn-export-ply');
  await page.waitForFunction((n) => window.likeness.downloads.length >= n + 3, handed, { timeout: JOB_TIMEOUT_MS });
  await new Promise((r) => setTimeout(r, 500));
  const files = {};
  for (const d of downloads) files[d.suggestedFilename()] = fs.readFileSync(await d.path());
  const obj = files['synthetic_head_head_level3.obj'], ctl = files['synthetic_head_head_control.obj'];
  const ply = files['synthetic_head_head_level3.ply'];
  const vCount = (b) => b ? b.toString().split('\n').filter((l) => l.startsWith('v ')).length : 0;
  check('"Head (OBJ)" downloads level 3 and the control mesh', vCount(obj) === fit.levels[2] && vCount(ctl) === fit.control,
        `files [${Object.keys(files)}], ${vCount(obj)} and ${vCount(ctl)} vertices`);
  check('"Head (PLY)" downloads a PLY of level 3', !!ply && ply.toString('latin1', 0, 3) === 'ply' &&
        new RegExp('element vertex ' + fit.levels[2] + '\\b').test(ply.toString('latin1', 0, 400)), ply ? `${ply.length} bytes` : 'missing');
  // "Distance map (PLY)": level 3 with the map's colours; the vertices
  // not drawn blue-grey are exactly those the checks measured.
  {
    await page.waitForFunction(() => window.likeness.fit.quality, null, { timeout: JOB_TIMEOUT_MS });  // the checks' map
    const measured = await page.evaluate(() => window.likeness.fit.quality.faceToScan.vertices);
    await page.click('#btn-export-map');
    await page.waitForFunction((n) => window.likeness.downloads.length >= n + 4, handed, { timeout: JOB_TIMEOUT_MS });
    await new Promise((r) => setTimeout(r, 500));
    const mapFile = downloads.find((d) => d.suggestedFilename() === 'synthetic_head_head_distance_map.ply');
    const map = mapFile ? fs.readFileSync(await mapFile.path()) : null;
    let detail = 'missing', ok = false;
    if (map) {
      const head = map.toString('latin1', 0, 600);
      const end = head.indexOf('end_header\n') + 11;
      const stride = 15;  // float x y z, uchar r g b
      let notGrey = 0;
      for (let k = 0; k < fit.levels[2]; ++k) {
        const o = end + k * stride + 12;
        if (!(map[o + 2] > map[o] + 30)) notGrey++;
      }
      ok = new RegExp('element vertex ' + fit.levels[2] + '\\b').test(head) && /property float x/.test(head) &&
           /property uchar red/.test(head) && end > 11 && notGrey === measured && measured > 1000;
      detail = `${map.length} bytes; ${notGrey} coloured vertices, ${measured} measured by the checks`;
    }
    check('"Distance map (PLY)" downloads level 3 coloured by distance, measured vertices exactly', ok, detail);
  }
  // "Head (GLB)": the chosen level (3) for avatar tools, valid for the
  // Khronos validator, with the parts' nodes and the clips (core/anim/clips.h),
  // and the words typed beside Talk as a "Say" animation.
  {
    await page.evaluate(() => { document.getElementById('say-text').value = 'hello there'; });
    await page.click('#btn-export-glb');
    await page.waitForFunction((n) => window.likeness.downloads.length >= n + 5, handed, { timeout: JOB_TIMEOUT_MS });
    await new Promise((r) => setTimeout(r, 500));
    const glbFile = downloads.find((d) => d.suggestedFilename() === 'synthetic_head_head_level3.glb');
    const glb = glbFile ? fs.readFileSync(await glbFile.path()) : null;
    let detail = 'missing', ok = false;
    if (glb) {
      const v = await createRequire(import.meta.url)('gltf-validator').validateBytes(new Uint8Array(glb));
      const json = JSON.parse(glb.toString('utf8', 20, 20 + glb.readUInt32LE(12)));
      const names = json.nodes.map((n) => n.name);
      const head = json.accessors[json.meshes[json.nodes[names.indexOf('HeadMesh')].mesh].primitives[0].attributes.POSITION].count;
      const clips = (json.animations || []).map((a) => a.name);
      ok = v.issues.numErrors === 0 && head === fit.levels[2] && ['Neck', 'LeftEye', 'RightEye', 'Jaw', 'Tongue'].every((n) => names.includes(n)) &&
        clips.join(' ') === 'Talk Blink Gaze Say';
      detail = `${glb.length} bytes; validator ${v.issues.numErrors} errors, ${v.issues.numWarnings} warnings; head ${head} vertices; nodes ${names.join(' ')}; ` +
        `animations ${clips.join(' ') || 'none'}`;
    }
    check('"Head (GLB)" downloads level 3 with eyes, teeth and tongue and the Talk, Blink and Gaze animations, and Say for the words typed beside Talk, valid glTF', ok, detail);
    await page.evaluate(() => { document.getElementById('say-text').value = ''; });
  }
  page.off('download', onDownload);
}

export const flow = { name: 'export', title: 'OBJ, PLY and distance-map downloads of the fitted head', run };
runAlone(import.meta.url, flow);
