// Shared by the displacement-smoothing tests (test_displacement_smoothing.cpp,
// test_displacement_grain.cpp): a flat 12 x 12 control patch (level-3 edges
// ~0.14) whose truth is a height field z = f(x, y) - a Gaussian bump about
// three level-3 edges wide, or a cliff (a step of 0.3 along x = 6.3) - and
// the measures the tests compare: error against the truth, roughness of the
// level-3 faces where the truth is flat, the bump's peak.
#pragma once

#include "multires/displacement.h"
#include "multires/multires.h"

#include "../subdiv/shapes.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <functional>

namespace lk::test {

constexpr double kPi = 3.14159265358979323846;
constexpr double kHeight = 0.3;            // of the bump and the cliff
const Vec3 kCentre(6.375, 6.625, 0);       // of the bump
constexpr double kStepX = 6.3;             // where the cliff is

inline double bump(double x, double y) {
  const double r2 = (x - kCentre.x()) * (x - kCentre.x()) + (y - kCentre.y()) * (y - kCentre.y());
  return kHeight * std::exp(-r2 / (2 * 0.4 * 0.4));
}

inline double cliff(double x, double) { return x > kStepX ? kHeight : 0.0; }

// The finest level's smoothing alone, with the rules it was made with (the
// defaults until the two finest levels were smoothed together).
inline DisplacementOptions finest_level_smoothing() {
  DisplacementOptions o;
  o.smooth_finest_levels = 1;
  o.smooth_strength = 0.3;
  o.smooth_noise_cap = 0;
  o.smooth_move_cap = 0;
  o.smooth_normal_degrees = 0;
  o.smooth_max_height_errors = 0;
  return o;
}

struct Measured {
  MultiresMesh mesh;
  DisplacementStats stats;
};

inline Measured measure(const PointCloud& cloud, const DisplacementOptions& options) {
  Measured m;
  REQUIRE(build_multires(regular_grid(12, 12), 3, m.mesh).ok());
  REQUIRE(measure_displacements(cloud, options, m.mesh, &m.stats).ok());
  return m;
}

// Away from the patch's border, where every vertex has data all around.
inline bool inside(const Vec3& p) { return p.x() > 2 && p.x() < 10 && p.y() > 2 && p.y() < 10; }

// Mean |z - truth| over level-3 vertices where `where` holds.
inline double mean_error(const Measured& m, const std::function<double(double, double)>& surface,
                         const std::function<bool(const Vec3&)>& where) {
  const TriMesh t = level_mesh(m.mesh, 3);
  double sum = 0;
  int n = 0;
  for (const Vec3& p : t.positions)
    if (inside(p) && where(p)) sum += std::abs(p.z() - surface(p.x(), p.y())), ++n;
  REQUIRE(n > 100);
  return sum / n;
}

// Mean angle (deg) between level-3 face normals and +z over the faces whose
// centre satisfies `where` (the truth must be flat there).
inline double roughness(const Measured& m, const std::function<bool(const Vec3&)>& where) {
  const TriMesh t = level_mesh(m.mesh, 3);
  double sum = 0;
  int n = 0;
  for (const Tri& f : t.triangles) {
    const Vec3 c = (t.positions[f[0]] + t.positions[f[1]] + t.positions[f[2]]) / 3.0;
    if (!inside(c) || !where(c)) continue;
    const Vec3 nrm = (t.positions[f[1]] - t.positions[f[0]]).cross(t.positions[f[2]] - t.positions[f[0]]).normalized();
    sum += std::acos(std::clamp(std::abs(nrm.z()), 0.0, 1.0)) * 180.0 / kPi;
    ++n;
  }
  REQUIRE(n > 100);
  return sum / n;
}

inline bool away_from_bump(const Vec3& p) { return (p - kCentre).head<2>().norm() > 2.0; }

// The highest level-3 vertex near the bump's centre.
inline double peak(const Measured& m) {
  const TriMesh t = level_mesh(m.mesh, 3);
  double best = 0;
  for (const Vec3& p : t.positions)
    if ((p - kCentre).head<2>().norm() < 0.1) best = std::max(best, p.z());
  return best;
}

// Moves the patch's middle control vertex and checks that the local update
// (re-measuring nothing, re-evaluating its support) gives exactly the mesh
// a full evaluation gives.
inline void check_local_update_equals_recompute(Measured& m) {
  MultiresMesh full = m.mesh;
  const int v = 6 * 13 + 6;
  const Vec3 to = m.mesh.control[v] + Vec3(0.1, -0.05, 0.2);
  REQUIRE(update_control_vertices(m.mesh, {v}, {to}).ok());
  full.control[v] = to;
  REQUIRE(evaluate(full).ok());
  for (int l = 0; l <= 3; ++l) CHECK(m.mesh.state.displaced[l] == full.state.displaced[l]);
}

}  // namespace lk::test
