#pragma once
// Words to say, as visemes (issue 38): the speech document the page
// (web/js/speech.js) and scripts/say write from typed words with
// TalkingHead's lip-sync readers, and anim/clips.h speech_clip turns into
// the Say clip. Reading words into sounds is that library's work; this
// module only checks its output, as bytes from outside.
//   {"format": "likeness-speech", "version": 1, "lipsync": "...",
//    "text": "hello", "visemes": ["I", "E", "nn", "O"],
//    "times": [0, 0.92, 1.82, 2.7], "durations": [0.92, 0.9, 0.88, 0.96]}
// Visemes by their Oculus names without "viseme_" ("sil": the mouth at
// rest); times and durations in the reader's units (1 is an average
// sound), each viseme starting no earlier than the one before it ends.
#include <string>
#include <vector>

#include "common/status.h"

namespace lk {

struct Speech {
  std::string text;  // the words, as typed (for the reader; not read here)
  std::vector<std::string> visemes;
  std::vector<double> times, durations;
};

constexpr std::size_t kMaxSpeechBytes = 1 << 20;
constexpr std::size_t kMaxSpeechVisemes = 4000;
constexpr double kMaxSpeechUnits = 6000;  // 10 minutes at anim/clips.h's pace

// InvalidInput (naming the field and why) unless the arrays have one entry
// per viseme, every name is one of the 15 visemes, and times and
// durations are finite, ascending without overlap, within the limits.
Status check_speech(const Speech& speech);
// The document's bytes to a Speech, checked (TooLarge past kMaxSpeechBytes).
Status parse_speech_json(const std::string& text, Speech& out);

}  // namespace lk
