// Progress reporting with cancellation, passed into long stages (never global).
#pragma once
#include <functional>

namespace lk {

// Called with the stage's name and its completed fraction in [0,1]. Returns
// false to ask the stage to stop; the stage then returns ErrorCode::Cancelled.
using ProgressFn = std::function<bool(const char* stage, double fraction)>;

// Calls fn if set; true means "go on".
inline bool report(const ProgressFn& fn, const char* stage, double fraction) {
  return !fn || fn(stage, fraction);
}

}  // namespace lk
