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
