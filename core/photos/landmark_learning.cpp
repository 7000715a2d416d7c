#include "photos/landmark_learning.h"

#include "mesh/geometry.h"
#include "photos/self_calibration.h"
#include "raycast/bvh.h"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>

namespace lk {
namespace {

double median_of(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

Vec3 surface_normal(const TriMesh& mesh, const std::vector<Vec3>& vn, const SurfacePoint& p) {
  const Tri& t = mesh.triangles[size_t(p.triangle)];
  Vec3 n = Vec3::Zero();
  for (int k = 0; k < 3; ++k) n += p.barycentric[k] * vn[size_t(t[k])];
  return n.normalized();
}

}  // namespace

Status learn_landmark_map(const TriMesh& generic, const LandmarkMap& start,
                          const std::vector<DetectedSessionView>& sessions, const LearnMapOptions& options,
                          LandmarkMap& out, LearnMapReport* report) {
  if (!(options.min_view_cos >= -1 && options.min_view_cos < 1) || options.min_views < 2 ||
      options.min_sessions < 1 || !(options.max_offset_m > 0))
    return Status::error(ErrorCode::InvalidInput, "learn_landmark_map: bad options");
  std::vector<SurfacePoint> attached;
  Status s = attach_landmark_map(start, generic, options.max_offset_m, attached);
  if (!s) return with_context(s, "learn_landmark_map");
  const size_t M = start.points.size();
  std::vector<std::vector<Vec3>> found(M);  // per landmark, one generic-frame point per session
  for (size_t si = 0; si < sessions.size(); ++si) {
    const DetectedSessionView& ses = sessions[si];
    if (!ses.person || ses.person->triangles.size() != generic.triangles.size() ||
        ses.person->positions.size() != generic.positions.size() || ses.cameras.size() != ses.photos.size())
      return Status::error(ErrorCode::InvalidInput,
                           "learn_landmark_map: session " + std::to_string(si) + " has another topology or sizes");
    const TriMesh& person = *ses.person;
    const std::vector<Vec3> vn = vertex_normals(person);
    MeshBvh bvh;
    s = build_bvh(person, bvh);
    if (!s) return with_context(s, "learn_landmark_map");
    for (size_t m = 0; m < M; ++m) {
      if (!attached[m].valid()) continue;
      const Vec3 P = surface_position(person, attached[m]);
      const Vec3 n = surface_normal(person, vn, attached[m]);
      // Linear triangulation: for each view, rows (R_a - x_a R_2) X = -(t_a - x_a t_2), a = 0, 1.
      Mat3 A = Mat3::Zero();
      Vec3 b = Vec3::Zero();
      int views = 0;
      for (size_t c = 0; c < ses.cameras.size(); ++c) {
        const LandmarkPhoto& ph = ses.photos[c];
        if (m >= ph.points.size() || !ph.present[m]) continue;
        const Camera& cam = ses.cameras[c];
        if (n.dot((cam.center() - P).normalized()) < options.min_view_cos) continue;
        const Vec2 x((ph.points[m].x() - cam.cx) / cam.fx, (ph.points[m].y() - cam.cy) / cam.fy);
        for (int a = 0; a < 2; ++a) {
          const Vec3 row = cam.R.row(a).transpose() - x[a] * cam.R.row(2).transpose();
          const double rhs = -(cam.t[a] - x[a] * cam.t[2]);
          A += row * row.transpose();
          b += row * rhs;
        }
        ++views;
      }
      if (views < options.min_views) continue;
      // Views too close in direction give no depth: refuse an ill-conditioned system.
      Eigen::SelfAdjointEigenSolver<Mat3> eig(A);
      if (!(eig.eigenvalues()[0] > 1e-6 * eig.eigenvalues()[2])) continue;
      const Vec3 X = A.ldlt().solve(b);
      if (!X.allFinite()) continue;
      // Onto the generic head: the person's closest surface place, the same place on the generic, the offset kept.
      const ClosestPoint cp = closest_point(bvh, X);
      if (!cp.found()) continue;
      SurfacePoint sp;
      sp.triangle = cp.triangle;
      sp.barycentric = cp.barycentric;
      sp.offset = X - cp.point;
      if (sp.offset.norm() > options.max_offset_m) sp.offset *= options.max_offset_m / sp.offset.norm();
      found[m].push_back(surface_position(generic, sp));
    }
  }
  out = start;
  std::vector<double> moves;
  for (size_t m = 0; m < M; ++m) {
    if (int(found[m].size()) < options.min_sessions) continue;
    Vec3 med;
    for (int k = 0; k < 3; ++k) {
      std::vector<double> v;
      for (const Vec3& p : found[m]) v.push_back(p[k]);
      med[k] = median_of(v);
    }
    moves.push_back((med - start.points[m]).norm());
    out.points[m] = med;
  }
  if (moves.empty()) return Status::error(ErrorCode::Empty, "learn_landmark_map: no landmark seen in enough views");
  if (report) {
    report->learned = int(moves.size());
    report->median_move_m = median_of(moves);
  }
  return Status::success();
}

}  // namespace lk

namespace lk {
namespace {

// One training view of one landmark: the true camera, the person's surface
// place there, the detector's pixel, the view's basis values.
struct SlideSample {
  const Camera* camera = nullptr;
  Vec3 place = Vec3::Zero();
  Vec2 pixel = Vec2::Zero();
  std::vector<double> phi;  // #K
  double yaw = 0;           // radians
};

struct SlideSolution {
  Vec3 offset = Vec3::Zero();
  std::vector<Vec3> shifts;       // #K
  std::vector<double> residual;   // per sample, metres at the landmark (2-D norm)
  bool ok = false;
};

// Gauss-Newton with Huber weights on the samples' reprojection errors
// (rows scaled to metres at the landmark), K shift coefficients under a
// ridge, the offset under a weak one.
SlideSolution solve_slide(const std::vector<SlideSample>& samples, size_t K, const Vec3& offset0,
                          const LearnSlideOptions& o) {
  SlideSolution sol;
  sol.offset = offset0;
  sol.shifts.assign(K, Vec3::Zero());
  const int P = 3 * int(K + 1);
  const double ridge = std::pow(o.noise_m / o.shift_prior_m, 2), ridge_offset = std::pow(o.noise_m / 0.02, 2);
  const double huber = 3 * o.noise_m;
  std::vector<double> w(samples.size(), 1.0);
  for (int it = 0; it < 6; ++it) {
    Eigen::MatrixXd N = Eigen::MatrixXd::Zero(P, P);
    Eigen::VectorXd g = Eigen::VectorXd::Zero(P);
    sol.residual.assign(samples.size(), 0.0);
    for (size_t v = 0; v < samples.size(); ++v) {
      const SlideSample& s = samples[v];
      Vec3 X = s.place + sol.offset;
      for (size_t k = 0; k < K; ++k) X += s.phi[k] * sol.shifts[k];
      ProjectionJacobian pj;
      if (!projection_jacobian(*s.camera, X, s.pixel, pj)) return sol;
      const double scale = s.camera->to_camera(X).z() / s.camera->fx;  // pixels -> metres at the landmark
      const Vec2 r = scale * pj.residual;
      sol.residual[v] = r.norm();
      Eigen::MatrixXd A(2, P);
      const Eigen::Matrix<double, 2, 3> J = scale * pj.d_point;
      A.block<2, 3>(0, 0) = J;
      for (size_t k = 0; k < K; ++k) A.block<2, 3>(0, 3 * long(k + 1)) = s.phi[k] * J;
      N += w[v] * A.transpose() * A;
      g -= w[v] * A.transpose() * r;
    }
    // Priors: the offset toward offset0 (weak), the shifts toward zero.
    for (int j = 0; j < 3; ++j) {
      N(j, j) += ridge_offset;
      g[j] -= ridge_offset * (sol.offset[j] - offset0[j]);
    }
    for (size_t k = 0; k < K; ++k)
      for (int j = 0; j < 3; ++j) {
        const int c = 3 * int(k + 1) + j;
        N(c, c) += ridge;
        g[c] -= ridge * sol.shifts[k][j];
      }
    const Eigen::VectorXd step = N.ldlt().solve(g);
    if (!step.allFinite()) return sol;
    sol.offset += step.head<3>();
    for (size_t k = 0; k < K; ++k) sol.shifts[k] += step.segment<3>(3 * long(k + 1));
    // Huber weights from this iteration's residuals (from the second on).
    if (it >= 1)
      for (size_t v = 0; v < samples.size(); ++v) w[v] = sol.residual[v] <= huber ? 1.0 : huber / sol.residual[v];
  }
  // Final residuals at the solution.
  for (size_t v = 0; v < samples.size(); ++v) {
    const SlideSample& s = samples[v];
    Vec3 X = s.place + sol.offset;
    for (size_t k = 0; k < K; ++k) X += s.phi[k] * sol.shifts[k];
    Vec2 uv;
    if (!s.camera->project(X, uv)) return sol;
    sol.residual[v] = (uv - s.pixel).norm() * s.camera->to_camera(X).z() / s.camera->fx;
  }
  sol.ok = true;
  return sol;
}

}  // namespace

Status learn_landmark_slide(const TriMesh& generic, const LandmarkMap& start,
                            const std::vector<DetectedSessionView>& sessions, const LearnSlideOptions& options,
                            LandmarkMap& out, LearnSlideReport* report) {
  if (!(options.min_view_cos >= -1 && options.min_view_cos < 1) || options.min_views < 2 ||
      options.min_sessions < 1 || !(options.max_offset_m > 0) || !(options.shift_prior_m > 0) ||
      !(options.noise_m > 0) || options.passes < 1 || !(options.sigma_kernel_deg > 0))
    return Status::error(ErrorCode::InvalidInput, "learn_landmark_slide: bad options");
  for (const auto& t : options.terms)
    if (t[0] < 0 || t[1] < 0 || t[0] + t[1] < 1 || t[0] + t[1] > 6)
      return Status::error(ErrorCode::InvalidInput, "learn_landmark_slide: a term's exponents are out of range");
  for (size_t b = 1; b < options.sigma_yaw_deg.size(); ++b)
    if (!(options.sigma_yaw_deg[b] > options.sigma_yaw_deg[b - 1]))
      return Status::error(ErrorCode::InvalidInput, "learn_landmark_slide: sigma_yaw_deg must increase");
  for (size_t si = 0; si < sessions.size(); ++si) {
    const DetectedSessionView& ses = sessions[si];
    if (!ses.person || ses.person->triangles.size() != generic.triangles.size() ||
        ses.person->positions.size() != generic.positions.size() || ses.cameras.size() != ses.photos.size())
      return Status::error(ErrorCode::InvalidInput,
                           "learn_landmark_slide: session " + std::to_string(si) + " has another topology or sizes");
  }
  constexpr double kDeg = 3.14159265358979323846 / 180;
  // The views' range: the slide is normalized by it and not extrapolated beyond.
  double max_yaw = 0, max_pitch = 0;
  for (const DetectedSessionView& ses : sessions)
    for (size_t c = 0; c < ses.cameras.size(); ++c)
      if (ses.photos[c].num_present() > 0) {
        double y, p;
        view_angles(ses.cameras[c], y, p);
        max_yaw = std::max(max_yaw, std::abs(y));
        max_pitch = std::max(max_pitch, std::abs(p));
      }
  if (!(max_yaw > 1) || !(max_pitch > 1))
    return Status::error(ErrorCode::Empty, "learn_landmark_slide: the views do not vary in yaw and pitch");
  LandmarkSlide model;
  model.yaw_range = max_yaw * kDeg;
  model.pitch_range = max_pitch * kDeg;
  model.terms = options.terms;
  const size_t K = model.terms.size(), M = start.points.size();

  std::vector<std::vector<Vec3>> normals;
  for (const DetectedSessionView& ses : sessions) normals.push_back(vertex_normals(*ses.person));
  LandmarkMap current = start;
  current.slide = {};
  std::vector<SlideSolution> sol(M);
  std::vector<std::vector<SlideSample>> samples(M);
  std::vector<char> sliding(M, 0), learned(M, 0);
  double fixed_sq = 0, slide_sq = 0;
  int residual_n = 0;
  for (int pass = 0; pass < options.passes; ++pass) {
    std::vector<SurfacePoint> attached;
    Status s = attach_landmark_map(current, generic, options.max_offset_m + 0.004, attached);
    if (!s) return with_context(s, "learn_landmark_slide");
    fixed_sq = slide_sq = 0;
    residual_n = 0;
    for (size_t m = 0; m < M; ++m) {
      samples[m].clear();
      sliding[m] = learned[m] = 0;
      if (!attached[m].valid()) continue;
      SurfacePoint place = attached[m];
      place.offset = Vec3::Zero();
      int sessions_seen = 0;
      for (size_t si = 0; si < sessions.size(); ++si) {
        const DetectedSessionView& ses = sessions[si];
        const Vec3 P = surface_position(*ses.person, place);
        const Vec3 n = surface_normal(*ses.person, normals[si], place);
        bool seen = false;
        for (size_t c = 0; c < ses.cameras.size(); ++c) {
          const LandmarkPhoto& ph = ses.photos[c];
          if (m >= ph.points.size() || !ph.present[m]) continue;
          const Camera& cam = ses.cameras[c];
          if (n.dot((cam.center() - P).normalized()) < options.min_view_cos) continue;
          SlideSample smp;
          smp.camera = &cam;
          smp.place = P;
          smp.pixel = ph.points[m];
          const SlideView v = slide_view(model, cam.center());
          for (const auto& t : model.terms) smp.phi.push_back(std::pow(v.a, t[0]) * std::pow(v.b, t[1]));
          smp.yaw = std::atan2(cam.center().x(), cam.center().z());
          samples[m].push_back(smp);
          seen = true;
        }
        sessions_seen += seen;
      }
      const int n = int(samples[m].size());
      if (n < options.min_views || sessions_seen < options.min_sessions) continue;
      const SlideSolution fixed = solve_slide(samples[m], 0, attached[m].offset, options);
      if (!fixed.ok) continue;
      learned[m] = 1;
      sol[m] = fixed;
      if (n >= 2 * int(K + 1)) {
        const SlideSolution slid = solve_slide(samples[m], K, attached[m].offset, options);
        if (slid.ok) {
          sol[m] = slid;
          sliding[m] = 1;
        }
      }
      for (size_t v = 0; v < samples[m].size(); ++v) {
        fixed_sq += fixed.residual[v] * fixed.residual[v];
        slide_sq += sol[m].residual[v] * sol[m].residual[v];
        ++residual_n;
      }
      if (sol[m].offset.norm() > options.max_offset_m) sol[m].offset *= options.max_offset_m / sol[m].offset.norm();
      current.points[m] = surface_position(generic, place) + sol[m].offset;
    }
  }
  out = current;
  model.shifts.assign(M, {});
  for (size_t m = 0; m < M; ++m)
    if (sliding[m]) model.shifts[m] = sol[m].shifts;
  // The scatter left, per landmark and yaw (per image coordinate: the 2-D
  // residual / sqrt 2), kernel-smoothed, with two pseudo-views of the
  // landmark's overall scatter, inflated by n / (n - unknowns).
  if (!options.sigma_yaw_deg.empty()) {
    for (double y : options.sigma_yaw_deg) model.sigma_yaw.push_back(y * kDeg);
    model.sigma.assign(M, {});
    for (size_t m = 0; m < M; ++m) {
      if (!learned[m]) continue;
      const double n = double(samples[m].size()), unknowns = 1.5 * (sliding[m] ? K + 1 : 1);
      const double inflate = n / std::max(1.0, n - unknowns);
      double all = 0;
      for (double r : sol[m].residual) all += 0.5 * r * r;
      all /= n;
      for (double yb : model.sigma_yaw) {
        double sw = 2, sr = 2 * all;
        for (size_t v = 0; v < samples[m].size(); ++v) {
          const double d = (samples[m][v].yaw - yb) / (options.sigma_kernel_deg * kDeg);
          const double k = std::exp(-0.5 * d * d);
          sw += k;
          sr += k * 0.5 * sol[m].residual[v] * sol[m].residual[v];
        }
        model.sigma[m].push_back(std::max(1e-5, std::sqrt(inflate * sr / sw)));
      }
    }
  }
  out.slide = model;
  int n_learned = 0, n_sliding = 0;
  for (size_t m = 0; m < M; ++m) {
    n_learned += learned[m];
    n_sliding += sliding[m];
  }
  if (!n_learned) return Status::error(ErrorCode::Empty, "learn_landmark_slide: no landmark seen in enough views");
  if (report) {
    report->learned = n_learned;
    report->sliding = n_sliding;
    report->yaw_range_deg = max_yaw;
    report->pitch_range_deg = max_pitch;
    report->rms_fixed_m = residual_n ? std::sqrt(fixed_sq / (2 * residual_n)) : 0;
    report->rms_slide_m = residual_n ? std::sqrt(slide_sq / (2 * residual_n)) : 0;
  }
  return Status::success();
}

}  // namespace lk
