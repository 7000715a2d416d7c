// Weight clips: named shapes' weights over time (issue 38's talking demo,
// a blink, a gaze), the one source the page's Talk and the GLB's glTF
// animations play. A clip is cubic Hermite keys shared by its shapes: at
// each key every shape's weight and its slope (per second), between keys
// the Hermite cubic glTF's CUBICSPLINE interpolation computes, so a GLB
// channel written from these keys plays exactly what the page plays.
#pragma once
#include "anim/speech.h"
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

// Words to say (a speech document, anim/speech.h) as a clip named "Say"
// (the page's Talk with words; lip sync from text, not audio): each
// viseme a key at the middle of its time (vowels at weight 1, consonants
// at 0.8), "sil" the mouth at rest from its start to its end, a unit
// kSpeechUnitSeconds, after a 0.1 s breath; cross-fading by smoothstep as
// Talk does. A blink every 2.8 s from 0.4 s; at rest at both ends, 0.3 s
// at rest to close. InvalidInput when check_speech refuses the document or
// it holds nothing but rest ("there is nothing to say").
constexpr double kSpeechUnitSeconds = 0.1;
Status speech_clip(const Speech& speech, WeightClip& out);

// Each shape's weight at t (clamped to [0, duration]), in clip.shapes' order.
std::vector<double> clip_weights(const WeightClip& clip, double t);

}  // namespace lk
