#include "anim/clips.h"

#include <algorithm>
#include <cmath>

namespace lk {

namespace {

// A shape's own keys: its weight at each, smoothstep between them (zero
// slope at every own key), flat outside.
struct Track {
  std::vector<double> t, w;
  // Value and slope at time x.
  void at(double x, double& v, double& d) const {
    if (t.empty() || x <= t.front() || x >= t.back()) {
      v = t.empty() ? 0.0 : x <= t.front() ? w.front() : w.back();
      d = 0;
      return;
    }
    std::size_t k = static_cast<std::size_t>(std::upper_bound(t.begin(), t.end(), x) - t.begin()) - 1;
    const double h = t[k + 1] - t[k], u = (x - t[k]) / h;
    v = w[k] + (w[k + 1] - w[k]) * u * u * (3 - 2 * u);
    d = (w[k + 1] - w[k]) * 6 * u * (1 - u) / h;
  }
};

// The clip of tracks sampled at the union of their keys: each key's value
// and slope are the track's, so the Hermite cubic between two union keys is
// the track's smoothstep piece (or a part of it) exactly.
WeightClip clip_of(const std::string& name, const std::vector<std::pair<std::string, Track>>& tracks) {
  WeightClip c;
  c.name = name;
  std::vector<double> times;
  for (const auto& [shape, track] : tracks) {
    c.shapes.push_back(shape);
    times.insert(times.end(), track.t.begin(), track.t.end());
  }
  times.push_back(0.0);
  std::sort(times.begin(), times.end());
  for (double x : times)
    if (c.times.empty() || x - c.times.back() > 1e-9) c.times.push_back(x);
  for (double x : c.times) {
    std::vector<double> v(tracks.size()), d(tracks.size());
    for (std::size_t s = 0; s < tracks.size(); ++s) tracks[s].second.at(x, v[s], d[s]);
    c.value.push_back(v);
    c.slope.push_back(d);
  }
  return c;
}

// Blinks starting at `starts`: closed in 70 ms, open again 130 ms later.
Track blinks(const std::vector<double>& starts) {
  Track b;
  for (double s : starts) {
    b.t.insert(b.t.end(), {s, s + 0.07, s + 0.20});
    b.w.insert(b.w.end(), {0.0, 1.0, 0.0});
  }
  return b;
}

// Poses at times: each shape named in any pose gets a track keyed at every
// pose's time with its weight there (0 where the pose leaves it out), so
// consecutive poses cross-fade by smoothstep.
using Pose = std::pair<double, std::vector<std::pair<std::string, double>>>;
std::vector<std::pair<std::string, Track>> pose_tracks(const std::vector<Pose>& poses) {
  std::vector<std::pair<std::string, Track>> tracks;
  for (const Pose& p : poses)
    for (const auto& named : p.second)
      if (std::none_of(tracks.begin(), tracks.end(), [&](const auto& t) { return t.first == named.first; }))
        tracks.emplace_back(named.first, Track{});
  for (const Pose& p : poses)
    for (auto& [name, track] : tracks) {
      double w = 0;
      for (const auto& [n, x] : p.second) w += n == name ? x : 0.0;
      track.t.push_back(p.first);
      track.w.push_back(w);
    }
  return tracks;
}

WeightClip make_talk() {
  // "hello, nice to meet you": a viseme per key (none: the rest).
  const std::vector<Pose> phrase = {
      {0.00, {}}, {0.12, {{"viseme_kk", 0.5}}}, {0.22, {{"viseme_E", 0.9}}}, {0.32, {{"viseme_nn", 0.7}}},
      {0.46, {{"viseme_O", 1.0}}}, {0.62, {{"viseme_U", 0.5}}}, {0.80, {}},                       // hello,
      {0.92, {{"viseme_nn", 0.8}}}, {1.04, {{"viseme_aa", 1.0}}}, {1.16, {{"viseme_I", 0.8}}},  // nice
      {1.28, {{"viseme_SS", 0.9}}}, {1.38, {{"viseme_DD", 0.8}}}, {1.48, {{"viseme_U", 0.8}}},  // to
      {1.58, {{"viseme_PP", 1.0}}}, {1.72, {{"viseme_I", 1.0}}}, {1.84, {{"viseme_DD", 0.7}}},  // meet
      {1.92, {{"viseme_I", 0.6}}}, {2.08, {{"viseme_U", 1.0}}}, {2.30, {}},                     // you
      {2.60, {}},
  };
  std::vector<std::pair<std::string, Track>> tracks = pose_tracks(phrase);
  tracks.emplace_back("blink", blinks({0.40, 2.20}));
  return clip_of("Talk", tracks);
}

// The eyes look to the head's left, to its right, up, and back (ARKit's
// eyeLook shapes: Out of the left eye is to the head's left).
WeightClip make_gaze() {
  const std::vector<std::pair<std::string, double>> left = {{"eyeLookOutLeft", 1.0}, {"eyeLookInRight", 1.0}},
                                                    right = {{"eyeLookInLeft", 1.0}, {"eyeLookOutRight", 1.0}},
                                                    up = {{"eyeLookUpLeft", 0.6}, {"eyeLookUpRight", 0.6}};
  return clip_of("Gaze", pose_tracks({{0.0, {}}, {0.4, left}, {0.9, left}, {1.3, right}, {1.8, right}, {2.2, up},
                                      {2.6, up}, {3.0, {}}}));
}

bool is_vowel_viseme(const std::string& v) { return v == "aa" || v == "E" || v == "I" || v == "O" || v == "U"; }

}  // namespace

Status speech_clip(const Speech& speech, WeightClip& out) {
  if (Status s = check_speech(speech); !s) return s;
  constexpr double kBreath = 0.10, kBlinkEvery = 2.8;
  std::vector<Pose> poses = {{0.0, {}}};
  // A rest key where the last one is not a rest at that time already.
  auto rest_at = [&](double t) {
    if (!(poses.back().second.empty() && t <= poses.back().first + 1e-9)) poses.push_back({t, {}});
  };
  double end = kBreath;
  bool said = false;
  for (std::size_t i = 0; i < speech.visemes.size(); ++i) {
    const std::string& v = speech.visemes[i];
    const double start = kBreath + speech.times[i] * kSpeechUnitSeconds;
    end = start + speech.durations[i] * kSpeechUnitSeconds;
    if (v == "sil") {
      rest_at(start);
      rest_at(end);
      continue;
    }
    poses.push_back({(start + end) / 2, {{"viseme_" + v, is_vowel_viseme(v) ? 1.0 : 0.8}}});
    said = true;
  }
  if (!said) return Status::error(ErrorCode::InvalidInput, "there is nothing to say: type some words");
  rest_at(end);
  poses.push_back({poses.back().first + 0.3, {}});  // a moment at rest to end
  std::vector<std::pair<std::string, Track>> tracks = pose_tracks(poses);
  std::vector<double> starts;
  for (double b = 0.4; b + 0.2 <= poses.back().first; b += kBlinkEvery) starts.push_back(b);
  if (!starts.empty()) tracks.emplace_back("blink", blinks(starts));
  out = clip_of("Say", tracks);
  return Status::success();
}

const WeightClip& talk_clip() {
  static const WeightClip clip = make_talk();
  return clip;
}

const WeightClip& blink_clip() {
  static const WeightClip clip = clip_of("Blink", {{"blink", blinks({0.0})}});
  return clip;
}

const WeightClip& gaze_clip() {
  static const WeightClip clip = make_gaze();
  return clip;
}

std::vector<WeightClip> weight_clips() { return {talk_clip(), blink_clip(), gaze_clip()}; }

std::vector<double> clip_weights(const WeightClip& clip, double t) {
  const std::size_t n = clip.shapes.size();
  if (clip.times.empty()) return std::vector<double>(n, 0.0);
  if (!(t > clip.times.front())) return clip.value.front();
  if (t >= clip.times.back()) return clip.value.back();
  const std::size_t k = static_cast<std::size_t>(std::upper_bound(clip.times.begin(), clip.times.end(), t) - clip.times.begin()) - 1;
  const double h = clip.times[k + 1] - clip.times[k], u = (t - clip.times[k]) / h;
  // glTF's cubic Hermite (CUBICSPLINE), tangents scaled by the interval.
  const double h00 = 2 * u * u * u - 3 * u * u + 1, h10 = u * u * u - 2 * u * u + u;
  const double h01 = -2 * u * u * u + 3 * u * u, h11 = u * u * u - u * u;
  std::vector<double> out(n);
  for (std::size_t s = 0; s < n; ++s)
    out[s] = h00 * clip.value[k][s] + h10 * h * clip.slope[k][s] + h01 * clip.value[k + 1][s] +
             h11 * h * clip.slope[k + 1][s];
  return out;
}

}  // namespace lk
