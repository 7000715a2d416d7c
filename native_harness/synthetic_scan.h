// The benchmarks' ground truth (synth/): person `seed` made from the generic
// head, its finer truth surface, and a virtual scan of `points` points with
// the truth's hair mask (the scalp returns junk, as a real scanner's does)
// and the scanner's default noise unless `noise_sigma_m` (>= 0) is given.
// `likeness synth-scan` runs the same steps with its own options and timing.
#pragma once
#include "synth/scanner.h"
#include "synth/synth_head.h"

#include <cstdint>

namespace lk::cli {

struct SyntheticScan {
  GenericHead person;
  TruthSurface truth;
  PointCloud cloud;
  ScanStats stats;
};

inline Status make_synthetic_scan(const GenericHead& generic, std::uint32_t seed, int points, SyntheticScan& out,
                                  double noise_sigma_m = -1) {
  Status st = synthesize_head(generic, seed, SynthHeadOptions{}, out.person);
  if (st) st = make_truth_surface(out.person, seed, TruthOptions{}, out.truth);
  if (!st) return st;
  ScannerOptions so;
  so.target_points = points;
  so.hair_triangles = out.truth.hair;
  if (noise_sigma_m >= 0) so.noise_sigma_m = noise_sigma_m;
  return scan_virtual(out.truth.mesh, so, seed, out.cloud, &out.stats);
}

}  // namespace lk::cli
