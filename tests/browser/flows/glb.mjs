// The GLB export read by the tools people use (issue 38): a textured head
// project is made by the native CLI (synth-scan 20k points, fit --levels 2
// --project, synthetic photos, texture --project-out; skipped with a note
// without the CLI), exported with `likeness project export --format glb`,
// then (1) the Khronos glTF-Validator (npm gltf-validator) finds no error,
// and (2) three.js's GLTFLoader (npm three) loads it in Chromium on a test
// page served from the page's own origin: the node names (Neck, Head, eyes,
// Jaw, teeth, tongue), the head's vertex count, a textured skin, and a
// WebGL render that shows the head; its morphTargetDictionary holds every
// expression, ARKit blendshape (Apple's names) and viseme of the muscle
// layer, and jawOpen and smile at weight 1 each change the render; its Talk
// animation played by three.js's AnimationMixer gives the head the
// sequence's weights at sampled times, and its Gaze animation turns the eye
// bones; the tongue's tongueOut target pushes
// its tip out; the file at level 2 with all of them and the textures is
// under 8 MB.
import { execFileSync } from 'node:child_process';
import fs from 'node:fs';
import { createRequire } from 'node:module';
import os from 'node:os';
import path from 'node:path';
import { check, likenessBin, note, runAlone, shot } from '../harness.mjs';

const require = createRequire(import.meta.url);

// The names avatar tools look up (../shared/FACE_NAMES.md), spelled here
// independently of core/anim/face_shapes.cpp so a misspelling there fails.
const ARKIT = ['eyeBlinkLeft', 'eyeLookDownLeft', 'eyeLookInLeft', 'eyeLookOutLeft', 'eyeLookUpLeft', 'eyeSquintLeft', 'eyeWideLeft',
  'eyeBlinkRight', 'eyeLookDownRight', 'eyeLookInRight', 'eyeLookOutRight', 'eyeLookUpRight', 'eyeSquintRight', 'eyeWideRight',
  'jawForward', 'jawLeft', 'jawRight', 'jawOpen', 'mouthClose', 'mouthFunnel', 'mouthPucker', 'mouthLeft', 'mouthRight',
  'mouthSmileLeft', 'mouthSmileRight', 'mouthFrownLeft', 'mouthFrownRight', 'mouthDimpleLeft', 'mouthDimpleRight',
  'mouthStretchLeft', 'mouthStretchRight', 'mouthRollLower', 'mouthRollUpper', 'mouthShrugLower', 'mouthShrugUpper',
  'mouthPressLeft', 'mouthPressRight', 'mouthLowerDownLeft', 'mouthLowerDownRight', 'mouthUpperUpLeft', 'mouthUpperUpRight',
  'browDownLeft', 'browDownRight', 'browInnerUp', 'browOuterUpLeft', 'browOuterUpRight', 'cheekPuff', 'cheekSquintLeft',
  'cheekSquintRight', 'noseSneerLeft', 'noseSneerRight', 'tongueOut'];
const VISEMES = ['sil', 'PP', 'FF', 'TH', 'DD', 'kk', 'CH', 'SS', 'nn', 'RR', 'aa', 'E', 'I', 'O', 'U'].map((v) => 'viseme_' + v);
const EXPRESSIONS = ['neutral', 'smile', 'openMouth', 'surprise', 'anger', 'sadness', 'disgust', 'fear', 'blink', 'wink'];
const ALL_SHAPES = [...EXPRESSIONS, ...ARKIT, ...VISEMES];

