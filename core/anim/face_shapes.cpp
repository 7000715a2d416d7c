#include "anim/face_shapes.h"

#include <algorithm>
#include <cmath>
#include <utility>

namespace lk {

namespace {

using Recipe = std::vector<std::pair<int, double>>;

// Channel L/R pairs are adjacent (face_controls.h): side 0 = left, 1 = right.
Recipe both(int left_channel, double v) { return {{left_channel, v}, {left_channel + 1, v}}; }
Recipe operator+(Recipe a, const Recipe& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

const std::vector<std::pair<std::string, Recipe>>& recipes() {
  static const std::vector<std::pair<std::string, Recipe>> table = [] {
    std::vector<std::pair<std::string, Recipe>> t;
    // Expressions.
    t.push_back({"neutral", {}});
    t.push_back({"smile", both(kZygomaticMajorL, 1.0) + both(kOculiL, 0.4) + both(kLowerLidL, 0.2)});
    t.push_back({"openMouth", Recipe{{kJawOpen, 1.0}} + both(kDepressorLabiiL, 0.4)});
    t.push_back({"surprise", both(kFrontalisInnerL, 1.0) + both(kFrontalisOuterL, 1.0) + both(kLidL, -1.0) +
                                 Recipe{{kJawOpen, 0.5}}});
    t.push_back({"anger", both(kCorrugatorL, 1.0) + Recipe{{kProcerus, 1.0}} + both(kLowerLidL, 0.5) +
                              both(kPressL, 0.6) + both(kLevatorNasiL, 0.3)});
    t.push_back({"sadness", both(kFrontalisInnerL, 1.0) + both(kCorrugatorL, 0.4) + both(kDepressorAnguliL, 1.0) +
                                both(kMentalisL, 0.4) + both(kLidL, 0.2)});
    t.push_back({"disgust", both(kLevatorNasiL, 1.0) + both(kLevatorLabiiL, 0.6) + both(kCorrugatorL, 0.4) +
                                both(kLowerLidL, 0.4) + both(kMentalisL, 0.3)});
    t.push_back({"fear", both(kFrontalisInnerL, 1.0) + both(kFrontalisOuterL, 0.6) + both(kCorrugatorL, 0.5) +
                             both(kLidL, -1.0) + both(kRisoriusL, 0.8) + Recipe{{kJawOpen, 0.25}}});
    t.push_back({"blink", both(kLidL, 1.0)});
    t.push_back({"wink", Recipe{{kLidL, 1.0}, {kOculiL, 0.4}, {kZygomaticMajorL, 0.2}}});
    // ARKit, per side (Left = the face's left = channel side 0).
    for (int s = 0; s < 2; ++s) {
      const std::string side = s == 0 ? "Left" : "Right";
      const double in = s == 0 ? -1.0 : 1.0;  // yaw towards the nose
      t.push_back({"eyeBlink" + side, {{kLidL + s, 1.0}}});
      t.push_back({"eyeLookDown" + side, {{kGazePitchL + s, -1.0}}});
      t.push_back({"eyeLookIn" + side, {{kGazeYawL + s, in}}});
      t.push_back({"eyeLookOut" + side, {{kGazeYawL + s, -in}}});
      t.push_back({"eyeLookUp" + side, {{kGazePitchL + s, 1.0}}});
      t.push_back({"eyeSquint" + side, {{kLowerLidL + s, 1.0}, {kOculiL + s, 0.5}}});
      t.push_back({"eyeWide" + side, {{kLidL + s, -1.0}}});
    }
    t.push_back({"jawForward", {{kJawForward, 1.0}}});
    t.push_back({"jawLeft", {{kJawSide, 1.0}}});
    t.push_back({"jawRight", {{kJawSide, -1.0}}});
    t.push_back({"jawOpen", {{kJawOpen, 1.0}}});
    t.push_back({"mouthClose", both(kPressL, 0.8) + Recipe{{kOrisPucker, 0.15}}});
    t.push_back({"mouthFunnel", Recipe{{kOrisPucker, 0.6}, {kJawOpen, 0.15}, {kShrugUpper, 0.5}} + both(kDepressorLabiiL, 0.3)});
    t.push_back({"mouthPucker", Recipe{{kOrisPucker, 1.0}} + both(kPressL, 0.3)});
    t.push_back({"mouthLeft", {{kMouthShift, 1.0}}});
    t.push_back({"mouthRight", {{kMouthShift, -1.0}}});
    for (int s = 0; s < 2; ++s) {
      const std::string side = s == 0 ? "Left" : "Right";
      t.push_back({"mouthSmile" + side, {{kZygomaticMajorL + s, 1.0}}});
    }
    for (int s = 0; s < 2; ++s) t.push_back({std::string("mouthFrown") + (s ? "Right" : "Left"), {{kDepressorAnguliL + s, 1.0}}});
    for (int s = 0; s < 2; ++s) t.push_back({std::string("mouthDimple") + (s ? "Right" : "Left"), {{kBuccinatorL + s, 1.0}}});
    for (int s = 0; s < 2; ++s)
      t.push_back({std::string("mouthStretch") + (s ? "Right" : "Left"), {{kRisoriusL + s, 1.0}, {kDepressorAnguliL + s, 0.3}}});
    t.push_back({"mouthRollLower", {{kRollLower, 1.0}}});
    t.push_back({"mouthRollUpper", {{kRollUpper, 1.0}}});
    t.push_back({"mouthShrugLower", both(kMentalisL, 1.0)});
    t.push_back({"mouthShrugUpper", {{kShrugUpper, 1.0}}});
    for (int s = 0; s < 2; ++s)
      t.push_back({std::string("mouthPress") + (s ? "Right" : "Left"), {{kPressL + s, 1.0}, {kBuccinatorL + s, 0.3}}});
    for (int s = 0; s < 2; ++s) t.push_back({std::string("mouthLowerDown") + (s ? "Right" : "Left"), {{kDepressorLabiiL + s, 1.0}}});
    for (int s = 0; s < 2; ++s) t.push_back({std::string("mouthUpperUp") + (s ? "Right" : "Left"), {{kLevatorLabiiL + s, 1.0}}});
    for (int s = 0; s < 2; ++s) t.push_back({std::string("browDown") + (s ? "Right" : "Left"), {{kCorrugatorL + s, 1.0}}});
    t.push_back({"browInnerUp", both(kFrontalisInnerL, 1.0)});
    for (int s = 0; s < 2; ++s) t.push_back({std::string("browOuterUp") + (s ? "Right" : "Left"), {{kFrontalisOuterL + s, 1.0}}});
    t.push_back({"cheekPuff", {{kCheekPuff, 1.0}}});
    for (int s = 0; s < 2; ++s) t.push_back({std::string("cheekSquint") + (s ? "Right" : "Left"), {{kOculiL + s, 1.0}}});
    for (int s = 0; s < 2; ++s) t.push_back({std::string("noseSneer") + (s ? "Right" : "Left"), {{kLevatorNasiL + s, 1.0}}});
    t.push_back({"tongueOut", {{kTongueOut, 1.0}, {kJawOpen, 0.45}}});
    // Visemes (OVRLipSync's 15).
    t.push_back({"viseme_sil", {}});
    t.push_back({"viseme_PP", both(kPressL, 1.0) + Recipe{{kRollUpper, 0.3}, {kRollLower, 0.3}}});
    t.push_back({"viseme_FF", Recipe{{kRollLower, 0.8}, {kJawOpen, 0.12}, {kShrugUpper, 0.3}} + both(kLevatorLabiiL, 0.3)});
    t.push_back({"viseme_TH", {{kJawOpen, 0.2}, {kTongueOut, 0.4}}});
    t.push_back({"viseme_DD", Recipe{{kJawOpen, 0.3}} + both(kRisoriusL, 0.2)});
    t.push_back({"viseme_kk", Recipe{{kJawOpen, 0.35}} + both(kRisoriusL, 0.35)});
    t.push_back({"viseme_CH", {{kOrisPucker, 0.6}, {kJawOpen, 0.2}, {kShrugUpper, 0.4}}});
    t.push_back({"viseme_SS", Recipe{{kJawOpen, 0.1}} + both(kRisoriusL, 0.5) + both(kZygomaticMajorL, 0.2)});
    t.push_back({"viseme_nn", Recipe{{kJawOpen, 0.22}} + both(kRisoriusL, 0.2)});
    t.push_back({"viseme_RR", {{kOrisPucker, 0.5}, {kJawOpen, 0.2}}});
    t.push_back({"viseme_aa", Recipe{{kJawOpen, 0.75}} + both(kDepressorLabiiL, 0.3)});
    t.push_back({"viseme_E", Recipe{{kJawOpen, 0.4}} + both(kRisoriusL, 0.5) + both(kZygomaticMajorL, 0.2)});
    t.push_back({"viseme_I", Recipe{{kJawOpen, 0.2}} + both(kRisoriusL, 0.6) + both(kZygomaticMajorL, 0.4)});
    t.push_back({"viseme_O", {{kJawOpen, 0.55}, {kOrisPucker, 0.7}}});
    t.push_back({"viseme_U", {{kOrisPucker, 1.0}, {kJawOpen, 0.15}}});
    return t;
  }();
  return table;
}

std::vector<std::string> names_between(std::size_t from, std::size_t to) {
  std::vector<std::string> out;
  for (std::size_t i = from; i < to; ++i) out.push_back(recipes()[i].first);
  return out;
}

const std::vector<std::string> kArkitOrder = {
    "eyeBlinkLeft", "eyeLookDownLeft", "eyeLookInLeft", "eyeLookOutLeft", "eyeLookUpLeft", "eyeSquintLeft", "eyeWideLeft",
    "eyeBlinkRight", "eyeLookDownRight", "eyeLookInRight", "eyeLookOutRight", "eyeLookUpRight", "eyeSquintRight",
    "eyeWideRight", "jawForward", "jawLeft", "jawRight", "jawOpen", "mouthClose", "mouthFunnel", "mouthPucker",
    "mouthLeft", "mouthRight", "mouthSmileLeft", "mouthSmileRight", "mouthFrownLeft", "mouthFrownRight",
    "mouthDimpleLeft", "mouthDimpleRight", "mouthStretchLeft", "mouthStretchRight", "mouthRollLower", "mouthRollUpper",
    "mouthShrugLower", "mouthShrugUpper", "mouthPressLeft", "mouthPressRight", "mouthLowerDownLeft",
    "mouthLowerDownRight", "mouthUpperUpLeft", "mouthUpperUpRight", "browDownLeft", "browDownRight", "browInnerUp",
    "browOuterUpLeft", "browOuterUpRight", "cheekPuff", "cheekSquintLeft", "cheekSquintRight", "noseSneerLeft",
    "noseSneerRight", "tongueOut"};

}  // namespace

const std::vector<std::string>& expression_names() {
  static const std::vector<std::string> v = names_between(0, 10);
  return v;
}
const std::vector<std::string>& arkit_names() { return kArkitOrder; }
const std::vector<std::string>& viseme_names() {
  static const std::vector<std::string> v = names_between(recipes().size() - 15, recipes().size());
  return v;
}
const std::vector<std::string>& face_shape_names() {
  static const std::vector<std::string> v = [] {
    std::vector<std::string> all = expression_names();
    all.insert(all.end(), arkit_names().begin(), arkit_names().end());
    all.insert(all.end(), viseme_names().begin(), viseme_names().end());
    return all;
  }();
  return v;
}

Status face_shape(const std::string& name, FaceControls& out) {
  for (const auto& [n, recipe] : recipes())
    if (n == name) {
      out = FaceControls{};
      for (const auto& [channel, value] : recipe) out[channel] += value;
      out.clamp();
      return Status::success();
    }
  return Status::error(ErrorCode::InvalidInput, "no face shape named '" + name + "'");
}

Status face_controls_from_weights(const std::map<std::string, double>& weights, FaceControls& out) {
  FaceControls sum;
  for (const auto& [name, weight] : weights) {
    FaceControls one;
    if (Status s = face_shape(name, one); !s.ok()) return s;
    const double w = std::isfinite(weight) ? std::clamp(weight, 0.0, 1.0) : 0.0;
    for (int c = 0; c < kChannelCount; ++c) sum[c] += w * one[c];
  }
  sum.clamp();
  out = sum;
  return Status::success();
}

}  // namespace lk
