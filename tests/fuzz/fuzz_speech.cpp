// libFuzzer target: the speech documents of `likeness export --say` and the
// page's Talk (parse_speech_json), then the Say clip made from a document
// it accepts. A success holds one time and duration per viseme, passes
// check_speech, and makes a clip (or says there is nothing to say) whose
// keys ascend and whose weights at the keys lie in [0, 1].
#include "fuzz_check.h"
#include "anim/clips.h"
#include "anim/speech.h"

#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  lk::Speech speech;
  const lk::Status s = lk::fuzz::watched(size, [&] { return lk::parse_speech_json(text, speech); });
  if (!s) {
    lk::fuzz::require(!s.message.empty() && speech.visemes.empty());
    return 0;
  }
  lk::fuzz::require(speech.times.size() == speech.visemes.size() && speech.durations.size() == speech.visemes.size() &&
                    speech.visemes.size() <= lk::kMaxSpeechVisemes && lk::check_speech(speech).ok());
  lk::WeightClip clip;
  const lk::Status c = lk::speech_clip(speech, clip);
  if (!c) {
    lk::fuzz::require(!c.message.empty());
    return 0;
  }
  lk::fuzz::require(!clip.times.empty() && clip.times.front() == 0 && clip.value.size() == clip.times.size());
  for (size_t k = 0; k < clip.times.size(); ++k) {
    lk::fuzz::require(k == 0 || clip.times[k] > clip.times[k - 1]);
    for (double w : clip.value[k]) lk::fuzz::require(w >= 0 && w <= 1);
  }
  return 0;
}
