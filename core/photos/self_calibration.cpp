#include "photos/self_calibration.h"

#include "calib/calibrate.h"
#include "common/rotation.h"
#include "mesh/geometry.h"
#include "photos/sparse_lm.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>

namespace lk {
namespace {

double median_of(std::vector<double> v) {
  if (v.empty()) return 0;
  std::nth_element(v.begin(), v.begin() + long(v.size() / 2), v.end());
  return v[v.size() / 2];
}

// A camera that sees the head's up (+y) pointing down the image: the
// landmarks make an upside-down face (seen on a detector's misreading of a
// full profile: mouth above the eyes).
bool upside_down(const Camera& c) { return c.R.col(1).y() > 0; }
const char* const kUpsideDown =
    "its landmarks make an upside-down face (mouth above the eyes): the detector misread this photo";

struct Observation {
  int camera = 0;    // index into the used cameras
  int landmark = 0;  // index into the active landmarks
  int map_index = 0; // the landmark's index in the map (for its slide)
  Vec2 pixel = Vec2::Zero();
  double weight = 1; // IRLS weight
  double sigma = 2;  // noise, pixels
};

// The bundle adjustment: focal, poses, landmark positions; reprojection
// residuals / pixel_sigma, landmark priors / shape_sigma, focal prior.
class BundleProblem : public LeastSquaresProblem {
 public:
  double focal = 0;
  std::vector<Camera> cameras;
  std::vector<Vec3> points, prior;
  std::vector<Observation> obs;
  double pixel_sigma = 2, shape_sigma = 0.01, focal_prior = 0, focal_prior_sigma = 0.05;
  const LandmarkSlide* slide = nullptr;
  // Per-camera depth scale (SelfCalibOptions::depth_scale_sigma): a 7th
  // parameter per camera when depth_sigma > 0, with its prior at depth_mean.
  double depth_sigma = 0;
  std::vector<double> depth, depth_mean;
  int cam_params() const { return depth_sigma > 0 ? 7 : 6; }
  double depth_of(int camera) const { return depth_sigma > 0 ? depth[size_t(camera)] : 1.0; }

  // The point observation o sees, at a camera: its 3-D point plus its shift for that view.
  Vec3 seen_point(const Observation& o, const Camera& c, const Vec3& X) const {
    if (!slide) return X;
    return X + landmark_shift(*slide, o.map_index, slide_view(*slide, c.center()));
  }

  int num_parameters() const override { return 1 + cam_params() * int(cameras.size()) + 3 * int(points.size()); }
  int point_index(int a) const { return 1 + cam_params() * int(cameras.size()) + 3 * a; }
  int num_residuals() const {
    return 2 * int(obs.size()) + 3 * int(points.size()) + (focal_prior > 0 ? 1 : 0) +
           (depth_sigma > 0 ? int(cameras.size()) : 0);
  }

  // Pixel of an observation with the depth scale k (false behind the camera).
  bool project(const Observation& o, const Camera& c, const Vec3& X, double k, Vec2& uv) const {
    const Vec3 q = c.R * seen_point(o, c, X);
    const double z = k * q.z() + c.t.z();
    if (z <= 1e-9) return false;
    uv = Vec2(c.fx * (q.x() + c.t.x()) / z + c.cx, c.fy * (q.y() + c.t.y()) / z + c.cy);
    return true;
  }

