#include "anim/speech.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <utility>

#include "anim/face_shapes.h"
#include "common/json_depth.h"

namespace lk {
namespace {

using Json = nlohmann::json;

Status invalid(const std::string& field, const std::string& what) {
  return Status::error(ErrorCode::InvalidInput, "speech " + field + ": " + what);
}

bool is_viseme(const std::string& name) {
  const std::vector<std::string>& names = viseme_names();
  return std::find(names.begin(), names.end(), "viseme_" + name) != names.end();
}

// The document's array `key` of at most kMaxSpeechVisemes entries.
Status array_of(const Json& root, const char* key, const Json*& out) {
  auto a = root.find(key);
  if (a == root.end() || !a->is_array()) return invalid(key, "must be an array");
  if (a->size() > kMaxSpeechVisemes)
    return invalid(key, std::to_string(a->size()) + " entries, at most " + std::to_string(kMaxSpeechVisemes));
  out = &*a;
  return Status::success();
}

}  // namespace

Status check_speech(const Speech& s) {
  const std::size_t n = s.visemes.size();
  if (n > kMaxSpeechVisemes) return invalid("visemes", std::to_string(n) + ", at most " + std::to_string(kMaxSpeechVisemes));
  if (s.times.size() != n || s.durations.size() != n)
    return invalid("times", "times and durations need one entry per viseme (" + std::to_string(n) + ")");
  for (std::size_t i = 0; i < n; ++i) {
    const std::string at = "[" + std::to_string(i) + "]";
    if (!is_viseme(s.visemes[i])) return invalid("visemes" + at, "\"" + s.visemes[i].substr(0, 40) + "\" is not a viseme (sil PP FF TH DD kk CH SS nn RR aa E I O U)");
    const double t = s.times[i], d = s.durations[i];
    if (!std::isfinite(t) || t < 0) return invalid("times" + at, "must be a finite time >= 0");
    if (!std::isfinite(d) || d < 0.01 || d > 100) return invalid("durations" + at, "must be within 0.01..100");
    if (i > 0 && t < s.times[i - 1] + s.durations[i - 1] - 1e-6)
      return invalid("times" + at, "starts before the viseme before it ends");
    if (t + d > kMaxSpeechUnits) return invalid("times" + at, "ends past " + std::to_string(int(kMaxSpeechUnits)) + " units");
  }
  return Status::success();
}

Status parse_speech_json(const std::string& text, Speech& speech) {
  speech = {};
  Speech out;  // handed over only when whole
  if (text.size() > kMaxSpeechBytes)
    return Status::error(ErrorCode::TooLarge, "speech document of " + std::to_string(text.size()) + " bytes, at most " +
                                                  std::to_string(kMaxSpeechBytes));
  constexpr int kMaxDepth = 8;  // the document nests 2 deep
  const Json root = json_nested_deeper(text, kMaxDepth) ? Json(Json::value_t::discarded)
                                                        : Json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (root.is_discarded()) return invalid("document", "not valid JSON");
  if (!root.is_object()) return invalid("document", "not a JSON object");
  auto f = root.find("format");
  if (f == root.end() || !f->is_string() || f->get<std::string>() != "likeness-speech")
    return invalid("format", "must be \"likeness-speech\" (scripts/say writes it)");
  auto v = root.find("version");
  if (v == root.end() || !v->is_number_integer() || v->get<long long>() != 1)
    return invalid("version", "must be 1 (the only version this build reads)");
  auto t = root.find("text");
  if (t != root.end()) {
    if (!t->is_string() || t->get<std::string>().size() > 4096) return invalid("text", "must be a string of at most 4096 bytes");
    out.text = t->get<std::string>();
  }
  const Json *visemes = nullptr, *times = nullptr, *durations = nullptr;
  for (auto [key, a] : {std::pair{"visemes", &visemes}, std::pair{"times", &times}, std::pair{"durations", &durations}})
    if (Status s = array_of(root, key, *a); !s) return s;
  for (const Json& name : *visemes) {
    if (!name.is_string()) return invalid("visemes", "must be names (strings)");
    out.visemes.push_back(name.get<std::string>());
  }
  for (auto [a, to] : {std::pair{times, &out.times}, std::pair{durations, &out.durations}})
    for (const Json& x : *a) {
      if (!x.is_number()) return invalid(a == times ? "times" : "durations", "must be numbers");
      to->push_back(x.get<double>());
    }
  if (Status s = check_speech(out); !s) return s;
  speech = std::move(out);
  return Status::success();
}

}  // namespace lk
