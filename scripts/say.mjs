// scripts/say: the words (one argument) as a speech document on stdout.
import { speechOf } from '../web/js/speech.js';

const lipsyncPath = new URL('../vendor/node_modules/@met4citizen/talkinghead/modules/lipsync-en.mjs', import.meta.url);
if (process.argv.length !== 3 || !process.argv[2].trim()) {
  console.error('usage: scripts/say "WORDS" > say.json');
  process.exit(2);
}
let LipsyncEn;
try {
  ({ LipsyncEn } = await import(lipsyncPath.href));
} catch (e) {
  console.error(`say: cannot load TalkingHead's lipsync-en (${lipsyncPath.pathname}); run scripts/setup`);
  process.exit(1);
}
const doc = speechOf(new LipsyncEn(), process.argv[2]);
if (!doc.visemes.length) {
  console.error('say: there is nothing to say in those words');
  process.exit(1);
}
if (doc.truncated) console.error(`say: only the first ${doc.text.length} characters are said`);
delete doc.truncated;
process.stdout.write(JSON.stringify(doc) + '\n');