// A textured head project and its GLB, made by the CLI: {glb, report} or {skip}.
function makeGlb(webdir) {
  const bin = likenessBin(webdir);
  if (!bin) return { skip: 'no native likeness binary (set LK_LIKENESS_BIN)' };
  const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'likeness-glb-'));
  const run = (...args) => execFileSync(bin, args, { cwd: dir, stdio: 'pipe' }).toString();
  try {
    run('synth-scan', '--seed', '3', '--points', '20000', '--out', '.');
    run('fit', '--scan', 'scan.ply', '--out', 'fit', '--levels', '2', '--project', 'head.likeness.glb');
    run('texture', '--project', 'head.likeness.glb', '--make-synthetic', 'photos', '--photo-width', '480', '--photo-height', '360');
    run('texture', '--project', 'head.likeness.glb', '--photos', 'photos/photo0.png', 'photos/photo1.png', 'photos/photo2.png',
        '--points', 'photos/points0.txt', 'photos/points1.txt', 'photos/points2.txt', '--out', 'tex', '--size', '512',
        '--project-out', 'textured.likeness.glb');
    const report = run('project', 'export', 'textured.likeness.glb', '--format', 'glb', '--out', 'head.glb').trim();
    return { glb: fs.readFileSync(path.join(dir, 'head.glb')), report };
  } catch (e) {
    return { skip: 'the CLI could not make the GLB: ' + String(e.stderr || e.message).split('\n')[0] };
  } finally {
    fs.rmSync(dir, { recursive: true, force: true });
  }
}

