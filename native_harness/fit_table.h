// Shared by `likeness fit` and the "fit" benchmark: the per-stage table of
// jeong2002 Table 1 with the paper's figures beside ours, and report.json.
#pragma once
#include "pipeline/fit_head.h"
#include "pipeline/fit_quality.h"

#include <chrono>
#include <cstdio>
#include <ctime>
#include <sstream>
#include <string>
#include <vector>

namespace lk::cli {

// --fit-back off|face-only|always and --fit-back-weight W of the fit
// benchmarks (FitHeadOptions::back_term, back_weight). False, with a
// message printed, on a value it does not know.
template <class ArgsT>
bool parse_back_term(const ArgsT& args, FitHeadOptions& options) {
  const std::string which = args.get("fit-back", "");
  if (which == "off") options.back_term = FitHeadOptions::BackTerm::Off;
  else if (which == "face-only") options.back_term = FitHeadOptions::BackTerm::FaceOnlyScans;
  else if (which == "always") options.back_term = FitHeadOptions::BackTerm::Always;
  else if (!which.empty()) {
    std::printf("   --fit-back takes off, face-only or always (not '%s')\n", which.c_str());
    return false;
  }
  if (!args.get_double("fit-back-weight", options.back_weight, options.back_weight) || !(options.back_weight >= 0)) {
    std::printf("   --fit-back-weight takes a number >= 0\n");
    return false;
  }
  return true;
}

struct TimedStage {
  std::string name;
  double ms = 0;      // wall time
  double cpu_ms = 0;  // process CPU time (the machine may be shared)
  DistanceStats distance;
};

// jeong2002 Table 1 (percent of the bbox diagonal) and Sec. 7 times (PC, 50k points).
struct PaperStage {
  const char* name;
  double male_mean, male_max, female_mean, female_max;
  const char* time;
};
inline const std::vector<PaperStage>& paper_table() {
  static const std::vector<PaperStage> t = {
      {"initial_alignment", 1.51, 13.13, 1.09, 11.35, "6-10 min"},
      {"local_fitting", 1.42, 13.13, 0.91, 10.26, "~5 min"},
      {"global_fitting", 0.11, 1.28, 0.12, 1.55, "~40 min"},
      {"subdivision", 0.04, 1.30, 0.08, 1.55, "n/a"},
  };
  return t;
}

// The other direction of Table 1 (fit_quality.h), a line.
inline void print_fit_to_scan(const CoveredDistances& d, int level) {
  if (d.vertices == 0) {
    std::printf("  level %d's face to the scan's %s: no face vertex lies over a scanned part of it\n", level,
                d.to_points ? "points" : "triangles");
    return;
  }
  std::printf("  level %d's face to the scan's %s where scanned (%d vertices): mean %.3f mm, p99 %.2f mm, "
              "max %.2f mm\n",
              level, d.to_points ? "points (their local quadric patches)" : "triangles", d.vertices, 1e3 * d.mean,
              1e3 * d.p99, 1e3 * d.max);
}

// The checks of the finest level, in two lines under the table.
inline void print_fit_quality(const FitQuality& q) {
  std::printf("  level %d: %d triangles, %d turned over by a displacement, %d degenerate; %d self-intersecting pairs "
              "(lips %d, ears %d, eye sockets %d, rest %d)\n",
              q.level, q.triangles, q.flipped, q.degenerate, q.crossings.total, q.crossings.lips, q.crossings.ears,
              q.crossings.eye_sockets, q.crossings.rest);
  std::printf("  the fitted control mesh crosses itself in %d triangle pairs; its smooth level %d in %d (lips %d, ears %d, "
              "eye sockets %d, rest %d)\n",
              q.control_crossings, q.level, q.smooth_crossings.total, q.smooth_crossings.lips, q.smooth_crossings.ears,
              q.smooth_crossings.eye_sockets, q.smooth_crossings.rest);
}

inline void print_fit_table(const std::vector<TimedStage>& stages) {
  std::printf("  %-18s %9s %9s %10s %10s | %-22s %-22s %s\n", "stage", "mean %", "max %", "wall ms", "cpu ms",
              "paper male mean/max", "paper female mean/max", "paper time");
  double total = 0, total_cpu = 0;
  for (const TimedStage& s : stages) {
    const PaperStage* p = nullptr;
    for (const auto& q : paper_table())
      if (s.name == q.name) p = &q;
    total += s.ms;
    total_cpu += s.cpu_ms;
    std::printf("  %-18s %9.3f %9.3f %10.1f %10.1f | ", s.name.c_str(), s.distance.mean_pct, s.distance.max_pct, s.ms,
                s.cpu_ms);
    if (p)
      std::printf("%6.2f / %-13.2f %6.2f / %-13.2f %s\n", p->male_mean, p->male_max, p->female_mean,
                  p->female_max, p->time);
    else
      std::printf("\n");
  }
  std::printf("  %-18s %9s %9s %10.1f %10.1f | paper: about an hour on a 50k-point subsample\n", "total", "", "",
              total, total_cpu);
}

// Wall and CPU stopwatch for the stage observer.
struct StageClock {
  std::chrono::steady_clock::time_point wall;
  std::clock_t cpu = 0;
  void start() {
    wall = std::chrono::steady_clock::now();
    cpu = std::clock();
  }
  void stop(TimedStage& s) const {
    s.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - wall).count();
    s.cpu_ms = 1000.0 * double(std::clock() - cpu) / CLOCKS_PER_SEC;
  }
};

