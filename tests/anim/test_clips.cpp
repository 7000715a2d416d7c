// The weight clips (anim/clips.h): Talk and Blink as cubic Hermite keys
// must play exactly the curves they are made of: visemes cross-fading by
// smoothstep from one phrase key to the next, blinks closing in 70 ms and
// opening in 130 ms. The oracle below is the page's former talkWeights
// (segment by segment), spelled here independently of clips.cpp.
#include "anim/clips.h"
#include "anim/face_shapes.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <map>
#include <string>

using namespace lk;

namespace {

double smooth(double x) { return x * x * (3 - 2 * x); }

std::map<std::string, double> oracle_talk(double t) {
  struct Key {
    double t;
    std::string v;
    double w;
  };
  static const std::vector<Key> phrase = {
      {0.00, "viseme_sil", 0}, {0.12, "viseme_kk", 0.5}, {0.22, "viseme_E", 0.9}, {0.32, "viseme_nn", 0.7},
      {0.46, "viseme_O", 1.0}, {0.62, "viseme_U", 0.5}, {0.80, "viseme_sil", 0}, {0.92, "viseme_nn", 0.8},
      {1.04, "viseme_aa", 1.0}, {1.16, "viseme_I", 0.8}, {1.28, "viseme_SS", 0.9}, {1.38, "viseme_DD", 0.8},
      {1.48, "viseme_U", 0.8}, {1.58, "viseme_PP", 1.0}, {1.72, "viseme_I", 1.0}, {1.84, "viseme_DD", 0.7},
      {1.92, "viseme_I", 0.6}, {2.08, "viseme_U", 1.0}, {2.30, "viseme_sil", 0}, {2.60, "viseme_sil", 0}};
  std::map<std::string, double> w;
  auto add = [&](const std::string& n, double v) {
    if (n != "viseme_sil") w[n] += v;
  };
  std::size_t k = 0;
  while (k + 1 < phrase.size() && phrase[k + 1].t <= t) ++k;
  if (k + 1 < phrase.size()) {
    const double s = smooth(std::clamp((t - phrase[k].t) / (phrase[k + 1].t - phrase[k].t), 0.0, 1.0));
    add(phrase[k].v, (1 - s) * phrase[k].w);
    add(phrase[k + 1].v, s * phrase[k + 1].w);
  }
  for (double b : {0.40, 2.20}) {
    const double u = t - b;
    add("blink", u < 0 ? 0 : u < 0.07 ? smooth(u / 0.07) : u < 0.20 ? 1 - smooth((u - 0.07) / 0.13) : 0);
  }
  return w;
}

}  // namespace

TEST_CASE("weight clips: Talk plays the visemes' smoothstep cross-fades and the blinks exactly") {
  const WeightClip& c = talk_clip();
  CHECK(c.name == "Talk");
  CHECK(c.duration() == 2.60);
  REQUIRE(c.times.size() >= 2);
  CHECK(c.times.front() == 0.0);
  for (std::size_t k = 1; k < c.times.size(); ++k) CHECK(c.times[k] > c.times[k - 1]);
  REQUIRE(c.value.size() == c.times.size());
  REQUIRE(c.slope.size() == c.times.size());
  const std::vector<std::string>& names = face_shape_names();
  for (const std::string& s : c.shapes) CHECK(std::find(names.begin(), names.end(), s) != names.end());
  CHECK(std::find(c.shapes.begin(), c.shapes.end(), "blink") != c.shapes.end());
  CHECK(std::find(c.shapes.begin(), c.shapes.end(), "viseme_sil") == c.shapes.end());
  double worst = 0, peak_blink = 0, peak_aa = 0;
  for (int ms = 0; ms <= 2700; ++ms) {
    const double t = ms / 1000.0;
    const std::vector<double> got = clip_weights(c, t);
    REQUIRE(got.size() == c.shapes.size());
    std::map<std::string, double> want = oracle_talk(t);
    for (std::size_t s = 0; s < c.shapes.size(); ++s) {
      worst = std::max(worst, std::abs(got[s] - want[c.shapes[s]]));
      want.erase(c.shapes[s]);
      if (c.shapes[s] == "blink") peak_blink = std::max(peak_blink, got[s]);
      if (c.shapes[s] == "viseme_aa") peak_aa = std::max(peak_aa, got[s]);
    }
    for (const auto& [name, v] : want) CHECK(v == 0.0);  // nothing the clip leaves out
  }
  INFO("largest difference from the cross-fades " << worst);
  CHECK(worst < 1e-12);
  CHECK(peak_blink > 1.0 - 1e-9);
  CHECK(peak_aa > 1.0 - 1e-9);
  // At rest at both ends.
  for (double v : clip_weights(c, 0.0)) CHECK(v == 0.0);
  for (double v : clip_weights(c, c.duration())) CHECK(v == 0.0);
}

