// Weight clips: named shapes' weights over time (issue 38's talking demo,
// a blink, a gaze), the one source the page's Talk and the GLB's glTF
// animations play. A clip is cubic Hermite keys shared by its shapes: at
// each key every shape's weight and its slope (per second), between keys
// the Hermite cubic glTF's CUBICSPLINE interpolation computes, so a GLB
// channel written from these keys plays exactly what the page plays.
#pragma once
#include "common/status.h"

#include <string>
#include <vector>

namespace lk {

struct WeightClip {
  std::string name;                           // "Talk", "Blink"
  std::vector<std::string> shapes;            // the shapes it drives (face_shapes.h names)
  std::vector<double> times;                  // key times, seconds, strictly ascending, the first 0
  std::vector<std::vector<double>> value;     // [key][shape]: the weight
  std::vector<std::vector<double>> slope;     // [key][shape]: its derivative (per second), in and out alike
  double duration() const { return times.empty() ? 0.0 : times.back(); }
};

// "hello, nice to meet you": visemes cross-fading from one key to the next
// by smoothstep, with two blinks (each closing in 70 ms and opening in
// 130 ms); it starts and ends at rest.
const WeightClip& talk_clip();
// One blink (the `blink` expression: both lids), 0.2 s.
const WeightClip& blink_clip();
// The eyes (eyeLook*) to the head's left, its right, up and back, 3 s.
const WeightClip& gaze_clip();
// The three, in that order (the GLB's animations).
std::vector<WeightClip> weight_clips();

// Typed words as a clip named "Say" (the page's Talk with words; lip sync
// from text, not audio): letters read to visemes by English spelling, one
// key per sound (vowels 120 ms at weight 1, consonants 80 ms at 0.8),
// cross-fading by smoothstep as Talk does. Digraphs first (th ch sh ph ck
// ng qu wh ee ea oo); c before e, i or y reads s; a word's final e (words
// of 4 letters or more) and h are silent; a repeated sound is one key;
// letters outside a-z (digits, accents) are skipped. A space adds 60 ms to
// the cross-fade between its words; punctuation (, . ; : ! ?) or a line
// break holds the mouth at rest for 250 ms (then 80 ms into the next
// sound). A blink every 2.8 s from 0.4 s; at rest at both ends. At most
// kMaxSayLetters letters are read (*truncated says so). InvalidInput when
// no letter a-z is left to say.
constexpr int kMaxSayLetters = 400;
Status text_clip(const std::string& text, WeightClip& out, bool* truncated = nullptr);

// Each shape's weight at t (clamped to [0, duration]), in clip.shapes' order.
std::vector<double> clip_weights(const WeightClip& clip, double t);

}  // namespace lk
