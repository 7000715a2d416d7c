// A scan's noise floor: the Table 1 figure (mean distance from the points to
// a surface, jeong2002 Table 1) that its own true surface would get.
//
// Each point's k nearest points (itself included) get a quadric height
// field over their principal plane (fit/point_patch.h); the residuals give
// the local noise, sigma_i^2 = RSS_i / (k - 6) (the quadric's 6 unknowns).
// A surface lying exactly on the truth leaves each point its noise away,
// whose mean is sqrt(2 / pi) sigma for Gaussian noise; the floor is that,
// averaged over the measured points. Where the surface is no quadric over k
// points (a crease, a hole's rim, a statue's carved curls) the misfit reads
// as noise: there the floor is an upper bound.
//
// Shapes: points #P by 3; measured #P flags or empty (all).
#pragma once
#include "common/status.h"
#include "common/types.h"

#include <vector>

namespace lk {

struct ScanNoise {
  int points = 0;           // points the floor averages over
  double sigma_mean = 0;    // mean of sigma_i, scan units
  double sigma_median = 0;  // median of sigma_i
  double floor = 0;         // sqrt(2 / pi) x sigma_mean: the mean distance a perfect fit leaves
};

// InvalidInput for k < 7, non-finite points or a mask of another size;
// Empty when fewer than k points (or none measured).
Status estimate_scan_noise(const std::vector<Vec3>& points, const std::vector<char>& measured, int k,
                           ScanNoise& out);

}  // namespace lk
