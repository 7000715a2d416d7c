// The generic head a harness command works with: "asset" (the committed
// core/head/data/generic_head.{obj,json}, what the app uses), or "plate" /
// "ring" (built now by generic_head_builder with GenericHeadBuildOptions::
// ring_ear off or on) or "even" (the plate with even_eye_corners), so a
// builder change can be measured on the same scans before the asset is
// regenerated (docs/generic_head.md).
#pragma once
#include "head/generic_head.h"
#include "head/generic_head_builder.h"

#include <string>

namespace lk::cli {

inline Status choose_generic_head(const std::string& which, GenericHead& out) {
  if (which == "asset") return load_generic_head(out);
  if (which == "plate" || which == "ring" || which == "even") {
    GenericHeadBuildOptions options;
    options.ring_ear = which == "ring";
    options.even_eye_corners = which == "even";
    return build_generic_head(options, out);
  }
  return Status::error(ErrorCode::InvalidInput, "unknown generic head '" + which + "' (asset, plate, ring or even)");
}

}  // namespace lk::cli