TEST_CASE("weight clips: Blink closes both lids in 70 ms and opens them 130 ms later") {
  const WeightClip& c = blink_clip();
  REQUIRE(c.shapes == std::vector<std::string>{"blink"});
  CHECK(std::abs(c.duration() - 0.20) < 1e-12);
  CHECK(clip_weights(c, 0.0)[0] == 0.0);
  CHECK(std::abs(clip_weights(c, 0.07)[0] - 1.0) < 1e-12);
  CHECK(std::abs(clip_weights(c, 0.035)[0] - 0.5) < 1e-12);                  // smoothstep's middle
  CHECK(std::abs(clip_weights(c, 0.07 + 0.065)[0] - 0.5) < 1e-12);
  CHECK(clip_weights(c, 0.2)[0] == 0.0);
  CHECK(weight_clips().size() == 3);
}

TEST_CASE("weight clips: Gaze turns both eyes to the head's left, its right, up and back") {
  const WeightClip& c = gaze_clip();
  auto at = [&](double t, const std::string& name) {
    const std::vector<double> w = clip_weights(c, t);
    const auto i = std::find(c.shapes.begin(), c.shapes.end(), name);
    REQUIRE(i != c.shapes.end());
    return w[static_cast<size_t>(i - c.shapes.begin())];
  };
  CHECK(std::abs(at(0.65, "eyeLookOutLeft") - 1.0) < 1e-12);
  CHECK(std::abs(at(0.65, "eyeLookInRight") - 1.0) < 1e-12);
  CHECK(at(0.65, "eyeLookInLeft") == 0.0);
  CHECK(std::abs(at(1.1, "eyeLookOutLeft") - 0.5) < 1e-12);  // half way over
  CHECK(std::abs(at(1.1, "eyeLookInLeft") - 0.5) < 1e-12);
  CHECK(std::abs(at(1.5, "eyeLookOutRight") - 1.0) < 1e-12);
  CHECK(std::abs(at(2.4, "eyeLookUpLeft") - 0.6) < 1e-12);
  for (double v : clip_weights(c, c.duration())) CHECK(v == 0.0);
}

namespace {

// The viseme keys of a Say clip, in time order: at each key time the one
// viseme at its full weight (the others 0), as "name@weight".
std::vector<std::string> said(const WeightClip& c) {
  std::vector<std::string> out;
  for (std::size_t k = 0; k < c.times.size(); ++k) {
    std::string top;
    for (std::size_t s = 0; s < c.shapes.size(); ++s)
      if (c.shapes[s] != "blink" && c.value[k][s] > 0.5) top += (top.empty() ? "" : "+") + c.shapes[s].substr(7);
    if (!top.empty() && (out.empty() || out.back() != top)) out.push_back(top);
  }
  return out;
}

}  // namespace

