// Typed words as visemes (issue 38): the speech document the core's Say
// clip is made from (core/anim/speech.h). The reading is TalkingHead's
// lip sync (npm @met4citizen/talkinghead, MIT): for English (lipsync-en.mjs)
// numbers and symbols to words, then the letter-to-sound rules of NRL
// Report 7948, to Oculus visemes with times and lengths in its own units
// (1 is an average sound); German, French, Finnish and Lithuanian by its
// readers for them, alike. The text is cut into phrases at punctuation and
// line breaks; each phrase is read alone and the phrases are joined by a
// pause ("sil", PAUSE units), where the mouth rests. The page and
// scripts/say (for likeness export --say) both call speechOf, so the same
// words give the same document. No DOM and no static import: speechOf is handed
// the reader (pageSpeech: the page's, from its own origin).

export const MAX_SAY_CHARS = 400;
export const PAUSE = 2.5;
// The languages TalkingHead reads: its module and class for each.
export const LANGUAGES = {
  en: { module: 'lipsync-en.mjs', reader: 'LipsyncEn' },
  de: { module: 'lipsync-de.mjs', reader: 'LipsyncDe' },
  fr: { module: 'lipsync-fr.mjs', reader: 'LipsyncFr' },
  fi: { module: 'lipsync-fi.mjs', reader: 'LipsyncFi' },
  lt: { module: 'lipsync-lt.mjs', reader: 'LipsyncLt' },
};

// {format, version, lipsync, text, visemes, times, durations, truncated}
// for text read by lipsync, the reader of language lang (at most
// MAX_SAY_CHARS characters are read); visemes is empty when nothing in it
// can be said.
export function speechOf(lipsync, text, lang = 'en') {
  const all = String(text);
  const said = all.slice(0, MAX_SAY_CHARS);
  const doc = { format: 'likeness-speech', version: 1, lipsync: '@met4citizen/talkinghead 1.7.0 lipsync-' + lang, text: said,
                visemes: [], times: [], durations: [], truncated: all.length > said.length };
  let t = 0;
  for (const phrase of said.split(/[,.;:!?\n\r]+/)) {
    const words = lipsync.preProcessText(phrase);
    if (!words) continue;
    const o = lipsync.wordsToVisemes(words);
    if (!o.visemes.length) continue;
    if (doc.visemes.length) {
      doc.visemes.push('sil'); doc.times.push(t); doc.durations.push(PAUSE);
      t += PAUSE;
    }
    for (let i = 0; i < o.visemes.length; i++) {
      doc.visemes.push(o.visemes[i]); doc.times.push(t + o.times[i]); doc.durations.push(o.durations[i]);
    }
    t += o.times[o.times.length - 1] + o.durations[o.durations.length - 1];
  }
  return doc;
}

// TalkingHead's reader of language lang, from the folder of its modules
// (a URL: the page's vendor/ copy, or the npm package under Node).
export async function readerFor(lang, modules) {
  const language = LANGUAGES[lang];
  return new (await import(new URL(language.module, modules).href))[language.reader]();
}

// The page's readers, each loaded from its own origin (build/web/vendor/)
// the first time words are said in its language; a missing one is said,
// not thrown.
const pageReaders = {};
export async function pageSpeech(text, lang = 'en') {
  if (!LANGUAGES[lang]) return { error: 'no lip-sync reader for the language "' + lang + '"' };
  if (!pageReaders[lang]) {
    try {
      pageReaders[lang] = await readerFor(lang, new URL('../vendor/talkinghead/modules/', import.meta.url));
    } catch (e) {
      return { error: 'the lip-sync reader (vendor/talkinghead, ' + lang + ') did not load: ' + (e && e.message ? e.message : e) };
    }
  }
  return speechOf(pageReaders[lang], text, lang);
}

// The page's first language among the readers' (navigator.languages), else English.
export function preferredLanguage(languages) {
  for (const l of languages || []) {
    const code = String(l).slice(0, 2).toLowerCase();
    if (LANGUAGES[code]) return code;
  }
  return 'en';
}
