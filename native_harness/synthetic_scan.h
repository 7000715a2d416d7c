// The benchmarks' ground truth (synth/): person `seed` made from the generic
// head, its finer truth surface, and a virtual scan of `points` points with
// the truth's hair mask (the scalp returns junk, as a real scanner's does)
// and the scanner's default noise unless `noise_sigma_m` (>= 0) is given;
// `stations` and `arc_degrees` (> 0) replace the scanner's 6 stations over
// 200 degrees (3 over 90: a face capture, the face-only path of fit_head).
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
                                  double noise_sigma_m = -1, int stations = 0, double arc_degrees = 0) {
  Status st = synthesize_head(generic, seed, SynthHeadOptions{}, out.person);
  if (st) st = make_truth_surface(out.person, seed, TruthOptions{}, out.truth);
  if (!st) return st;
  ScannerOptions so;
  so.target_points = points;
  so.hair_triangles = out.truth.hair;
  if (noise_sigma_m >= 0) so.noise_sigma_m = noise_sigma_m;
  if (stations > 0) so.stations = stations;
  if (arc_degrees > 0) so.arc_degrees = arc_degrees;
  return scan_virtual(out.truth.mesh, so, seed, out.cloud, &out.stats);
}

}  // namespace lk::cli