TEST_CASE("weight clips: Say reads typed words to visemes by their spelling, with pauses and blinks") {
  WeightClip c;
  REQUIRE(text_clip("papa", c).ok());
  CHECK(c.name == "Say");
  CHECK(said(c) == std::vector<std::string>{"PP", "aa", "PP", "aa"});
  // Every shape it names is one of the 77 (the page and the GLB know them).
  for (const std::string& s : c.shapes)
    CHECK(std::find(face_shape_names().begin(), face_shape_names().end(), s) != face_shape_names().end());
  // Keys ascending, at rest at both ends; each vowel key at weight 1, each
  // consonant at 0.8: p a p a from 0.10 s, 80 / 120 ms apart.
  for (std::size_t k = 1; k < c.times.size(); ++k) CHECK(c.times[k] > c.times[k - 1]);
  for (double v : clip_weights(c, 0.0)) CHECK(v == 0.0);
  for (double v : clip_weights(c, c.duration())) CHECK(v == 0.0);
  auto at = [&](double t, const std::string& name) {
    const auto i = std::find(c.shapes.begin(), c.shapes.end(), name);
    return i == c.shapes.end() ? 0.0 : clip_weights(c, t)[static_cast<size_t>(i - c.shapes.begin())];
  };
  CHECK(std::abs(at(0.10, "viseme_PP") - 0.8) < 1e-12);
  CHECK(std::abs(at(0.18, "viseme_aa") - 1.0) < 1e-12);
  CHECK(std::abs(at(0.30, "viseme_PP") - 0.8) < 1e-12);
  CHECK(std::abs(at(0.38, "viseme_aa") - 1.0) < 1e-12);
  CHECK(std::abs(at(0.14, "viseme_PP") - 0.4) < 1e-12);  // half way from p to a: smoothstep's middle
  CHECK(std::abs(at(0.14, "viseme_aa") - 0.5) < 1e-12);

  // Digraphs, the silent final e of longer words, h as breath, repeated
  // letters as one sound; case and digits do not matter.
  REQUIRE(text_clip("The SHIP", c).ok());
  CHECK(said(c) == std::vector<std::string>{"TH", "E", "CH", "I", "PP"});
  REQUIRE(text_clip("nice ball 42", c).ok());
  CHECK(said(c) == std::vector<std::string>{"nn", "I", "SS", "PP", "aa", "nn"});  // c before e reads s, ll one nn
  REQUIRE(text_clip("cat", c).ok());
  CHECK(said(c) == std::vector<std::string>{"kk", "aa", "DD"});
  REQUIRE(text_clip("see food", c).ok());
  CHECK(said(c) == std::vector<std::string>{"SS", "I", "FF", "U", "DD"});

  // Punctuation holds the mouth at rest (250 ms); a space only slows the
  // cross-fade between its words (60 ms).
  WeightClip space, stop;
  REQUIRE(text_clip("ma ma", space).ok());
  REQUIRE(text_clip("ma. ma", stop).ok());
  CHECK(std::abs(stop.duration() - space.duration() - (0.25 + 0.08 - 0.06)) < 1e-9);  // the pause, the fade out of it, not the space
  const double into_pause = 0.10 + 0.08 + 0.12 + 0.12;  // "m" "a", then into the pause
  for (double t : {into_pause, into_pause + 0.12}) {
    const std::vector<double> w = clip_weights(stop, t);
    for (size_t s = 0; s < w.size(); ++s)
      if (stop.shapes[s] != "blink") CHECK(w[s] == 0.0);
  }
  CHECK(said(space) == std::vector<std::string>{"PP", "aa", "PP", "aa"});

  // Blinks every 2.8 s from 0.4 s in a long text; none in one shorter than 0.6 s.
  REQUIRE(text_clip("a", c).ok());
  CHECK(std::find(c.shapes.begin(), c.shapes.end(), "blink") == c.shapes.end());
  REQUIRE(text_clip("hello, nice to meet you. I am a head made from your own photographs", c).ok());
  INFO("duration " << c.duration());
  REQUIRE(c.duration() > 3.5);
  const auto blink = std::find(c.shapes.begin(), c.shapes.end(), "blink");
  REQUIRE(blink != c.shapes.end());
  const size_t b = static_cast<size_t>(blink - c.shapes.begin());
  CHECK(std::abs(clip_weights(c, 0.47)[b] - 1.0) < 1e-12);
  CHECK(std::abs(clip_weights(c, 3.27)[b] - 1.0) < 1e-12);
  CHECK(clip_weights(c, 1.5)[b] == 0.0);

  // Whatever the punctuation and spacing: keys strictly ascending, weights
  // within [0, 1] every 10 ms (the cross-fades never overshoot), at rest at both ends.
  for (const std::string text : {"hi!!", "...a...", "a - b", "x,y", "   a   ", "Hello, World! How are you?\nFine.",
                                  "\xc3\x9f\xc3\xbc a", "tt th ee oo ck"}) {
    INFO(text);
    REQUIRE(text_clip(text, c).ok());
    for (std::size_t k = 1; k < c.times.size(); ++k) CHECK(c.times[k] > c.times[k - 1]);
    double low = 0, high = 0;
    for (double t = 0; t <= c.duration(); t += 0.01)
      for (double v : clip_weights(c, t)) {
        low = std::min(low, v);
        high = std::max(high, v);
      }
    CHECK(low > -1e-12);
    CHECK(high < 1 + 1e-12);
    for (double v : clip_weights(c, c.duration())) CHECK(v == 0.0);
  }

  // Nothing to say: refused with a reason; a long text is cut at the limit, said.
  const std::string msg = text_clip("123 !?", c).message;
  CHECK(msg.find("nothing to say") != std::string::npos);
  CHECK_FALSE(text_clip("", c).ok());
  bool cut = false;
  REQUIRE(text_clip(std::string(kMaxSayLetters + 50, 'a') , c, &cut).ok());
  CHECK(cut);
  REQUIRE(text_clip("papa", c, &cut).ok());
  CHECK_FALSE(cut);
}