  void linearize(Eigen::VectorXd& r, SparseMat& J) override {
    r.setZero(num_residuals());
    std::vector<Eigen::Triplet<double>> trip;
    trip.reserve(obs.size() * 24 + points.size() * 3 + 1);
    int row = 0;
    for (const Observation& o : obs) {
      Camera c = cameras[size_t(o.camera)];
      c.fx = c.fy = focal;
      ProjectionJacobian pj;
      const double s = std::sqrt(o.weight) / o.sigma;
      const double dk = depth_of(o.camera);
      const bool ok = slide ? slid_projection_jacobian(c, points[size_t(o.landmark)], *slide, o.map_index, o.pixel, pj, dk)
                            : projection_jacobian(c, points[size_t(o.landmark)], o.pixel, pj, dk);
      if (ok) {
        r.segment<2>(row) = s * pj.residual;
        const int ci = 1 + cam_params() * o.camera, pi = point_index(o.landmark);
        for (int k = 0; k < 2; ++k) {
          trip.emplace_back(row + k, 0, s * pj.d_focal[k]);
          if (depth_sigma > 0) trip.emplace_back(row + k, ci + 6, s * pj.d_depth_scale[k]);
          for (int j = 0; j < 3; ++j) {
            trip.emplace_back(row + k, ci + j, s * pj.d_rotation(k, j));
            trip.emplace_back(row + k, ci + 3 + j, s * pj.d_translation(k, j));
            trip.emplace_back(row + k, pi + j, s * pj.d_point(k, j));
          }
        }
      } else {
        r.segment<2>(row).setConstant(s * 1e4);  // behind the camera: a large constant, no gradient
      }
      row += 2;
    }
    for (size_t a = 0; a < points.size(); ++a) {
      r.segment<3>(row) = (points[a] - prior[a]) / shape_sigma;
      for (int j = 0; j < 3; ++j) trip.emplace_back(row + j, point_index(int(a)) + j, 1.0 / shape_sigma);
      row += 3;
    }
    if (focal_prior > 0) {
      const double w = 1.0 / (focal_prior_sigma * focal_prior);
      r[row] = w * (focal - focal_prior);
      trip.emplace_back(row, 0, w);
      ++row;
    }
    if (depth_sigma > 0)
      for (size_t k = 0; k < cameras.size(); ++k, ++row) {
        r[row] = (depth[k] - depth_mean[k]) / depth_sigma;
        trip.emplace_back(row, 1 + cam_params() * int(k) + 6, 1.0 / depth_sigma);
      }
    J.resize(num_residuals(), num_parameters());
    J.setFromTriplets(trip.begin(), trip.end());
  }

  // The state moved by step, into the given copies.
  void moved(const Eigen::VectorXd& step, double& f, std::vector<Camera>& cams, std::vector<Vec3>& pts,
             std::vector<double>& ks) const {
    f = focal + step[0];
    cams = cameras;
    ks = depth;
    const long cp = cam_params();
    for (size_t k = 0; k < cams.size(); ++k) {
      cams[k].R = rotation_from_vector(step.segment<3>(1 + cp * long(k))) * cams[k].R;
      cams[k].t += step.segment<3>(4 + cp * long(k));
      if (depth_sigma > 0) ks[k] += step[1 + cp * long(k) + 6];
    }
    pts = points;
    for (size_t a = 0; a < pts.size(); ++a) pts[a] += step.segment<3>(point_index(int(a)));
  }

  double cost_of(double f, const std::vector<Camera>& cams, const std::vector<Vec3>& pts,
                 const std::vector<double>& ks) const {
    if (!(f > 0)) return std::numeric_limits<double>::infinity();
    double cost = 0;
    for (const Observation& o : obs) {
      Camera c = cams[size_t(o.camera)];
      c.fx = c.fy = f;
      Vec2 uv;
      if (!project(o, c, pts[size_t(o.landmark)], depth_sigma > 0 ? ks[size_t(o.camera)] : 1.0, uv))
        return std::numeric_limits<double>::infinity();
      cost += o.weight * (uv - o.pixel).squaredNorm() / (o.sigma * o.sigma);
    }
    for (size_t a = 0; a < pts.size(); ++a) cost += (pts[a] - prior[a]).squaredNorm() / (shape_sigma * shape_sigma);
    if (focal_prior > 0) {
      const double d = (f - focal_prior) / (focal_prior_sigma * focal_prior);
      cost += d * d;
    }
    if (depth_sigma > 0)
      for (size_t k = 0; k < ks.size(); ++k) {
        const double d = (ks[k] - depth_mean[k]) / depth_sigma;
        cost += d * d;
      }
    return cost;
  }

  double cost_after(const Eigen::VectorXd& step) override {
    double f;
    std::vector<Camera> cams;
    std::vector<Vec3> pts;
    std::vector<double> ks;
    moved(step, f, cams, pts, ks);
    return cost_of(f, cams, pts, ks);
  }
  void apply(const Eigen::VectorXd& step) override { moved(step, focal, cameras, points, depth); }

