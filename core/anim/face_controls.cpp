#include "anim/face_controls.h"

namespace lk {

const char* channel_name(int channel) {
  static const char* const names[kChannelCount] = {
      "frontalis_inner_left", "frontalis_inner_right", "frontalis_outer_left", "frontalis_outer_right",
      "corrugator_left", "corrugator_right", "procerus",
      "zygomatic_major_left", "zygomatic_major_right", "zygomatic_minor_left", "zygomatic_minor_right",
      "levator_labii_left", "levator_labii_right", "levator_labii_alaeque_nasi_left", "levator_labii_alaeque_nasi_right",
      "depressor_anguli_oris_left", "depressor_anguli_oris_right", "depressor_labii_left", "depressor_labii_right",
      "mentalis_left", "mentalis_right", "buccinator_left", "buccinator_right", "risorius_left", "risorius_right",
      "orbicularis_oris", "orbicularis_oculi_left", "orbicularis_oculi_right",
      "cheek_puff", "lip_roll_upper", "lip_roll_lower", "lip_press_left", "lip_press_right", "mouth_shift", "lip_shrug_upper",
      "jaw_open", "jaw_side", "jaw_forward",
      "lid_left", "lid_right", "lower_lid_left", "lower_lid_right",
      "gaze_yaw_left", "gaze_yaw_right", "gaze_pitch_left", "gaze_pitch_right",
      "tongue_out"};
  return channel >= 0 && channel < kChannelCount ? names[channel] : "";
}

bool channel_signed(int channel) {
  return channel == kMouthShift || channel == kJawSide || channel == kLidL || channel == kLidR ||
         channel == kGazeYawL || channel == kGazeYawR || channel == kGazePitchL || channel == kGazePitchR;
}

}  // namespace lk
