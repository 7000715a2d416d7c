// scripts/say: the words (one argument) as a speech document on stdout,
// read in English or, with --lang, another language TalkingHead reads.
import { LANGUAGES, readerFor, speechOf } from '../web/js/speech.js';

const args = process.argv.slice(2);
let lang = 'en';
const at = args.indexOf('--lang');
if (at >= 0) {
  lang = args[at + 1];
  args.splice(at, 2);
}
if (args.length !== 1 || !args[0].trim() || !LANGUAGES[lang]) {
  console.error(`usage: scripts/say [--lang ${Object.keys(LANGUAGES).join('|')}] "WORDS" > say.json`);
  process.exit(2);
}
const modules = new URL('../vendor/node_modules/@met4citizen/talkinghead/modules/', import.meta.url);
let reader;
try {
  reader = await readerFor(lang, modules);
} catch (e) {
  console.error(`say: cannot load TalkingHead's reader (${modules.pathname}${LANGUAGES[lang].module}); run scripts/setup`);
  process.exit(1);
}
const doc = speechOf(reader, args[0], lang);
if (!doc.visemes.length) {
  console.error('say: there is nothing to say in those words');
  process.exit(1);
}
if (doc.truncated) console.error(`say: only the first ${doc.text.length} characters are said`);
delete doc.truncated;
process.stdout.write(JSON.stringify(doc) + '\n');
