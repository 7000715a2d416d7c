// The weight clips (anim/clips.h): Talk and Blink as cubic Hermite keys
// must play exactly the curves they are made of: visemes cross-fading by
// smoothstep from one phrase key to the next, blinks closing in 70 ms and
// opening in 130 ms. The oracle below is the page's former talkWeights
// (segment by segment), spelled here independently of clips.cpp.
#include "anim/clips.h"
#include "anim/face_shapes.h"
#include "anim/speech.h"

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

// A speech document as TalkingHead's lipsync-en writes it (web/js/speech.js):
// visemes at times and durations in its units.
Speech speech(std::vector<std::string> visemes, std::vector<double> times, std::vector<double> durations) {
  Speech s;
  s.visemes = std::move(visemes);
  s.times = std::move(times);
  s.durations = std::move(durations);
  return s;
}

double weight_of(const WeightClip& c, double t, const std::string& name) {
  const auto i = std::find(c.shapes.begin(), c.shapes.end(), name);
  return i == c.shapes.end() ? 0.0 : clip_weights(c, t)[static_cast<size_t>(i - c.shapes.begin())];
}

}  // namespace

TEST_CASE("weight clips: Say plays a speech document's visemes at their middles, rests at sil, blinks") {
  // "papa" as lipsync-en reads it: PP aa PP aa.
  const double u = kSpeechUnitSeconds;
  WeightClip c;
  REQUIRE(speech_clip(speech({"PP", "aa", "PP", "aa"}, {0, 1.08, 2.03, 3.11}, {1.08, 0.95, 1.08, 0.95}), c).ok());
  CHECK(c.name == "Say");
  CHECK(said(c) == std::vector<std::string>{"PP", "aa", "PP", "aa"});
  // Every shape it names is one of the 77 (the page and the GLB know them).
  for (const std::string& s : c.shapes)
    CHECK(std::find(face_shape_names().begin(), face_shape_names().end(), s) != face_shape_names().end());
  // Keys ascending, at rest at both ends; each viseme at its middle after
  // a 0.1 s breath, vowels at weight 1, consonants at 0.8; half way
  // between two middles, smoothstep's middle.
  for (std::size_t k = 1; k < c.times.size(); ++k) CHECK(c.times[k] > c.times[k - 1]);
  for (double v : clip_weights(c, 0.0)) CHECK(v == 0.0);
  for (double v : clip_weights(c, c.duration())) CHECK(v == 0.0);
  const double p1 = 0.1 + 0.54 * u, a1 = 0.1 + (1.08 + 0.475) * u, p2 = 0.1 + (2.03 + 0.54) * u, a2 = 0.1 + (3.11 + 0.475) * u;
  CHECK(std::abs(weight_of(c, p1, "viseme_PP") - 0.8) < 1e-12);
  CHECK(std::abs(weight_of(c, a1, "viseme_aa") - 1.0) < 1e-12);
  CHECK(std::abs(weight_of(c, p2, "viseme_PP") - 0.8) < 1e-12);
  CHECK(std::abs(weight_of(c, a2, "viseme_aa") - 1.0) < 1e-12);
  CHECK(std::abs(weight_of(c, (p1 + a1) / 2, "viseme_PP") - 0.4) < 1e-12);
  CHECK(std::abs(weight_of(c, (p1 + a1) / 2, "viseme_aa") - 0.5) < 1e-12);
  // The mouth is at rest again where the last viseme ends, 0.3 s before the clip does.
  const double end = 0.1 + (3.11 + 0.95) * u;
  for (const char* v : {"viseme_PP", "viseme_aa"}) CHECK(weight_of(c, end, v) == 0.0);
  CHECK(std::abs(c.duration() - (end + 0.3)) < 1e-12);

  // "sil" (a pause between phrases) holds the mouth at rest from its start to its end.
  REQUIRE(speech_clip(speech({"PP", "aa", "sil", "PP", "aa"}, {0, 1, 2, 4.5, 5.5}, {1, 1, 2.5, 1, 1}), c).ok());
  for (int k = 0; k <= 25; ++k) {
    const double t = 0.1 + (2 + 0.1 * k) * u;
    for (size_t s = 0; s < c.shapes.size(); ++s)
      if (c.shapes[s] != "blink") CHECK(std::abs(clip_weights(c, t)[s]) < 1e-12);
  }
  CHECK(std::abs(weight_of(c, 0.1 + 5 * u, "viseme_PP") - 0.8) < 1e-12);

  // Blinks every 2.8 s from 0.4 s in a long speech (closed 70 ms in); none in one shorter than 0.6 s.
  REQUIRE(speech_clip(speech({"aa"}, {0}, {1}), c).ok());
  CHECK(std::find(c.shapes.begin(), c.shapes.end(), "blink") == c.shapes.end());
  Speech long_one;
  for (int i = 0; i < 40; ++i) {
    long_one.visemes.push_back(i % 2 ? "aa" : "nn");
    long_one.times.push_back(i);
    long_one.durations.push_back(1);
  }
  REQUIRE(speech_clip(long_one, c).ok());
  REQUIRE(c.duration() > 3.5);
  CHECK(std::abs(weight_of(c, 0.47, "blink") - 1.0) < 1e-12);
  CHECK(std::abs(weight_of(c, 3.27, "blink") - 1.0) < 1e-12);
  CHECK(weight_of(c, 1.5, "blink") == 0.0);

  // Touching, spaced and repeated visemes, pauses anywhere: keys strictly
  // ascending, weights within [0, 1] every 10 ms, at rest at both ends.
  for (const Speech& s : {speech({"sil", "aa", "sil", "sil", "E"}, {0, 2.5, 3.5, 6, 9}, {2.5, 1, 2.5, 3, 0.01}),
                          speech({"aa", "aa", "aa"}, {0, 1, 5}, {1, 0.02, 1}),
                          speech({"O", "U", "sil"}, {0, 0.5, 0.6}, {0.5, 0.1, 2.5})}) {
    REQUIRE(speech_clip(s, c).ok());
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

  // Nothing to say (no viseme, or rests only): refused with a reason; so is a document check_speech refuses.
  CHECK(speech_clip(speech({}, {}, {}), c).message.find("nothing to say") != std::string::npos);
  CHECK(speech_clip(speech({"sil"}, {0}, {2.5}), c).message.find("nothing to say") != std::string::npos);
  CHECK(speech_clip(speech({"aa", "zz"}, {0, 1}, {1, 1}), c).code == ErrorCode::InvalidInput);
}

TEST_CASE("speech documents: read as written, refused with the field and why") {
  Speech s;
  const std::string ok = R"({"format": "likeness-speech", "version": 1, "lipsync": "x", "text": "papa",
    "visemes": ["PP", "aa", "PP", "aa"], "times": [0, 1.08, 2.03, 3.11], "durations": [1.08, 0.95, 1.08, 0.95]})";
  REQUIRE(parse_speech_json(ok, s).ok());
  CHECK(s.text == "papa");
  CHECK(s.visemes == std::vector<std::string>{"PP", "aa", "PP", "aa"});
  CHECK(s.times == std::vector<double>{0, 1.08, 2.03, 3.11});
  CHECK(s.durations == std::vector<double>{1.08, 0.95, 1.08, 0.95});

  auto refused = [&](const std::string& text) {
    const Status st = parse_speech_json(text, s);
    CHECK_FALSE(st.ok());
    CHECK(s.visemes.empty());
    return st.message;
  };
  auto doc = [](const std::string& visemes, const std::string& times, const std::string& durations) {
    return R"({"format": "likeness-speech", "version": 1, "visemes": )" + visemes + R"(, "times": )" + times +
           R"(, "durations": )" + durations + "}";
  };
  CHECK(refused("hello").find("not valid JSON") != std::string::npos);
  CHECK(refused("[1, 2]").find("not a JSON object") != std::string::npos);
  CHECK(refused(R"({"format": "likeness-landmarks", "version": 1})").find("format") != std::string::npos);
  CHECK(refused(R"({"format": "likeness-speech", "version": 2})").find("version") != std::string::npos);
  CHECK(refused(doc(R"(["PP", "viseme_aa"])", "[0, 1]", "[1, 1]")).find("visemes[1]") != std::string::npos);
  CHECK(refused(doc(R"(["PP", 3])", "[0, 1]", "[1, 1]")).find("visemes") != std::string::npos);
  CHECK(refused(doc(R"(["PP", "aa"])", "[0]", "[1, 1]")).find("one entry per viseme") != std::string::npos);
  CHECK(refused(doc(R"(["PP", "aa"])", "[0, 0.5]", "[1, 1]")).find("before the viseme before it ends") != std::string::npos);
  CHECK(refused(doc(R"(["PP", "aa"])", "[0, -1]", "[1, 1]")).find("times[1]") != std::string::npos);
  CHECK(refused(doc(R"(["PP"])", "[0]", "[0]")).find("durations[0]") != std::string::npos);
  CHECK(refused(doc(R"(["PP"])", "[0]", R"(["1"])")).find("durations") != std::string::npos);
  CHECK(refused(doc(R"(["PP"])", "[5999.5]", "[1]")).find("units") != std::string::npos);
  CHECK(refused(std::string(kMaxSpeechBytes + 1, ' ')).find("at most") != std::string::npos);
  CHECK(refused(std::string(100000, '[')).find("not valid JSON") != std::string::npos);
  std::string many = "[";
  for (std::size_t i = 0; i <= kMaxSpeechVisemes; ++i) many += i ? ", \"aa\"" : "\"aa\"";
  CHECK(refused(doc(many + "]", "[]", "[]")).find("at most") != std::string::npos);
}
