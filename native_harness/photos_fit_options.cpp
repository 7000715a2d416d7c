#include "photos_fit_options.h"

#include <cmath>
#include <sstream>

namespace lk::cli {

namespace {

std::vector<std::string> comma_list(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream in(s);
  std::string item;
  while (std::getline(in, item, ','))
    if (!item.empty()) out.push_back(item);
  return out;
}

}  // namespace

bool parse_fit_levels(const std::string& coarse, const std::string& schedule, const std::string& follow,
                      ShapeFitOptions& fit, std::string& why) {
  if (coarse == "none") {
    fit.coarse_levels.clear();
  } else if (!coarse.empty()) {
    fit.coarse_levels.clear();
    for (const std::string& item : comma_list(coarse)) {
      ShapeFitOptions::CoarseLevel c;
      char tail = 0;
      if (std::sscanf(item.c_str(), "%d:%lf%c", &c.nodes, &c.stiffness, &tail) != 2 || c.nodes < 4 ||
          !(c.stiffness > 0) || !std::isfinite(c.stiffness)) {
        why = "coarse levels are N:S[,N:S...] (N >= 4 nodes, stiffness S > 0) or none, got '" + item + "'";
        return false;
      }
      fit.coarse_levels.push_back(c);
    }
  }
  if (schedule == "none") {
    fit.stiffness_schedule.clear();
  } else if (!schedule.empty()) {
    fit.stiffness_schedule.clear();
    for (const std::string& item : comma_list(schedule)) {
      char* end = nullptr;
      const double k = std::strtod(item.c_str(), &end);
      if (*end != 0 || !(k > 0) || !std::isfinite(k)) {
        why = "the stiffness schedule is S[,S...] (each > 0) or none, got '" + item + "'";
        return false;
      }
      fit.stiffness_schedule.push_back(k);
    }
  }
  if (!follow.empty()) {
    double k = 0, w = 0;
    char* end = nullptr;
    k = std::strtod(follow.c_str(), &end);
    bool empty = end == follow.c_str();
    const bool has_w = *end == ':';
    if (has_w) {
      const char* w_text = end + 1;
      w = std::strtod(w_text, &end);
      empty = empty || end == w_text;
    }
    if (empty || *end != 0 || !(k >= 0) || !std::isfinite(k) || !(w >= 0) || !std::isfinite(w)) {
      why = "follow is K or K:W (numbers >= 0: the weight, and its share where observations are), got '" + follow + "'";
      return false;
    }
    fit.follow = k;
    fit.follow_observed = has_w ? w : 0.0;
  }
  if (fit.stiffness_schedule.empty() && fit.coarse_levels.empty()) {
    why = "no stage left: give coarse levels or a stiffness schedule";
    return false;
  }
  return true;
}

}  // namespace lk::cli
