#include "photos_pulls_report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace lk::cli {
namespace {

const FitPullGroup* find_group(const FitPulls& p, const std::string& name) {
  for (const FitPullGroup& g : p.groups)
    if (g.name == name) return &g;
  return nullptr;
}

}  // namespace

std::string fit_pulls_table(const PhotosFitPulls& pulls, const std::string& indent, int max_groups) {
  std::string out = indent + "what moves the face's sides outward (mean over the region, + = wider): the first step's share mm, "
                             "the fit's share mm, the force at the end (% of the start's)\n";
  char buf[160];
  std::snprintf(buf, sizeof buf, "%s  %-16s %5s", indent.c_str(), "group", "rows");
  out += buf;
  for (const PullRegion& r : pulls.regions) {
    std::snprintf(buf, sizeof buf, " | %-6s %6s %6s %6s", r.name.c_str(), "step", "share", "force");
    out += buf;
  }
  out += "\n";
  std::vector<const FitPullGroup*> rows;
  for (const FitPullGroup& g : pulls.end.groups) rows.push_back(&g);
  if (max_groups > 0 && int(rows.size()) > max_groups + 3) {
    auto key = [](const FitPullGroup* g) { return g->share_m.empty() || !std::isfinite(g->share_m[0]) ? 0.0 : g->share_m[0]; };
    std::stable_sort(rows.begin(), rows.end(), [&](auto a, auto b) { return key(a) > key(b); });
    std::vector<const FitPullGroup*> kept(rows.begin(), rows.begin() + max_groups);
    kept.insert(kept.end(), rows.end() - 3, rows.end());
    rows = kept;
  }
  for (const FitPullGroup* gp : rows) {
    const FitPullGroup& g = *gp;
    const FitPullGroup* s = find_group(pulls.start, g.name);
    std::snprintf(buf, sizeof buf, "%s  %-16s %5d", indent.c_str(), g.name.c_str(), g.rows);
    out += buf;
    for (size_t k = 0; k < pulls.regions.size(); ++k) {
      const double step = s && k < s->share_m.size() ? 1000 * s->share_m[k] : std::nan("");
      std::snprintf(buf, sizeof buf, " | %-6s %+6.2f %+6.2f %+5.0f%%", "", step, 1000 * g.share_m[k], 100 * g.force[k]);
      out += buf;
    }
    out += "\n";
  }
  const char* names[2] = {"sum of shares", "the fit itself"};
  for (int w = 0; w < 2; ++w) {
    std::snprintf(buf, sizeof buf, "%s  %-16s %5s", indent.c_str(), names[w], "");
    out += buf;
    for (size_t k = 0; k < pulls.regions.size(); ++k) {
      const double step = w ? std::nan("") : 1000 * pulls.start.explained_m[k];
      const double fit = 1000 * (w ? pulls.end.displacement_m[k] : pulls.end.explained_m[k]);
      std::snprintf(buf, sizeof buf, " | %-6s %+6.2f %+6.2f %6s", "", step, fit, "");
      out += buf;
    }
    out += "\n";
  }
  return out;
}

nlohmann::json fit_pulls_json(const PhotosFitPulls& pulls) {
  nlohmann::json j = {{"units", "mean outward mm over the region; force as a share of the start's total"},
                      {"regions", nlohmann::json::object()}};
  for (size_t k = 0; k < pulls.regions.size(); ++k) {
    nlohmann::json r = {{"vertices", pulls.regions[k].vertices.size()},
                        {"fitted_mm", 1000 * pulls.end.displacement_m[k]},
                        {"explained_mm", 1000 * pulls.end.explained_m[k]},
                        {"first_step_mm", 1000 * pulls.start.explained_m[k]},
                        {"groups", nlohmann::json::object()}};
    for (const FitPullGroup& g : pulls.end.groups) {
      const FitPullGroup* s = find_group(pulls.start, g.name);
      nlohmann::json jg = {{"rows", g.rows}, {"force_end", g.force[k]}};
      if (std::isfinite(g.share_m[k])) jg["fitted_share_mm"] = 1000 * g.share_m[k];
      if (s && std::isfinite(s->share_m[k])) jg["first_step_mm"] = 1000 * s->share_m[k];
      if (s) jg["force_start"] = s->force[k];
      r["groups"][g.name] = jg;
    }
    j["regions"][pulls.regions[k].name] = r;
  }
  return j;
}

}  // namespace lk::cli
