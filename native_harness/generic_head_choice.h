// The generic head a harness command works with: "asset" (the committed
// core/head/data/generic_head.{obj,json}, what the app uses), or one built
// now by generic_head_builder, so a builder change can be measured on the
// same scans before the asset is regenerated (docs/journal.md):
// "plate" the plate ear with the eye rings' corners at 45 deg (the asset
// before 3a8dc46), "ring" the ring ear with the same 45-degree corners (as
// it was measured), "even" the plate ear with even corners (the asset's
// layout from 3a8dc46 until the back's rows were evened), "back" the plate
// ear with even corners and even rows behind the ears (the asset's layout
// from 8518b1e until the nape was made regular), "nape" that with the
// regular nape (the asset's until its quads were split as their mirror
// images, issue 35), "wide-mouth" the builder's default with the wider
// ring round the mouth (docs/design/generic_head_measured.md), "nostrils"
// the builder's default with open nostrils (docs/design/generic_head.md).
#pragma once
#include <cstdlib>
#include "head/generic_head.h"
#include "head/generic_head_builder.h"

#include <string>

namespace lk::cli {

inline Status choose_generic_head(const std::string& which, GenericHead& out) {
  if (which == "asset") return load_generic_head(out);
  if (which == "nostrils") {  // the asset's builder with open nostrils (issue 35, not the asset's yet)
    GenericHeadBuildOptions options;
    options.nostrils = true;
    return build_generic_head(options, out);
  }
  if (which == "wide-mouth") {
    GenericHeadBuildOptions options;
    options.wide_mouth_ring = true;
    options.fair_iterations = 0;  // as measured before the skin was faired
    return build_generic_head(options, out);
  }
  // unfaired: the asset's builder with the skin as cast (the asset's);
  // fair-N: with N fairing passes (issue 35's, not landed).
  if (which == "unfaired" || which.rfind("fair-", 0) == 0) {
    GenericHeadBuildOptions options;
    options.fair_iterations = which == "unfaired" ? 0 : std::atoi(which.c_str() + 5);
    // fair-N-rK: the K rings round the rims and lip lines kept as cast too.
    if (const size_t r = which.find("-r", 5); r != std::string::npos)
      options.fair_keep_rim_rings = std::atoi(which.c_str() + r + 2);
    if (options.fair_iterations < 0 || options.fair_iterations > 100)
      return Status::error(ErrorCode::InvalidInput, "fair-N needs N in 0..100");
    return build_generic_head(options, out);
  }
  if (which == "plate" || which == "ring" || which == "even" || which == "back" || which == "nape") {
    GenericHeadBuildOptions options;
    options.ring_ear = which == "ring";
    options.even_eye_corners = which == "even" || which == "back" || which == "nape";
    options.even_back_rows = which == "back" || which == "nape";
    options.regular_nape = which == "nape";
    options.mirror_diagonals = false;
    options.fair_iterations = 0;
    return build_generic_head(options, out);
  }
  return Status::error(ErrorCode::InvalidInput, "unknown generic head '" + which + "' (asset, plate, ring, even, back, nape, wide-mouth, nostrils, unfaired or fair-N)");
}

}  // namespace lk::cli
