// --up and --facing: which way a scan is turned (likeness fit, likeness
// project refit), as an axis name ("+z", "-y") or three numbers ("0 0 1").
#pragma once
#include "command.h"
#include "common/types.h"

#include <cmath>
#include <cstdlib>
#include <optional>
#include <string>

namespace lk::cli {

// v is left empty when key is not given; false when it is given but is
// neither an axis name nor a finite nonzero direction.
inline bool get_direction(const Args& a, const std::string& key, std::optional<Vec3>& v) {
  if (!a.has(key)) return true;
  const auto vals = a.get_all(key);
  Vec3 d = Vec3::Zero();
  if (vals.size() == 1) {
    const std::string& name = vals[0];
    if (name.size() != 2 || (name[0] != '+' && name[0] != '-') || name[1] < 'x' || name[1] > 'z') return false;
    d[name[1] - 'x'] = name[0] == '+' ? 1.0 : -1.0;
  } else if (vals.size() == 3) {
    for (int k = 0; k < 3; ++k) {
      char* end = nullptr;
      d[k] = std::strtod(vals[k].c_str(), &end);
      if (vals[k].empty() || *end || !std::isfinite(d[k])) return false;
    }
    if (!(d.norm() > 0)) return false;
  } else {
    return false;
  }
  v = d;
  return true;
}

// Both options of cmd; false after saying what they take.
inline bool get_scan_axes(const std::string& cmd, const Args& a, std::optional<Vec3>& up,
                          std::optional<Vec3>& facing) {
  if (get_direction(a, "up", up) && get_direction(a, "facing", facing)) return true;
  fail(cmd, "--up and --facing take an axis (+x, -y, ...) or three numbers, e.g. --up +z or --up 0 0 1");
  return false;
}

}  // namespace lk::cli
