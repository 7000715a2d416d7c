// Scoring the photos-to-head stages against a synthetic truth (tests and
// `likeness bench --only photos`). Uncalibrated photos fix a head only up to
// a similarity (absolute scale is unobservable; the self-calibration takes
// the generic head's), so the fit is first brought onto the truth by the
// least-squares similarity over corresponding vertices (same topology,
// Umeyama 1991) and the scale factor is reported apart.
//
// Shapes: fit and truth #V, same triangles; vertices: indices into both.
#pragma once
#include "calib/camera.h"
#include "fit/closest_point.h"
#include "mesh/tri_mesh.h"

#include <vector>

namespace lk {

struct Similarity {
  double scale = 1;
  Mat3 R = Mat3::Identity();
  Vec3 t = Vec3::Zero();
  Vec3 apply(const Vec3& p) const { return scale * (R * p) + t; }
};

// The similarity taking from[v] closest to to[v] over the listed vertices.
Similarity fit_similarity(const std::vector<Vec3>& from, const std::vector<Vec3>& to, const std::vector<int>& vertices);

// A camera of the fit's frame moved into the truth's frame by s (the image is unchanged).
Camera transform_camera(const Camera& c, const Similarity& s);

// Angle of R_a^T R_b, degrees.
double rotation_angle_deg(const Mat3& Ra, const Mat3& Rb);

// Distances from the listed vertices of `from` to the surface of `to`
// (fit/closest_point.h's summary; no reference diagonal: the _pct fields 0).
DistanceStats surface_distances(const TriMesh& from, const std::vector<int>& vertices, const TriMesh& to);

}  // namespace lk