async function run(s) {
  const made = makeGlb(s.webdir);
  if (made.skip) {
    note('the GLB is not exercised: ' + made.skip);
    return;
  }
  note(made.report);
  // (1) The Khronos validator.
  const validator = require('gltf-validator');
  const v = await validator.validateBytes(new Uint8Array(made.glb), { maxIssues: 200 });
  const issues = v.issues;
  const errors = issues.messages.filter((m) => m.severity === 0).map((m) => `${m.code} ${m.pointer || ''}`);
  check('the Khronos glTF-Validator finds no error and no warning in the GLB', issues.numErrors === 0 && issues.numWarnings === 0,
        `${issues.numErrors} errors, ${issues.numWarnings} warnings, ${issues.numInfos} infos${errors.length ? ': ' + errors.slice(0, 5).join(', ') : ''}; ` +
        `${v.info.drawCallCount} draw calls, ${v.info.totalVertexCount} vertices, ${v.info.totalTriangleCount} triangles, ` +
        `${(made.glb.length / 1048576).toFixed(2)} MB`);

  // (2) three.js in Chromium, on a test page of the page's own origin (routes:
  // the test page, three's modules and the GLB are served by the test itself).
  const page = s.watch(await (await s.context()).newPage());
  const three = path.dirname(path.dirname(require.resolve('three')));  // node_modules/three (its main is build/three.cjs)
  await page.route('**/__glb_test/**', (r) => {
    const url = new URL(r.request().url());
    const rel = url.pathname.replace(/^\/__glb_test\//, '');
    if (rel === 'index.html') {
      return r.fulfill({ contentType: 'text/html', body: `<!doctype html><meta charset="utf-8"><body>
<script type="importmap">{"imports": {"three": "./three/build/three.module.js", "three/addons/": "./three/examples/jsm/"}}</script>
<canvas id="c" width="256" height="256" style="width:512px;height:512px"></canvas>
<script type="module">
import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
window.result = (async () => {
  const gltf = await new GLTFLoader().loadAsync('./head.glb');
  const names = []; let headVertices = 0, meshes = 0, skinTextured = false, head = null;
  gltf.scene.traverse((o) => {
    names.push(o.name);
    if (o.isMesh) meshes++;
    if (o.isMesh && o.name === 'HeadMesh') { head = o; headVertices = o.geometry.attributes.position.count; skinTextured = !!o.material.map; }
  });
  const renderer = new THREE.WebGLRenderer({ canvas: document.getElementById('c'), preserveDrawingBuffer: true });
  const scene = new THREE.Scene(); scene.background = new THREE.Color(0, 0, 0);
  scene.add(gltf.scene); scene.add(new THREE.AmbientLight(0xffffff, 2));
  const box = new THREE.Box3().setFromObject(gltf.scene), c = box.getCenter(new THREE.Vector3()), size = box.getSize(new THREE.Vector3()).length();
  const camera = new THREE.PerspectiveCamera(30, 1, size / 100, size * 10); camera.position.set(c.x, c.y, c.z + 2.2 * size); camera.lookAt(c);
  const gl = renderer.getContext();
  const draw = () => { renderer.render(scene, camera); const px = new Uint8Array(256 * 256 * 4); gl.readPixels(0, 0, 256, 256, gl.RGBA, gl.UNSIGNED_BYTE, px); return px; };
  const rest = draw();
  let lit = 0; for (let i = 0; i < rest.length; i += 4) if (rest[i] + rest[i + 1] + rest[i + 2] > 30) lit++;
  // jawOpen, then smile, at full weight: pixels change.
  const morphs = head ? Object.keys(head.morphTargetDictionary || {}) : [];
  const changedBy = (name) => {
    if (!head || head.morphTargetDictionary[name] === undefined) return 0;
    head.morphTargetInfluences.fill(0);
    head.morphTargetInfluences[head.morphTargetDictionary[name]] = 1;
    const posed = draw();
    head.morphTargetInfluences.fill(0);
    let changed = 0;
    for (let i = 0; i < posed.length; i += 4) if (Math.abs(posed[i] - rest[i]) + Math.abs(posed[i + 1] - rest[i + 1]) + Math.abs(posed[i + 2] - rest[i + 2]) > 30) changed++;
    return changed / (256 * 256);
  };
  const jawChanged = changedBy('jawOpen'), smileChanged = changedBy('smile');
  // The Talk clip played by three.js's AnimationMixer: the head's
  // morphTargetInfluences at sampled times (compared below with the
  // sequence's weights); then everything back at rest.
  const clips = gltf.animations.map((a) => a.name + ':' + a.tracks.length);
  const talk = THREE.AnimationClip.findByName(gltf.animations, 'Talk');
  const SAMPLED = ['viseme_nn', 'viseme_aa', 'viseme_O', 'viseme_U', 'viseme_PP', 'viseme_I', 'blink', 'jawOpen', 'smile'];
  const talkAt = {};
  let talkDuration = 0, talkChanged = 0;
  if (talk && head) {
    talkDuration = talk.duration;
    const mixer = new THREE.AnimationMixer(gltf.scene);
    mixer.clipAction(talk).play();
    for (const t of [0.47, 0.98, 1.65]) {
      mixer.setTime(t);
      talkAt[t] = Object.fromEntries(SAMPLED.map((n) => [n, head.morphTargetInfluences[head.morphTargetDictionary[n]]]));
    }
    mixer.setTime(1.04);  // viseme_aa at 1: the mouth open
    const posed = draw();
    for (let i = 0; i < posed.length; i += 4) if (Math.abs(posed[i] - rest[i]) + Math.abs(posed[i + 1] - rest[i + 1]) + Math.abs(posed[i + 2] - rest[i + 2]) > 30) talkChanged++;
    talkChanged /= 256 * 256;
    mixer.stopAllAction();
    mixer.uncacheRoot(gltf.scene);
    gltf.scene.traverse((o) => { if (o.morphTargetInfluences) o.morphTargetInfluences.fill(0); });
  }
  // Gaze played by the AnimationMixer turns the LeftEye and RightEye bones
  // (where a tool that reads the gaze from bones looks): each eye's forward
  // direction (+z) at 0.6 s (to the head's left) and 2.4 s (up), and the
  // largest weight the eyeballs' own eyeLook targets get (they must stay 0:
  // the bones turn the eyes).
  const gazeClip = THREE.AnimationClip.findByName(gltf.animations, 'Gaze');
  const gazeAt = {}; let eyeWeights = -1;
  const eyeBones = head && head.isSkinnedMesh ? head.skeleton.bones.filter((b) => /^(Left|Right)Eye/.test(b.name)) : [];
  if (gazeClip && eyeBones.length === 2) {
    const mixer = new THREE.AnimationMixer(gltf.scene);
    mixer.clipAction(gazeClip).play();
    eyeWeights = 0;
    for (const t of [0.6, 2.4]) {
      mixer.setTime(t);
      gazeAt[t] = eyeBones.map((b) => new THREE.Vector3(0, 0, 1).applyQuaternion(b.quaternion).toArray());
      for (const b of eyeBones) b.traverse((o) => { if (o.isMesh && o.morphTargetInfluences) eyeWeights = Math.max(eyeWeights, ...o.morphTargetInfluences); });
    }
    mixer.stopAllAction();
    mixer.uncacheRoot(gltf.scene);
    for (const b of eyeBones) b.quaternion.identity();
    gltf.scene.traverse((o) => { if (o.morphTargetInfluences) o.morphTargetInfluences.fill(0); });
  }
  // The tongue's own morph target: tongueOut at 1 pushes its frontmost
  // vertex forward (+z, the face's front), by three.js's own morphing.
  let tongueForward = 0, tongueNames = [];
  const tongue = gltf.scene.getObjectByName('Tongue');
  if (tongue && tongue.isMesh && tongue.morphTargetDictionary) {
    tongueNames = Object.keys(tongue.morphTargetDictionary);
    const pos = tongue.geometry.attributes.position, v = new THREE.Vector3();
    let tip = 0; for (let i = 1; i < pos.count; i++) if (pos.getZ(i) > pos.getZ(tip)) tip = i;
    const out = tongue.morphTargetDictionary.tongueOut;
    if (out !== undefined) {
      tongue.morphTargetInfluences[out] = 1;
      tongue.getVertexPosition(tip, v);
      tongueForward = v.z - pos.getZ(tip);
      tongue.morphTargetInfluences[out] = 0;
    }
  }
  // The skeleton: the head is a SkinnedMesh on Neck, Head, LeftEye, RightEye,
  // Jaw; turning the Jaw bone 0.3 rad about x lowers the skinned head's
  // lowest-moving vertices (skinned by three.js itself: the chin), leaves the
  // crown (the highest vertex) and changes the render.
  const bones = head && head.isSkinnedMesh ? head.skeleton.bones.map((b) => b.name) : [];
  let boneChanged = 0, chinDrop = 0, crownMoved = -1;
  const jawBone = gltf.scene.getObjectByName('Jaw');
  if (head && head.isSkinnedMesh && jawBone) {
    const pos = head.geometry.attributes.position;
    const skinnedAll = () => {
      gltf.scene.updateMatrixWorld(true); head.skeleton.update();
      const out = new Float32Array(3 * pos.count), v = new THREE.Vector3();
      for (let i = 0; i < pos.count; i++) { v.fromBufferAttribute(pos, i); head.applyBoneTransform(i, v); out[3 * i] = v.x; out[3 * i + 1] = v.y; out[3 * i + 2] = v.z; }
      return out;
    };
    let crown = 0; for (let i = 1; i < pos.count; i++) if (pos.getY(i) > pos.getY(crown)) crown = i;
    const before = skinnedAll();
    jawBone.rotation.x = 0.3;
    const after = skinnedAll();
    for (let i = 0; i < pos.count; i++) chinDrop = Math.max(chinDrop, before[3 * i + 1] - after[3 * i + 1]);
    crownMoved = Math.hypot(after[3 * crown] - before[3 * crown], after[3 * crown + 1] - before[3 * crown + 1], after[3 * crown + 2] - before[3 * crown + 2]);
    const posed = draw();
    for (let i = 0; i < posed.length; i += 4) if (Math.abs(posed[i] - rest[i]) + Math.abs(posed[i + 1] - rest[i + 1]) + Math.abs(posed[i + 2] - rest[i + 2]) > 30) boneChanged++;
    boneChanged /= 256 * 256;
    // Left on screen for the screenshot: the head turned by its Head bone, the
    // jaw open by its Jaw bone, the eyes turned 25 degrees to the head's
    // left by their bones, smiling by its morph target.
    const headBone = gltf.scene.getObjectByName('Head');
    if (headBone) headBone.rotation.y = 0.45;
    for (const b of eyeBones) b.rotation.y = 25 * Math.PI / 180;
    head.morphTargetInfluences[head.morphTargetDictionary.smile] = 1;
    draw();
  }
  return { names, meshes, headVertices, skinTextured, litFraction: lit / (256 * 256), morphs, jawChanged, smileChanged, bones, boneChanged, chinDrop, crownMoved,
           clips, talkDuration, talkAt, talkChanged, gazeAt, eyeWeights, tongueForward, tongueNames };
})().catch((e) => ({ error: String(e && e.message || e) }));
</script>` });
    }
    if (rel === 'head.glb') return r.fulfill({ contentType: 'model/gltf-binary', body: made.glb });
    if (rel.startsWith('three/')) {
      const file = path.join(three, rel.slice('three/'.length));
      if (!file.startsWith(three) || !fs.existsSync(file)) return r.fulfill({ status: 404, body: 'not found' });
      return r.fulfill({ contentType: 'text/javascript', body: fs.readFileSync(file) });
    }
    return r.fulfill({ status: 404, body: 'not found' });
  });
  await page.goto(s.origin + '/__glb_test/index.html');
  await page.waitForFunction(() => window.result, null, { timeout: 60000 });
  const got = await page.evaluate(() => window.result);
  const wanted = ['Neck', 'Head', 'HeadMesh', 'LeftEye', 'RightEye', 'UpperTeeth', 'Jaw', 'LowerTeeth', 'Tongue'];
  const headVerts = Number((/(\d+) vertices/.exec(made.report) || [])[1]);
  check('three.js\'s GLTFLoader loads the GLB: every node, the head\'s vertices, the skin texture',
        !got.error && wanted.every((n) => got.names.includes(n)) && got.headVertices === headVerts && got.skinTextured && got.meshes === 6,
        JSON.stringify(Object.assign({}, got, { names: got.names && got.names.join(' ') })));
  await shot(page, 'glb_threejs.png');
  check('... and renders the head with WebGL', got.litFraction > 0.05, `${(100 * (got.litFraction || 0)).toFixed(1)}% of the pixels lit`);
  const missing = ALL_SHAPES.filter((n) => !(got.morphs || []).includes(n));
  check(`... its morphTargetDictionary holds all ${ALL_SHAPES.length} names (10 expressions, Apple's 52 ARKit shapes, 15 visemes)`,
        missing.length === 0 && got.morphs.length === ALL_SHAPES.length,
        `${(got.morphs || []).length} morph targets${missing.length ? '; missing ' + missing.join(', ') : ''}`);
  check('... and jawOpen, smile at weight 1 each change the render', got.jawChanged > 0.001 && got.smileChanged > 0.001,
        `jawOpen ${(100 * (got.jawChanged || 0)).toFixed(2)}%, smile ${(100 * (got.smileChanged || 0)).toFixed(2)}% of the pixels changed`);
  check('... the head is skinned to the skeleton Neck, Head, LeftEye, RightEye, Jaw; turning the Jaw bone drops the chin and changes the render',
        (got.bones || []).join(' ') === 'Neck Head LeftEye RightEye Jaw' && got.chinDrop > 0.005 && got.crownMoved === 0 && got.boneChanged > 0.001,
        `bones ${(got.bones || []).join(' ')}; Jaw 0.3 rad: chin ${(1000 * (got.chinDrop || 0)).toFixed(1)} mm down, crown moved ${got.crownMoved} m, ${(100 * (got.boneChanged || 0)).toFixed(2)}% of the pixels changed`);
  // Talk's weights at the sampled times, from its keys (core/anim/clips.cpp:
  // [0.46 viseme_O 1.0] -> [0.62 viseme_U 0.5], [0.92 viseme_nn 0.8] ->
  // [1.04 viseme_aa 1.0], [1.58 viseme_PP 1.0] -> [1.72 viseme_I 1.0],
  // smoothstep between keys; a blink closing from 0.40 to 0.47), spelled
  // here independently: a channel on the wrong targets or times fails.
  const sm = (u) => u * u * (3 - 2 * u);
  const want = {
    0.47: { viseme_O: 1 - sm(0.01 / 0.16), viseme_U: 0.5 * sm(0.01 / 0.16), blink: 1 },
    0.98: { viseme_nn: 0.4, viseme_aa: 0.5 },
    1.65: { viseme_PP: 0.5, viseme_I: 0.5 },
  };
  let worst = 0;
  const rows = [];
  for (const [t, w] of Object.entries(want)) {
    const got1 = (got.talkAt || {})[t] || {};
    for (const n of ['viseme_nn', 'viseme_aa', 'viseme_O', 'viseme_U', 'viseme_PP', 'viseme_I', 'blink', 'jawOpen', 'smile'])
    {
      const d = Math.abs(got1[n] - (w[n] || 0));
      worst = Math.max(worst, Number.isFinite(d) ? d : Infinity);  // a missing influence fails
    }
    rows.push(t + ' s: ' + Object.entries(got1).filter(([, x]) => x > 0.001).map(([n, x]) => n + ' ' + x.toFixed(3)).join(', '));
  }
  check('the GLB\'s animations (Talk, Blink, Gaze) play in three.js: AnimationMixer on Talk gives the head the sequence\'s weights at sampled times, and the mouth moves',
        (got.clips || []).some((c) => c.startsWith('Talk:')) && (got.clips || []).some((c) => c.startsWith('Blink:')) &&
        Math.abs(got.talkDuration - 2.6) < 1e-3 && worst < 1e-3 && got.talkChanged > 0.001,
        `clips ${(got.clips || []).join(' ')} (name:tracks), Talk ${got.talkDuration} s; ${rows.join('; ')}; largest difference ${worst.toExponential(2)}; ` +
        `at 1.04 s ${(100 * (got.talkChanged || 0)).toFixed(2)}% of the pixels changed`);
  // Gaze (core/anim/clips.cpp, spelled here independently): both eyes 25
  // degrees to the head's left (+x) at 0.6 s, 0.6 of 25 degrees up at 2.4 s.
  const deg = Math.PI / 180;
  const gazeWant = { 0.6: [Math.sin(25 * deg), 0, Math.cos(25 * deg)], 2.4: [0, Math.sin(15 * deg), Math.cos(15 * deg)] };
  let gazeWorst = 0;
  for (const [t, d] of Object.entries(gazeWant))
    for (const e of ((got.gazeAt || {})[t] || [])) gazeWorst = Math.max(gazeWorst, Math.acos(Math.min(1, e[0] * d[0] + e[1] * d[1] + e[2] * d[2])) / deg);
  const gazeRows = Object.entries(got.gazeAt || {}).map(([t, es]) => t + ' s: ' + es.map((e) => '(' + e.map((x) => x.toFixed(3)).join(', ') + ')').join(' '));
  check('... its Gaze animation turns the LeftEye and RightEye bones (25 degrees to the head\'s left at 0.6 s, 15 up at 2.4 s) and leaves the eyeballs\' own eyeLook weights at 0',
        Object.keys(got.gazeAt || {}).length === 2 && gazeWorst < 0.5 && got.eyeWeights === 0,
        `eyes' forward directions ${gazeRows.join('; ')}; worst ${gazeWorst.toFixed(3)} degrees off; the eyeballs' largest weight ${got.eyeWeights}`);
  check('the tongue has its own tongueOut target: at weight 1 three.js moves its tip forward by over 15 mm; smile, brows are not on it',
        got.tongueForward > 0.015 && got.tongueNames.includes('tongueOut') && !got.tongueNames.includes('smile') && !got.tongueNames.includes('browInnerUp'),
        `tip ${(1000 * (got.tongueForward || 0)).toFixed(1)} mm forward; the tongue's targets: ${(got.tongueNames || []).length} (${(got.tongueNames || []).slice(0, 6).join(', ')}, ...)`);
  check('the level-2 GLB with every shape and its textures is under 8 MB', made.glb.length < 8 * 1048576,
        `${(made.glb.length / 1048576).toFixed(2)} MB`);
  await page.close();
}

export const flow = { name: 'glb', title: 'the GLB export: Khronos validator and three.js', run };
runAlone(import.meta.url, flow);
