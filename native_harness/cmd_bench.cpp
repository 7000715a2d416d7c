// likeness bench: runs the registered benchmark sections.
#include "command.h"

#include <iostream>
#include <set>

namespace lk::cli {

std::map<std::string, Bench>& bench_registry() {
  static std::map<std::string, Bench> r;
  return r;
}

namespace {

int run_bench(const Args& args) {
  // Every option a section reads (bench_*.cpp, fit_table.h).
  if (!only_known_options(
          "bench", args,
          {"only", "quick", "size", "data", "dump", "save-scans", "truth-head", "fit-arc", "fit-area-ratio", "fit-back",
           "fit-back-weight", "fit-below-cut-mm", "fit-cap-pct", "fit-crease-angle", "fit-crease-edges",
           "fit-crease-trials", "fit-data-level", "fit-displaced-creases", "fit-ear-refit-late", "fit-ear-give-up", "fit-neck-guard", "fit-neck-reach", "fit-ear-refit-rounds", "fit-edge-fade", "fit-footprint",
           "fit-guard-always", "fit-guard-face-only", "fit-guard-off", "fit-guard-passes", "fit-head",
           "fit-hinges-last", "fit-isolated", "fit-levels", "fit-line-edges", "fit-no-climb",
           "fit-no-corners-to-smooth", "fit-no-creases", "fit-no-eye-region", "fit-scanned-neck", "fit-no-scanned-neck", "fit-no-parents-to-smooth",
           "fit-noise-confidence", "fit-noise-edge", "fit-noise-points", "fit-noise-radius", "fit-pleat-steps",
           "fit-points", "fit-real-copies", "fit-real-copy", "fit-real-dump", "fit-real-stages", "fit-real-sweep", "fit-real-cube", "fit-real-dense", "fit-real-dense-x64", "fit-real-surface-cells", "fit-real-align-only", "fit-align-pitches", "fit-align-polish", "fit-align-loss", "fit-align-choose", "fit-align-smooth", "fit-align-coarse", "fit-align-tolerance", "fit-real-no-scanned-neck", "fit-real-scanned-neck", "fit-real-scan", "fit-relief-level", "fit-remeasure",
           "fit-restarts", "fit-restore-rings", "fit-scan-noise-mm", "fit-seed", "fit-seeds", "fit-separate-rounds",
           "fit-separation-repeats", "fit-smooth-agreement", "fit-smooth-iterations", "fit-smooth-levels",
           "fit-smooth-max-radius", "fit-smooth-region-rings", "fit-smooth-strength", "fit-stations",
           "fit-surface-edges", "fit-thin-cells", "fit-untangle-level", "fit-guard-others", "fit-guard-remeasure", "fit-pleat-undo", "fit-guard-by-cost", "fit-guard-cost-tries", "fit-face-screen", "fit-face-symmetry", "fit-face-frame", "fit-orient-screen-points", "fit-orient-screen-keep", "fit-orient-retry", "fit-orient-surface-retry", "fit-dense-retry", "fit-face-match-edge", "fit-z-up-hint", "photos-seeds", "photos-cameras", "photos-noise-px", "photos-map", "photos-stiffness-scale", "photos-first-seed",
           "photos-silhouettes", "photos-lambda-sil", "photos-mask-grow", "photos-sil-facets", "photos-stereo", "photos-lambda-features", "photos-symmetry", "photos-detected", "photos-focal-px", "photos-shape-sigma", "photos-view-cos", "photos-drop", "photos-detected-map", "photos-focal-sigma", "photos-true-cameras", "photos-no-slide", "photos-no-slide-sigma", "photos-coarse", "photos-schedule", "photos-follow", "photos-no-lips", "photos-descent-iterations", "photos-depth-scale", "photos-depth-0", "photos-depth-yaw2", "photos-contours", "photos-contour-lambda", "photos-lids", "photos-pulls", "photos-pulls-by-photo", "photos-focal-jackknife", "photos-detected-silhouettes", "photos-sil-exclude"}))
    return 2;
  const auto only_list = args.get_all("only");
  std::set<std::string> only(only_list.begin(), only_list.end());
  int failures = 0, ran = 0;
  for (auto& [name, b] : bench_registry()) {
    if (!only.empty() && !only.count(name)) continue;
    std::cout << "\n== " << name << ": " << b.summary << "\n";
    ++ran;
    if (b.run(args) != 0) {
      std::cout << "   (section " << name << " failed)\n";
      ++failures;
    }
  }
  if (ran == 0) {
    std::cerr << "likeness bench: no section matched; sections:";
    for (auto& [name, b] : bench_registry()) std::cerr << " " << name;
    std::cerr << "\n";
    return 2;
  }
  return failures ? 1 : 0;
}

std::string sections() {
  std::string out = "sections (all by default; --only picks some):\n";
  for (auto& [name, b] : bench_registry()) {
    const std::string pad(name.size() < 10 ? 10 - name.size() : 1, ' ');
    out += "  " + name + pad + b.summary + "\n";
  }
  return out;
}

Registrar reg({"bench", "likeness bench [--only SECTION ...] [--quick]",
               "measures speed and accuracy, printed beside the papers' figures", run_bench, sections});

}  // namespace
}  // namespace lk::cli