  // Pixel error of an observation (inf behind the camera).
  double error(const Observation& o) const {
    Camera c = cameras[size_t(o.camera)];
    c.fx = c.fy = focal;
    Vec2 uv;
    return project(o, c, points[size_t(o.landmark)], depth_of(o.camera), uv) ? (uv - o.pixel).norm()
                                                                             : std::numeric_limits<double>::infinity();
  }
};

// The problem without camera `drop` (its observations gone, the others'
// camera indices moved down): the jackknife's leave-one-photo-out.
BundleProblem without_camera(const BundleProblem& bp, int drop) {
  BundleProblem out = bp;
  out.cameras.erase(out.cameras.begin() + drop);
  if (!out.depth.empty()) out.depth.erase(out.depth.begin() + drop);
  if (!out.depth_mean.empty()) out.depth_mean.erase(out.depth_mean.begin() + drop);
  out.obs.clear();
  for (Observation o : bp.obs) {
    if (o.camera == drop) continue;
    if (o.camera > drop) --o.camera;
    out.obs.push_back(o);
  }
  return out;
}

}  // namespace

double typical_focal_px(double focal_35mm, int width, int height) {
  return focal_35mm * std::hypot(double(width), double(height)) / 43.27;
}

int SelfCalibResult::num_used() const {
  int n = 0;
  for (const auto& p : photos) n += p.used;
  return n;
}

void view_angles(const Camera& camera, double& yaw_deg, double& pitch_deg) {
  const Vec3 c = camera.center();
  constexpr double kDeg = 180.0 / 3.14159265358979323846;
  yaw_deg = std::atan2(c.x(), c.z()) * kDeg;
  pitch_deg = std::atan2(c.y(), std::hypot(c.x(), c.z())) * kDeg;
}

bool projection_jacobian(const Camera& camera, const Vec3& X, const Vec2& observed, ProjectionJacobian& out,
                         double depth_scale) {
  const Vec3 Xr = camera.R * X;
  const Vec3 c(Xr.x() + camera.t.x(), Xr.y() + camera.t.y(), depth_scale * Xr.z() + camera.t.z());
  if (c.z() <= 1e-9) return false;
  const double iz = 1.0 / c.z(), x = c.x() * iz, y = c.y() * iz, f = camera.fx;
  out.residual = Vec2(f * x + camera.cx - observed.x(), f * y + camera.cy - observed.y());
  out.d_focal << x, y;
  Eigen::Matrix<double, 2, 3> dc;
  dc << f * iz, 0, -f * x * iz, 0, f * iz, -f * y * iz;
  out.d_translation = dc;
  out.d_depth_scale = dc.col(2) * Xr.z();
  Eigen::Matrix<double, 2, 3> dq = dc;  // d residual / d (R X)
  dq.col(2) *= depth_scale;
  out.d_point = dq * camera.R;
  out.d_rotation = -dq * skew(Xr);
  return true;
}

bool slid_projection_jacobian(const Camera& camera, const Vec3& X, const LandmarkSlide& slide, int landmark,
                              const Vec2& observed, ProjectionJacobian& out, double depth_scale) {
  Mat3 dS;
  const Vec3 shift = landmark_shift(slide, landmark, slide_view(slide, camera.center()), &dS);
  if (!projection_jacobian(camera, X + shift, observed, out, depth_scale)) return false;
  // C = -R^T t; with R <- exp([w]x) R: dC/dw = -R^T [t]x, dC/dt = -R^T.
  const Eigen::Matrix<double, 2, 3> through = out.d_point * dS;
  out.d_rotation -= through * camera.R.transpose() * skew(camera.t);
  out.d_translation -= through * camera.R.transpose();
  return true;
}

double slide_sigma_px(const LandmarkSlide& slide, int landmark, const Camera& camera, const Vec3& X, double min_px,
                      double fallback_px) {
  const double s = landmark_sigma(slide, landmark, camera.center());
  const double z = camera.to_camera(X).z();
  if (!(s > 0) || !(z > 0)) return fallback_px;
  return std::max(min_px, s * camera.fx / z);
}

Status self_calibrate(const std::vector<LandmarkPhoto>& photos, const TriMesh& generic,
                      const std::vector<SurfacePoint>& landmarks, const SelfCalibOptions& options,
                      SelfCalibResult& result, const LandmarkSlide* slide) {
  result = {};
  const int P = int(photos.size()), M = int(landmarks.size());
  if (!(options.pixel_sigma > 0) || !(options.shape_sigma_m > 0) || !(options.huber_k > 0) ||
      !(options.focal_prior_px >= 0) || !(options.focal_prior_sigma > 0) || options.min_landmarks < 6 || !(options.refuse_factor > 1) ||
      !(options.refuse_min_sigma >= 0) || !(options.min_view_cos >= -1 && options.min_view_cos < 1) ||
      !(options.min_sigma_px > 0) || !(options.depth_scale_sigma >= 0) || !std::isfinite(options.depth_scale_yaw2) ||
      !(options.depth_scale_0 > 0))
    return Status::error(ErrorCode::InvalidInput, "self-calibration: an option is out of range");
  for (const SurfacePoint& s : landmarks)
    if (s.valid() && (s.triangle >= generic.num_triangles()))
      return Status::error(ErrorCode::InvalidInput, "self-calibration: a landmark's triangle is out of range");
  std::vector<Vec3> generic_points(size_t(M), Vec3::Zero());
  for (int m = 0; m < M; ++m)
    if (landmarks[size_t(m)].valid()) generic_points[size_t(m)] = surface_position(generic, landmarks[size_t(m)]);
  result.photos.assign(size_t(P), PhotoCalibration{});
  result.landmarks = generic_points;
  result.landmark_seen.assign(size_t(M), 0);

  // 1. Each photo alone against the generic head. A photo whose landmarks
  // alone fit no camera (DLT mirrors shallow, mismatched face points; seen
  // on a face photographed from below) is posed at the other photos' focal.
  CalibOptions co;
  co.fix_principal_point = true;
  co.pixel_sigma = options.pixel_sigma;
  co.outlier_px = 3 * options.pixel_sigma;
  co.focal_prior = options.focal_prior_px;
  co.focal_prior_sigma = options.focal_prior_sigma;
  std::vector<std::vector<Correspondence>> corr(static_cast<size_t>(P));
  std::vector<std::vector<int>> corr_index(static_cast<size_t>(P));
  std::vector<CalibResult> alone(static_cast<size_t>(P));
  std::vector<std::string> alone_error(static_cast<size_t>(P));
  std::vector<double> focals;
  for (int i = 0; i < P; ++i) {
    const LandmarkPhoto& ph = photos[size_t(i)];
    PhotoCalibration& pc = result.photos[size_t(i)];
    pc.weights.assign(ph.points.size(), 0.0);
    if (ph.points.size() != ph.present.size() || ph.width <= 0 || ph.height <= 0)
      return Status::error(ErrorCode::InvalidInput, "self-calibration: photo " + std::to_string(i) + " is malformed");
    for (int m = 0; m < std::min(M, int(ph.points.size())); ++m)
      if (ph.present[size_t(m)] && landmarks[size_t(m)].valid()) {
        corr[size_t(i)].push_back({ph.points[size_t(m)], generic_points[size_t(m)]});
        corr_index[size_t(i)].push_back(m);
      }
    pc.num_landmarks = int(corr[size_t(i)].size());
    if (pc.num_landmarks < options.min_landmarks) {
      pc.refusal = std::to_string(pc.num_landmarks) + " mapped landmarks, at least " +
                   std::to_string(options.min_landmarks) + " needed (no face found?)";
      continue;
    }
    const Status s = calibrate_camera(corr[size_t(i)], ph.width, ph.height, co, alone[size_t(i)]);
    if (s && upside_down(alone[size_t(i)].camera) && options.refuse_upside_down) {
      pc.refusal = kUpsideDown;
    } else if (s) {
      pc.used = true;
      focals.push_back(alone[size_t(i)].camera.fx);
    } else {
      alone_error[size_t(i)] = s.message;
    }
  }
  const double fallback_focal = options.focal_prior_px > 0 ? options.focal_prior_px : median_of(focals);
  for (int i = 0; i < P; ++i) {
    PhotoCalibration& pc = result.photos[size_t(i)];
    if (alone_error[size_t(i)].empty()) continue;
    Status s = Status::error(ErrorCode::InvalidInput, alone_error[size_t(i)]);
    if (fallback_focal > 0) {
      CalibOptions at_focal = co;
      at_focal.known_focal = fallback_focal;
      s = calibrate_camera(corr[size_t(i)], photos[size_t(i)].width, photos[size_t(i)].height, at_focal,
                           alone[size_t(i)]);
    }
    if (s && upside_down(alone[size_t(i)].camera) && options.refuse_upside_down) pc.refusal = kUpsideDown;
    else if (s) pc.used = true;
    else pc.refusal = "its landmarks fit no camera: " + s.message;
  }

  // With a slide: each photo posed again (twice) against the landmarks
  // where the detector sees them from its current camera, a view far to the
  // side being the one the fixed points place least turned.
  if (slide && slide->has_slide())
    for (int i = 0; i < P; ++i) {
      if (!result.photos[size_t(i)].used) continue;
      for (int again = 0; again < 2; ++again) {
        const SlideView v = slide_view(*slide, alone[size_t(i)].camera.center());
        std::vector<Correspondence> slid = corr[size_t(i)];
        for (size_t q = 0; q < slid.size(); ++q) slid[q].point += landmark_shift(*slide, corr_index[size_t(i)][q], v);
        CalibOptions at = co;
        at.known_focal = alone[size_t(i)].camera.fx;
        CalibResult r;
        if (!calibrate_camera(slid, photos[size_t(i)].width, photos[size_t(i)].height, at, r) || upside_down(r.camera))
          break;
        alone[size_t(i)] = r;
      }
    }

  // Visibility: the detector places every landmark, also those the face
  // hides (the far cheek, the outline seen edge-on); it puts them on the
  // silhouette, not where the map says. Each photo keeps only the landmarks
  // whose generic-head normal faces its camera by more than
  // min_view_cos (the camera from step 1).
  const std::vector<Vec3> vn = vertex_normals(generic);
  std::vector<Vec3> generic_normals(size_t(M), Vec3::Zero());
  for (int m = 0; m < M; ++m)
    if (landmarks[size_t(m)].valid()) {
      const auto& tri = generic.triangles[size_t(landmarks[size_t(m)].triangle)];
      Vec3 n = Vec3::Zero();
      for (int k = 0; k < 3; ++k) n += landmarks[size_t(m)].barycentric[k] * vn[size_t(tri[k])];
      generic_normals[size_t(m)] = n.normalized();
    }
  for (int i = 0; i < P; ++i) {
    PhotoCalibration& pc = result.photos[size_t(i)];
    if (!pc.used || options.min_view_cos <= -1) continue;
    const Vec3 C = alone[size_t(i)].camera.center();
    std::vector<Correspondence> kept;
    std::vector<int> kept_index;
    for (size_t q = 0; q < corr_index[size_t(i)].size(); ++q) {
      const int m = corr_index[size_t(i)][q];
      const Vec3 d = (C - generic_points[size_t(m)]).normalized();
      if (generic_normals[size_t(m)].dot(d) >= options.min_view_cos) {
        kept.push_back(corr[size_t(i)][q]);
        kept_index.push_back(m);
      }
    }
    pc.num_hidden = pc.num_landmarks - int(kept.size());
    if (int(kept.size()) < options.min_landmarks) {
      pc.used = false;
      pc.refusal = std::to_string(kept.size()) + " of its " + std::to_string(pc.num_landmarks) +
                   " landmarks face the camera, at least " + std::to_string(options.min_landmarks) + " needed";
      continue;
    }
    corr[size_t(i)] = std::move(kept);
    corr_index[size_t(i)] = std::move(kept_index);
  }

  // 2. One focal for all usable photos; 3-4. bundle adjustment, refusals.
  for (int pass = 0; pass < P; ++pass) {
    std::vector<int> used;
    for (int i = 0; i < P; ++i)
      if (result.photos[size_t(i)].used) used.push_back(i);
    // One photo given: calibrated against the generic head alone (the caller
    // notes that depth then comes from the generic head). Several given but
    // fewer than 2 usable: refused.
    if (used.size() < 2 && !(P == 1 && used.size() == 1))
      return Status::error(ErrorCode::NotConverged, "self-calibration: " + std::to_string(used.size()) +
                                                        " usable photo(s), at least 2 needed");
    std::vector<std::vector<Correspondence>> sets;
    std::vector<std::array<int, 2>> sizes;
    for (int i : used) {
      sets.push_back(corr[size_t(i)]);
      // The landmarks where the detector sees them from this photo's first camera.
      if (slide && slide->has_slide()) {
        const SlideView v = slide_view(*slide, alone[size_t(i)].camera.center());
        for (size_t q = 0; q < sets.back().size(); ++q)
          sets.back()[q].point += landmark_shift(*slide, corr_index[size_t(i)][q], v);
      }
      sizes.push_back({photos[size_t(i)].width, photos[size_t(i)].height});
    }
    SharedCalibResult shared;
    Status s = calibrate_cameras_shared(sets, sizes, co, shared);
    if (!s) return with_context(s, "self-calibration");

    // The focal's prior: EXIF's, else the typical phone's (its image size the photos' median diagonal).
    double prior_px = options.focal_prior_px, prior_sigma = options.focal_prior_sigma;
    if (!(prior_px > 0) && options.typical_focal_35mm > 0 && options.typical_focal_sigma > 0) {
      std::vector<double> typ;
      for (const auto& wh : sizes) typ.push_back(typical_focal_px(options.typical_focal_35mm, wh[0], wh[1]));
      prior_px = median_of(typ);
      prior_sigma = options.typical_focal_sigma;
    }
    const double ratio = slide && slide->has_slide() ? options.slide_focal_ratio : 1.0;
    const bool jackknife = options.focal_from_jackknife && used.size() >= 3 && (prior_px > 0 || ratio != 1.0);

    BundleProblem bp;
    bp.focal = shared.focal;
    bp.pixel_sigma = options.pixel_sigma;
    bp.shape_sigma = options.shape_sigma_m;
    bp.focal_prior = jackknife ? 0.0 : options.focal_prior_px;  // the jackknife adds its prior afterwards
    bp.focal_prior_sigma = options.focal_prior_sigma;
    if (slide && slide->has_slide()) bp.slide = slide;
    bp.depth_sigma = options.depth_scale_sigma;
    const bool slide_sigma = slide && slide->has_sigma() && options.use_slide_sigma;
    std::vector<int> active_of(size_t(M), -1), landmark_of;
    for (size_t k = 0; k < used.size(); ++k) {
      bp.cameras.push_back(shared.photos[k].camera);
      double yaw, pitch;
      view_angles(shared.photos[k].camera, yaw, pitch);
      bp.depth_mean.push_back(options.depth_scale_0 + options.depth_scale_yaw2 * (yaw / 60) * (yaw / 60));
      bp.depth.push_back(bp.depth_mean.back());
      const auto& idx = corr_index[size_t(used[k])];
      for (size_t q = 0; q < idx.size(); ++q) {
        const int m = idx[q];
        if (active_of[size_t(m)] < 0) {
          active_of[size_t(m)] = int(landmark_of.size());
          landmark_of.push_back(m);
          bp.points.push_back(generic_points[size_t(m)]);
        }
        bp.obs.push_back({int(k), active_of[size_t(m)], m, corr[size_t(used[k])][q].pixel, 1.0, options.pixel_sigma});
      }
    }
    bp.prior = bp.points;
    auto rms_all = [&]() {
      double sum = 0;
      int n = 0;
      for (const Observation& o : bp.obs) {
        const double e = bp.error(o);
        if (o.weight >= 0.5 && std::isfinite(e)) { sum += e * e; ++n; }
      }
      return n ? std::sqrt(sum / n) : 0.0;
    };
    result.initial_rms_px = rms_all();
    result.lm_iterations = 0;
    for (int round = 0; round < options.reweighting_rounds; ++round) {
      // Each observation's noise: the landmark's scatter at the current view.
      if (slide_sigma)
        for (Observation& o : bp.obs) {
          Camera c = bp.cameras[size_t(o.camera)];
          c.fx = c.fy = bp.focal;
          o.sigma = slide_sigma_px(*slide, o.map_index, c, bp.points[size_t(o.landmark)], options.min_sigma_px,
                                   options.pixel_sigma);
        }
      // Huber weights from the current errors.
      if (round > 0)
        for (Observation& o : bp.obs) {
          const double e = bp.error(o) / o.sigma;
          o.weight = e <= options.huber_k ? 1.0 : (std::isfinite(e) ? options.huber_k / e : 0.0);
        }
      LmOptions lo;
      lo.max_iterations = 30;
      result.lm_iterations += levenberg_marquardt(bp, lo).iterations;
    }

    // Per-photo robust error: the median pixel error of its landmarks.
    std::vector<double> med(used.size());
    std::vector<std::vector<double>> errs(used.size());
    for (const Observation& o : bp.obs) errs[size_t(o.camera)].push_back(bp.error(o));
    for (size_t k = 0; k < used.size(); ++k) med[k] = median_of(errs[k]);
    const double typical = median_of(med);
    int worst = -1;
    for (size_t k = 0; k < used.size(); ++k)
      if (med[k] > std::max(options.refuse_factor * typical, options.refuse_min_sigma * options.pixel_sigma) &&
          (worst < 0 || med[k] > med[size_t(worst)]))
        worst = int(k);
    if (worst >= 0 && used.size() > 2) {
      PhotoCalibration& pc = result.photos[size_t(used[size_t(worst)])];
      pc.used = false;
      char buf[200];
      std::snprintf(buf, sizeof buf,
                    "its landmarks do not fit the other photos' head (median error %.1f px, the others %.1f px): "
                    "another person, or wrong points?",
                    med[size_t(worst)], typical);
      pc.refusal = buf;
      continue;
    }

    // The landmarks' focal, its spread over the photos left out in turn,
    // and the prior: combined as two Gaussians; the adjustment again at
    // that focal (held by a tight prior).
    if (jackknife) {
      const int n = int(used.size());
      std::vector<double> loo(static_cast<size_t>(n));
      for (int k = 0; k < n; ++k) {
        BundleProblem sub = without_camera(bp, k);
        LmOptions lo;
        lo.max_iterations = 30;
        result.lm_iterations += levenberg_marquardt(sub, lo).iterations;
        loo[size_t(k)] = sub.focal;
      }
      double mean = 0, var = 0;
      for (double f : loo) mean += f / n;
      for (double f : loo) var += (f - mean) * (f - mean);
      var *= double(n - 1) / n;
      // The detector's measured bias taken out of the landmarks' focal and its spread.
      const double fl = bp.focal / ratio;
      var /= ratio * ratio;
      const double pv = (prior_sigma * prior_px) * (prior_sigma * prior_px);
      const double combined = prior_px > 0 && var > 0 ? (fl / var + prior_px / pv) / (1 / var + 1 / pv) : fl;
      result.focal_landmarks_raw = bp.focal;
      result.focal_landmarks = fl;
      result.focal_landmarks_sigma = std::sqrt(var);
      result.focal_prior = prior_px;
      result.focal_prior_sigma = prior_sigma * prior_px;
      bp.focal_prior = combined;
      bp.focal_prior_sigma = 1e-4;
      for (Camera& c : bp.cameras) c.t.z() *= combined / bp.focal;  // the same image size at the new focal
      bp.focal = combined;
      LmOptions lo;
      lo.max_iterations = 30;
      result.lm_iterations += levenberg_marquardt(bp, lo).iterations;
    }

    // Done: write the result.
    result.focal = bp.focal;
    result.focal_before_ba = shared.focal;
    result.final_rms_px = rms_all();
    std::vector<int> seen(size_t(M), 0);
    for (size_t k = 0; k < used.size(); ++k) {
      PhotoCalibration& pc = result.photos[size_t(used[k])];
      pc.camera = bp.cameras[k];
      pc.camera.fx = pc.camera.fy = bp.focal;
      pc.camera.width = photos[size_t(used[k])].width;
      pc.camera.height = photos[size_t(used[k])].height;
      pc.depth_scale = bp.depth_of(int(k));
      pc.num_outliers = 0;
      double sum = 0;
      int n = 0;
      for (const Observation& o : bp.obs) {
        if (o.camera != int(k)) continue;
        const int m = landmark_of[size_t(o.landmark)];
        pc.weights[size_t(m)] = o.weight;
        ++seen[size_t(m)];
        if (o.weight < 0.5) ++pc.num_outliers;  // error beyond 2 huber_k sigma
        else {
          const double e = bp.error(o);
          sum += e * e;
          ++n;
        }
      }
      pc.rms_px = n ? std::sqrt(sum / n) : 0;
      pc.median_px = med[k];
    }
    for (size_t a = 0; a < landmark_of.size(); ++a) {
      const int m = landmark_of[a];
      result.landmarks[size_t(m)] = bp.points[a];
      result.landmark_seen[size_t(m)] = seen[size_t(m)] >= 2;
    }
    return Status::success();
  }
  return Status::error(ErrorCode::Internal, "self-calibration: refusal loop did not end");
}

}  // namespace lk