inline void json_crossings(std::ostringstream& j, const char* name, const CrossingCounts& c) {
  j << "\"" << name << "\": {\"total\": " << c.total << ", \"lips\": " << c.lips << ", \"ears\": " << c.ears
    << ", \"eye_sockets\": " << c.eye_sockets << ", \"rest\": " << c.rest << ", \"rest_by_region\": {";
  // Where the "rest" pairs are (regions overlap, so these need not sum to rest).
  bool first = true;
  for (const auto& kv : c.rest_by_region) {
    j << (first ? "" : ", ") << "\"" << kv.first << "\": " << kv.second;
    first = false;
  }
  j << "}}";
}

// report.json; `quality` (may be null) adds the checks of the finest level.
inline std::string fit_report_json(const FitHeadResult& r, const std::vector<TimedStage>& stages,
                                   const std::string& status = "ok", const FitQuality* quality = nullptr,
                                   const CoveredDistances* to_scan = nullptr) {
  std::ostringstream j;
  j.precision(9);
  double total = 0;
  for (const auto& s : stages) total += s.ms;
  j << "{\n  \"status\": \"" << status << "\",\n  \"points\": " << r.points
    << ",\n  \"fitted_points\": " << r.fitted_points << ",\n  \"bbox_diagonal\": " << r.bbox_diagonal
    << ",\n  \"unit_to_metres\": " << r.unit_to_metres << ",\n  \"surface_samples\": " << r.surface_samples.samples
    << ",\n  \"stages\": [";
  for (size_t i = 0; i < stages.size(); ++i) {
    const auto& s = stages[i];
    j << (i ? "," : "") << "\n    {\"name\": \"" << s.name << "\", \"mean_pct\": " << s.distance.mean_pct
      << ", \"max_pct\": " << s.distance.max_pct << ", \"p95_pct\": "
      << (r.bbox_diagonal > 0 ? 100.0 * s.distance.p95 / (r.bbox_diagonal * r.unit_to_metres) : 0.0)
      << ", \"ms\": " << s.ms << ", \"cpu_ms\": " << s.cpu_ms << "}";
  }
  j << "\n  ],\n  \"total_ms\": " << total;
  if (quality) {
    const FitQuality& q = *quality;
    j << ",\n  \"quality\": {\"level\": " << q.level << ", \"triangles\": " << q.triangles
      << ", \"flipped\": " << q.flipped << ", \"degenerate\": " << q.degenerate << ",\n    ";
    json_crossings(j, "self_intersecting_pairs", q.crossings);
    j << ",\n    ";
    json_crossings(j, "smooth_surface_pairs", q.smooth_crossings);
    j << ",\n    \"control_mesh_pairs\": " << q.control_crossings << "}";
  }
  if (to_scan) {  // metres: the head frame's unit
    j << ",\n  \"face_to_scan\": {\"to\": \"" << (to_scan->to_points ? "points" : "triangles")
      << "\", \"vertices\": " << to_scan->vertices << ", \"mean_m\": " << to_scan->mean
      << ", \"p99_m\": " << to_scan->p99 << ", \"max_m\": " << to_scan->max << "}";
  }
  j << "\n}\n";
  return j.str();
}

}  // namespace lk::cli
