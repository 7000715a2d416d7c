// Typed words to a speech document (web/js/speech.js with TalkingHead's
// lip-sync readers, as the page and scripts/say read them) under Node, and, given
// the native CLI, the document through `likeness export --say` into a GLB's
// Say animation that the Khronos validator passes.
// Usage: node tests/browser/speech_node.mjs [build/bin/likeness]   (exit 0: every check passed)
import assert from 'node:assert/strict';
import { execFileSync } from 'node:child_process';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { createRequire } from 'node:module';
import { fileURLToPath } from 'node:url';
import { MAX_SAY_CHARS, PAUSE, preferredLanguage, readerFor, speechOf } from '../../web/js/speech.js';

const ROOT = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '../..');
const MODULES = new URL('../../vendor/node_modules/@met4citizen/talkinghead/modules/', import.meta.url);
if (!fs.existsSync(new URL('lipsync-en.mjs', MODULES))) {
  console.log(`skipped: ${MODULES.pathname} is missing (run scripts/setup)`);
  process.exit(77);
}
const reader = await readerFor('en', MODULES);
let checks = 0;

// "papa": the library's reading, whole.
const papa = speechOf(reader, 'papa');
assert.deepEqual(papa.visemes, ['PP', 'aa', 'PP', 'aa']);
assert.deepEqual(papa.times.map((t) => +t.toFixed(6)), [0, 1.08, 2.03, 3.11]);
assert.deepEqual(papa.durations, [1.08, 0.95, 1.08, 0.95]);
assert.equal(papa.format, 'likeness-speech');
checks++;

// Punctuation cuts phrases: each read alone, joined by a rest of PAUSE units
// that starts where the phrase before ends; no rest at either end.
const two = speechOf(reader, 'papa, papa!');
assert.deepEqual(two.visemes, ['PP', 'aa', 'PP', 'aa', 'sil', 'PP', 'aa', 'PP', 'aa']);
assert.ok(Math.abs(two.times[4] - 4.06) < 1e-9 && two.durations[4] === PAUSE && Math.abs(two.times[5] - (4.06 + PAUSE)) < 1e-9,
          JSON.stringify(two));
for (let i = 1; i < two.times.length; i++) assert.ok(two.times[i] >= two.times[i - 1] + two.durations[i - 1] - 1e-9);
checks++;

// The reader's own work: numbers and symbols become words, so they are said.
const n = speechOf(reader, '42 & 3');
assert.ok(n.visemes.length >= 8 && !n.visemes.includes('sil'), n.visemes.join(' '));
checks++;

// Nothing to say: no viseme (the page and scripts/say say so); a long text is cut, and says it was.
assert.equal(speechOf(reader, '!? ...').visemes.length, 0);
assert.equal(speechOf(reader, '').visemes.length, 0);
const long = speechOf(reader, 'ba '.repeat(300));
assert.ok(long.truncated && long.text.length === MAX_SAY_CHARS && !papa.truncated);
checks++;

// The other languages TalkingHead reads: each reader loads from the
// package, reads a sentence of its language to known visemes, and the
// document names it; the page picks the browser's first language it has.
const VISEMES = ['sil', 'PP', 'FF', 'TH', 'DD', 'kk', 'CH', 'SS', 'nn', 'RR', 'aa', 'E', 'I', 'O', 'U'];
const SENTENCES = { de: 'Guten Tag, wie geht es Ihnen?', fr: 'Bonjour, comment allez-vous?', fi: 'Hyvää päivää, mitä kuuluu?',
                    lt: 'Laba diena, kaip sekasi?' };
for (const [lang, text] of Object.entries(SENTENCES)) {
  const doc = speechOf(await readerFor(lang, MODULES), text, lang);
  assert.ok(doc.visemes.length >= 6 && doc.visemes.every((v) => VISEMES.includes(v)), lang + ': ' + doc.visemes.join(' '));
  assert.equal(doc.visemes.filter((v) => v === 'sil').length, 1, lang + ': one pause, at the comma');
  assert.equal(doc.lipsync, '@met4citizen/talkinghead 1.7.0 lipsync-' + lang);
}
assert.equal(preferredLanguage(['de-CH', 'en']), 'de');
assert.equal(preferredLanguage(['ja', 'fr-FR']), 'fr');
assert.equal(preferredLanguage(['ja']), 'en');
checks++;

// The command line: scripts/say writes the document, likeness export
// reads it into a Say animation of the clip's length (anim/clips.h: 0.1 s
// a unit after a 0.1 s breath, 0.3 s at rest to end), valid glTF.
const cli = process.argv[2];
if (cli && fs.existsSync(cli)) {
  const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'lk-say-'));
  try {
    const run = (cmd, args) => execFileSync(cmd, args, { encoding: 'utf8', stdio: ['ignore', 'pipe', 'pipe'] });
    const said = run(path.join(ROOT, 'scripts/say'), ['papa, papa!']);
    assert.deepEqual(JSON.parse(said).visemes, two.visemes);
    assert.equal(JSON.parse(run(path.join(ROOT, 'scripts/say'), ['--lang', 'de', 'Guten Tag'])).lipsync,
                 '@met4citizen/talkinghead 1.7.0 lipsync-de');
    fs.writeFileSync(path.join(dir, 'say.json'), said);
    run(cli, ['synth-scan', '--seed', '1', '--points', '5000', '--out', path.join(dir, 'scan')]);
    run(cli, ['fit', '--scan', path.join(dir, 'scan/scan.ply'), '--out', path.join(dir, 'fit'), '--levels', '1']);
    const out = run(cli, ['export', '--head', path.join(dir, 'fit'), '--out', path.join(dir, 'head.glb'), '--level', '1',
                          '--say', path.join(dir, 'say.json')]);
    assert.ok(/animations: Talk, Blink, Gaze, Say/.test(out), out);
    const glb = fs.readFileSync(path.join(dir, 'head.glb'));
    const json = JSON.parse(glb.toString('utf8', 20, 20 + glb.readUInt32LE(12)));
    const anim = json.animations.find((a) => a.name === 'Say');
    const seconds = Math.max(...anim.samplers.map((s) => json.accessors[s.input].max[0]));
    const end = two.times.at(-1) + two.durations.at(-1);
    assert.ok(Math.abs(seconds - (0.1 + 0.1 * end + 0.3)) < 1e-5, `Say lasts ${seconds} s`);
    const require = createRequire(path.join(ROOT, 'tests/browser/package.json'));
    const report = await require('gltf-validator').validateBytes(new Uint8Array(glb));
    assert.equal(report.issues.numErrors, 0, JSON.stringify(report.issues.messages.slice(0, 3)));
    // The words themselves are not a file: the reason, not a crash.
    let refused = '';
    try { run(cli, ['export', '--head', path.join(dir, 'fit'), '--out', path.join(dir, 'x.glb'), '--say', 'hello there']); }
    catch (e) { refused = String(e.stderr); }
    assert.ok(/scripts\/say/.test(refused), refused);
    checks += 2;
  } finally {
    fs.rmSync(dir, { recursive: true, force: true });
  }
} else {
  console.log('the command line was not checked: no likeness binary given');
}
console.log(`speech: ${checks} checks passed`);
