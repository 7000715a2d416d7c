// The muscle layer's channels: one activation per muscle (each side its
// own), per sphincter, per extra skin action, and the kinematic ones (jaw,
// lids, gaze, tongue). A shape (face_shapes.h) is a set of channel values.
#pragma once
#include "common/types.h"

#include <array>
#include <string>

namespace lk {

enum Channel : int {
  // Waters linear muscles (L = the head's left, +x).
  kFrontalisInnerL, kFrontalisInnerR, kFrontalisOuterL, kFrontalisOuterR,
  kCorrugatorL, kCorrugatorR, kProcerus,
  kZygomaticMajorL, kZygomaticMajorR, kZygomaticMinorL, kZygomaticMinorR,
  kLevatorLabiiL, kLevatorLabiiR, kLevatorNasiL, kLevatorNasiR,
  kDepressorAnguliL, kDepressorAnguliR, kDepressorLabiiL, kDepressorLabiiR,
  kMentalisL, kMentalisR, kBuccinatorL, kBuccinatorR, kRisoriusL, kRisoriusR,
  // Sphincters: orbicularis oris (pucker: narrows and pushes the lips out),
  // orbicularis oculi per side (pulls the skin around the eye inwards).
  kOrisPucker, kOculiL, kOculiR,
  // Skin actions no single linear muscle makes: cheeks blown out, lips
  // rolled in, pressed together per side, the mouth shifted sideways
  // (+: to the head's left), the upper lip shrugged up.
  kCheekPuff, kRollUpper, kRollLower, kPressL, kPressR, kMouthShift, kShrugUpper,
  // Kinematic: the jaw (open, side +: to the left, forward), the upper lids
  // (+1 closed, -1 wide open), the lower lids raised, gaze per eye (yaw +:
  // towards the head's left, pitch +: up; 1 = 25 degrees), the tongue out.
  kJawOpen, kJawSide, kJawForward,
  kLidL, kLidR, kLowerLidL, kLowerLidR,
  kGazeYawL, kGazeYawR, kGazePitchL, kGazePitchR,
  kTongueOut,
  kChannelCount
};

constexpr int kFirstKinematicChannel = kJawOpen;

// The channel's name ("zygomatic_major_left", "jaw_open", ...).
const char* channel_name(int channel);
// Signed channels take [-1, 1], the others [0, 1].
bool channel_signed(int channel);

struct FaceControls {
  std::array<double, kChannelCount> value{};  // zero: the rest pose
  double& operator[](int c) { return value[static_cast<std::size_t>(c)]; }
  double operator[](int c) const { return value[static_cast<std::size_t>(c)]; }
  // Each value into its channel's range (NaN: 0).
  void clamp();
  bool any() const;
};

// The jaw's turn at full opening (radians), its glide forward per unit of
// opening, its sideways and forward travel (metres on the generic head's
// scale; FaceRig::scale), the gaze's full turn.
constexpr double kJawOpenAngle = 0.22;
constexpr double kJawOpenGlide = 0.0015;
constexpr double kJawSideShift = 0.006;
constexpr double kJawForwardShift = 0.006;
constexpr double kGazeAngle = 25.0 * 3.14159265358979323846 / 180.0;

}  // namespace lk
