#include "calib/calibrate.h"

#include "common/prng.h"
#include "common/rotation.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

namespace lk {
namespace {

using Mat34 = Eigen::Matrix<double, 3, 4>;
using VecX = Eigen::VectorXd;
using MatX = Eigen::MatrixXd;

// Hartley normalization: moves the centroid to 0 and scales the mean distance
// to sqrt(dim), so the DLT system is well conditioned.
template <int D>
Eigen::Matrix<double, D + 1, D + 1> normalizer(const std::vector<Eigen::Matrix<double, D, 1>>& pts) {
  Eigen::Matrix<double, D, 1> c = Eigen::Matrix<double, D, 1>::Zero();
  for (const auto& p : pts) c += p;
  c /= double(pts.size());
  double mean = 0;
  for (const auto& p : pts) mean += (p - c).norm();
  mean /= double(pts.size());
  const double s = mean > 0 ? std::sqrt(double(D)) / mean : 1.0;
  Eigen::Matrix<double, D + 1, D + 1> T = Eigen::Matrix<double, D + 1, D + 1>::Identity();
  T.template topLeftCorner<D, D>() *= s;
  T.template topRightCorner<D, 1>() = -s * c;
  return T;
}

// Normalized DLT (Hartley & Zisserman Alg. 7.1) on the listed correspondences.
Mat34 dlt(const std::vector<Correspondence>& cs, const std::vector<int>& idx) {
  std::vector<Vec2> x;
  std::vector<Vec3> X;
  for (int i : idx) { x.push_back(cs[i].pixel); X.push_back(cs[i].point); }
  const Mat3 T = normalizer<2>(x);
  const Mat4 U = normalizer<3>(X);
  MatX A = MatX::Zero(2 * idx.size(), 12);
  for (size_t i = 0; i < idx.size(); ++i) {
    const Vec3 xn = T * x[i].homogeneous();
    const Vec4 Xn = U * X[i].homogeneous();
    A.block<1, 4>(2 * i, 4) = -xn.z() * Xn.transpose();
    A.block<1, 4>(2 * i, 8) = xn.y() * Xn.transpose();
    A.block<1, 4>(2 * i + 1, 0) = xn.z() * Xn.transpose();
    A.block<1, 4>(2 * i + 1, 8) = -xn.x() * Xn.transpose();
  }
  Eigen::JacobiSVD<MatX> svd(A, Eigen::ComputeFullV);
  const VecX p = svd.matrixV().col(11);
  Mat34 Pn;
  Pn << p.segment<4>(0).transpose(), p.segment<4>(4).transpose(), p.segment<4>(8).transpose();
  return T.inverse() * Pn * U;
}

// P = K [R | t] with K upper triangular, positive diagonal, det R = +1.
// Returns false when the points would lie behind the camera.
bool decompose(Mat34 P, const std::vector<Correspondence>& cs, const std::vector<int>& idx,
               Camera& cam) {
  Mat3 M = P.leftCols<3>();
  if (M.determinant() < 0) { P = -P; M = -M; }
  // RQ via QR of the row-reversed, transposed matrix.
  Mat3 J = Mat3::Zero();
  J(0, 2) = J(1, 1) = J(2, 0) = 1;
  Eigen::HouseholderQR<Mat3> qr((J * M).transpose());
  const Mat3 Q = qr.householderQ();
  const Mat3 Ru = qr.matrixQR().triangularView<Eigen::Upper>();
  Mat3 K = J * Ru.transpose() * J;
  Mat3 R = J * Q.transpose();
  const Mat3 D = K.diagonal().cwiseSign().asDiagonal();
  K = K * D;
  R = D * R;
  if (R.determinant() < 0 || K(2, 2) <= 0) return false;
  const Vec3 t = K.inverse() * P.col(3);
  K /= K(2, 2);
  cam.fx = K(0, 0);
  cam.fy = K(1, 1);
  cam.cx = K(0, 2);
  cam.cy = K(1, 2);
  cam.k1 = cam.k2 = 0;
  cam.R = R;
  cam.t = t;
  int in_front = 0;
  for (int i : idx) in_front += cam.to_camera(cs[i].point).z() > 0;
  return 2 * in_front > int(idx.size());
}

// Coplanar points with known K: pose from the plane homography (Zhang 2000).
bool pose_from_plane(const std::vector<Correspondence>& cs, const std::vector<int>& idx,
                     const Vec3& centroid, const Mat3& basis /* e1 e2 n */, Camera& cam) {
  std::vector<Vec2> x, a;
  for (int i : idx) {
    x.push_back(cs[i].pixel);
    a.push_back((basis.transpose() * (cs[i].point - centroid)).head<2>());
  }
  const Mat3 T = normalizer<2>(x), U = normalizer<2>(a);
  MatX A = MatX::Zero(2 * idx.size(), 9);
  for (size_t i = 0; i < idx.size(); ++i) {
    const Vec3 xn = T * x[i].homogeneous(), an = U * a[i].homogeneous();
    A.block<1, 3>(2 * i, 3) = -xn.z() * an.transpose();
    A.block<1, 3>(2 * i, 6) = xn.y() * an.transpose();
    A.block<1, 3>(2 * i + 1, 0) = xn.z() * an.transpose();
    A.block<1, 3>(2 * i + 1, 6) = -xn.x() * an.transpose();
  }
  Eigen::JacobiSVD<MatX> svd(A, Eigen::ComputeFullV);
  const VecX h = svd.matrixV().col(8);
  Mat3 Hn;
  Hn << h.segment<3>(0).transpose(), h.segment<3>(3).transpose(), h.segment<3>(6).transpose();
  const Mat3 H = T.inverse() * Hn * U;
  Mat3 K = Mat3::Identity();
  K(0, 0) = cam.fx; K(1, 1) = cam.fy; K(0, 2) = cam.cx; K(1, 2) = cam.cy;
  Mat3 B = K.inverse() * H;
  double lambda = 2.0 / (B.col(0).norm() + B.col(1).norm());
  if (B(2, 2) * lambda < 0) lambda = -lambda;  // the plane's origin must be in front
  B *= lambda;
  Mat3 Rl;
  Rl.col(0) = B.col(0);
  Rl.col(1) = B.col(1);
  Rl.col(2) = B.col(0).cross(B.col(1));
  Eigen::JacobiSVD<Mat3> r(Rl, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Rl = r.matrixU() * r.matrixV().transpose();
  if (Rl.determinant() < 0) return false;
  cam.R = Rl * basis.transpose();
  cam.t = B.col(2) - cam.R * centroid;
  return true;
}

// Which parameters the refinement may change.
struct FreeParams {
  bool focal = true, separate = false, principal = true, k1 = true, k2 = false;
  int count() const { return (focal ? (separate ? 2 : 1) : 0) + (principal ? 2 : 0) + k1 + k2 + 6; }
};

// Camera from the base camera and a parameter vector. Rotation is a local
// axis-angle update of base.R, so it never meets the axis-angle singularity.
Camera apply(const Camera& base, const FreeParams& fp, const VecX& p) {
  Camera c = base;
  int j = 0;
  if (fp.focal) {
    if (fp.separate) { c.fx = p[j++]; c.fy = p[j++]; }
    else { c.fx = c.fy = p[j++]; }
  }
  if (fp.principal) { c.cx = p[j++]; c.cy = p[j++]; }
  if (fp.k1) c.k1 = p[j++];
  if (fp.k2) c.k2 = p[j++];
  const Vec3 w = p.segment<3>(j);
  j += 3;
  c.R = rotation_from_vector(w) * base.R;
  c.t = p.segment<3>(j);
  return c;
}

VecX pack(const Camera& c, const FreeParams& fp) {
  VecX p(fp.count());
  int j = 0;
  if (fp.focal) {
    if (fp.separate) { p[j++] = c.fx; p[j++] = c.fy; }
    else p[j++] = 0.5 * (c.fx + c.fy);
  }
  if (fp.principal) { p[j++] = c.cx; p[j++] = c.cy; }
  if (fp.k1) p[j++] = c.k1;
  if (fp.k2) p[j++] = c.k2;
  p.segment<3>(j) = Vec3::Zero();
  p.segment<3>(j + 3) = c.t;
  return p;
}

// Soft Gaussian prior on the focal: one extra residual weight * (f - focal).
struct FocalPrior {
  double focal = 0;   // 0 = none
  double weight = 0;  // pixels per pixel of focal error
  bool active() const { return focal > 0 && weight > 0; }
  double residual(double f) const { return weight * (f - focal); }
};

FocalPrior focal_prior_of(const CalibOptions& o) {
  FocalPrior p;
  if (o.focal_prior > 0 && o.known_focal <= 0) {
    p.focal = o.focal_prior;
    p.weight = o.pixel_sigma / (o.focal_prior_sigma * o.focal_prior);
  }
  return p;
}

// Reprojection residuals into r starting at row `at`; a point behind the
// camera gets a large constant residual so the solver is pushed away from
// such solutions.
void reprojection(const Camera& c, const std::vector<Correspondence>& cs, const std::vector<int>& idx, VecX& r,
                  Eigen::Index at) {
  for (size_t i = 0; i < idx.size(); ++i) {
    Vec2 uv;
    if (c.project(cs[idx[i]].point, uv)) r.segment<2>(at + 2 * i) = uv - cs[idx[i]].pixel;
    else r.segment<2>(at + 2 * i) = Vec2::Constant(1e6);
  }
}

VecX residuals(const Camera& c, const std::vector<Correspondence>& cs, const std::vector<int>& idx,
               const FocalPrior& prior = {}) {
  VecX r(2 * idx.size() + (prior.active() ? 1 : 0));
  reprojection(c, cs, idx, r, 0);
  if (prior.active()) r[r.size() - 1] = prior.residual(0.5 * (c.fx + c.fy));
  return r;
}

// Levenberg-Marquardt (Marquardt's diagonal scaling) with a central-difference
// Jacobian: at most a few dozen parameters and a few hundred residuals, so
// numeric derivatives cost little and cannot get out of sync with the model.
// The parameters p are an increment on a base State (apply(base, p)); after
// every accepted step the base moves there and pack(base) restarts p (the
// axis-angle parts restart at 0). A trial state that valid() rejects counts
// as a failed step.
template <typename State, typename Pack, typename Apply, typename Residuals, typename Valid>
State levenberg_marquardt(State base, const Pack& pack, const Apply& apply, const Residuals& residuals,
                          const Valid& valid, int max_iterations) {
  VecX p = pack(base);
  VecX r = residuals(base);
  double cost = r.squaredNorm();
  double lambda = 1e-3;
  const Eigen::Index n = p.size();
  for (int it = 0; it < max_iterations; ++it) {
    MatX Jac(r.size(), n);
    for (Eigen::Index j = 0; j < n; ++j) {
      const double h = 1e-6 * std::max(1.0, std::abs(p[j]));
      VecX pp = p, pm = p;
      pp[j] += h;
      pm[j] -= h;
      Jac.col(j) = (residuals(apply(base, pp)) - residuals(apply(base, pm))) / (2 * h);
    }
    const MatX JtJ = Jac.transpose() * Jac;
    const VecX g = Jac.transpose() * r;
    bool improved = false;
    for (int tries = 0; tries < 12; ++tries) {
      MatX A = JtJ;
      for (Eigen::Index j = 0; j < n; ++j) A(j, j) += lambda * std::max(JtJ(j, j), 1e-12);
      const VecX step = A.ldlt().solve(-g);
      if (!step.allFinite()) { lambda *= 10; continue; }
      const State cn = apply(base, p + step);
      if (!valid(cn)) { lambda *= 10; continue; }
      const VecX rn = residuals(cn);
      const double cn_cost = rn.squaredNorm();
      if (cn_cost < cost) {
        const double gain = cost - cn_cost;
        base = cn;
        p = pack(base);
        r = rn;
        cost = cn_cost;
        lambda = std::max(lambda * 0.3, 1e-12);
        improved = true;
        if (gain < 1e-14 * (1 + cost) || step.norm() < 1e-14 * (1 + p.norm())) return base;
        break;
      }
      lambda *= 10;
    }
    if (!improved) break;
  }
  return base;
}

// One camera: its free parameters (fp) against the reprojection error.
Camera refine(const Camera& start, const FreeParams& fp, const std::vector<Correspondence>& cs,
              const std::vector<int>& idx, int max_iterations, const FocalPrior& focal_prior = {}) {
  const FocalPrior prior = fp.focal ? focal_prior : FocalPrior{};
  return levenberg_marquardt(
      start, [&](const Camera& c) { return pack(c, fp); },
      [&](const Camera& c, const VecX& p) { return apply(c, fp, p); },
      [&](const Camera& c) { return residuals(c, cs, idx, prior); }, [](const Camera&) { return true; },
      max_iterations);
}

// Known intrinsics, no usable DLT: the pose with the lowest reprojection
// error among LM runs started from cameras looking at the points' centroid
// from around their principal axes (basis: e1 e2 n, by decreasing spread),
// both ways up, at the distance that matches their spread in the image.
// A shallow, nearly symmetric point set (face landmarks) has a mirrored
// solution seen from behind; starting from all sides lets LM find both and
// the error decide.
bool multi_start_pose(const std::vector<Correspondence>& cs, const std::vector<int>& idx, const Vec3& centroid,
                      const Mat3& basis, double focal, int width, int height, const Vec3& seen_from, Camera& best) {
  Vec2 mean2 = Vec2::Zero();
  for (int i : idx) mean2 += cs[size_t(i)].pixel;
  mean2 /= double(idx.size());
  double spread2 = 0, spread3 = 0;
  for (int i : idx) {
    spread2 += (cs[size_t(i)].pixel - mean2).norm();
    spread3 += (cs[size_t(i)].point - centroid).norm();
  }
  if (!(spread2 > 0) || !(spread3 > 0)) return false;
  const double distance = focal * spread3 / spread2;
  const Vec3 e1 = basis.col(0), e2 = basis.col(1), n = basis.col(2);
  std::vector<Vec3> directions = {n, -n, e1, -e1, e2, -e2};
  for (double a : {-1.0, 1.0})
    for (double b : {-1.0, 1.0}) {
      directions.push_back((b * n + a * e1).normalized());
      directions.push_back((b * n + a * e2).normalized());
    }
  double best_cost = std::numeric_limits<double>::infinity();
  for (const Vec3& dir : directions)
    for (double up_sign : {-1.0, 1.0}) {
      Camera c;
      c.width = width;
      c.height = height;
      c.fx = c.fy = focal;
      c.cx = 0.5 * width;
      c.cy = 0.5 * height;
      const Vec3 z = -dir;  // looking at the centroid
      Vec3 up = up_sign * (std::abs(z.dot(e2)) < 0.9 ? e2 : e1);
      const Vec3 y = -(up - up.dot(z) * z).normalized();  // image y runs down
      const Vec3 x = y.cross(z);
      c.R.row(0) = x;
      c.R.row(1) = y;
      c.R.row(2) = z;
      c.t = -c.R * (centroid + distance * dir);
      c = refine(c, FreeParams{false, false, false, false, false}, cs, idx, 40);
      const double cost = residuals(c, cs, idx).squaredNorm();
      int in_front = 0;
      for (int i : idx) in_front += c.to_camera(cs[size_t(i)].point).z() > 0;
      const bool right_side = seen_from.isZero() || (c.center() - centroid).dot(seen_from) > 0;
      if (in_front == int(idx.size()) && right_side && cost < best_cost) {
        best_cost = cost;
        best = c;
      }
    }
  return std::isfinite(best_cost);
}

// RANSAC's trial count for an inlier share w and samples of s points: the
// N with 1 - (1 - w^s)^N >= confidence, at most cap (confidence 0: cap).
int ransac_trials_needed(double w, int s, double confidence, int cap) {
  if (!(confidence > 0 && confidence < 1)) return cap;
  const double all_in = std::pow(w, s);
  if (all_in >= 1) return 1;
  if (all_in <= 0) return cap;
  const double n = std::ceil(std::log(1 - confidence) / std::log(1 - all_in));
  return n < cap ? std::max(1, int(n)) : cap;
}

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  const size_t m = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + m, v.end());
  return v[m];
}

std::vector<double> errors_of(const Camera& cam, const std::vector<Correspondence>& cs) {
  std::vector<double> e(cs.size());
  for (size_t i = 0; i < cs.size(); ++i) {
    Vec2 uv;
    e[i] = cam.project(cs[i].point, uv) ? (uv - cs[i].pixel).norm()
                                        : std::numeric_limits<double>::infinity();
  }
  return e;
}


// A free focal length outside [0.2, 50] image diagonals (fields of view of
// about 160 deg down to 1.2 deg) is not a photo of a head: it is what LM
// reaches when the points cannot separate focal length from distance (too
// few, nearly coplanar, or very noisy clicks) and drifts towards an affine
// camera at infinity. Say so instead of returning it.
Status check_focal_plausible(double focal, int width, int height, const std::string& who) {
  const double diagonal = std::hypot(double(width), double(height));
  if (std::isfinite(focal) && focal >= 0.2 * diagonal && focal <= 50 * diagonal) return Status::success();
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.4g", focal);
  return Status::error(ErrorCode::NotConverged,
                       who + "the focal length came out as " + buf + " px for a " + std::to_string(width) + "x" +
                           std::to_string(height) + " photo, which no camera has: the points cannot determine it "
                           "(too few, too noisy, or nearly flat). Give the focal length, add photos taken with the "
                           "same camera, or click more points.");
}
}  // namespace

Status calibrate_camera(const std::vector<Correspondence>& cs, int image_width, int image_height,
                        const CalibOptions& options, CalibResult& result) {
  result = CalibResult{};
  const int n = int(cs.size());
  if (n < 6)
    return Status::error(ErrorCode::InvalidInput,
                         "calibration needs at least 6 point correspondences, got " + std::to_string(n));
  if (image_width <= 0 || image_height <= 0)
    return Status::error(ErrorCode::InvalidInput, "calibration needs a positive image size");
  for (int i = 0; i < n; ++i)
    if (!cs[i].pixel.allFinite() || !cs[i].point.allFinite())
      return Status::error(ErrorCode::InvalidInput,
                           "correspondence " + std::to_string(i) + " has a NaN or infinite coordinate");
  if (options.known_focal < 0 || !std::isfinite(options.known_focal))
    return Status::error(ErrorCode::InvalidInput, "known_focal must be positive (or 0 = unknown)");
  if (options.focal_prior < 0 || !std::isfinite(options.focal_prior) || !(options.focal_prior_sigma > 0) ||
      !std::isfinite(options.focal_prior_sigma) || !(options.pixel_sigma > 0) || !std::isfinite(options.pixel_sigma) ||
      !options.seen_from.allFinite() || !(options.ransac_confidence >= 0 && options.ransac_confidence < 1))
    return Status::error(ErrorCode::InvalidInput,
                         "focal_prior must be >= 0 (0 = none), focal_prior_sigma and pixel_sigma positive, "
                         "seen_from finite, ransac_confidence in [0, 1)");
  const FocalPrior prior = focal_prior_of(options);

  // Shape of the 3-D point set: collinear sets never determine a camera;
  // coplanar ones cannot give intrinsics and pose together by DLT.
  Vec3 centroid = Vec3::Zero();
  for (const auto& c : cs) centroid += c.point;
  centroid /= n;
  Mat3 cov = Mat3::Zero();
  for (const auto& c : cs) cov += (c.point - centroid) * (c.point - centroid).transpose();
  Eigen::JacobiSVD<Mat3> shape(cov, Eigen::ComputeFullU);
  const Vec3 sv = shape.singularValues().cwiseSqrt();
  if (sv[0] <= 0 || sv[1] < 1e-6 * sv[0])
    return Status::error(ErrorCode::InvalidInput,
                         "the 3-D points are collinear (or identical): they cannot determine a camera");
  const bool known = options.known_focal > 0;
  const bool coplanar = sv[2] < 1e-3 * sv[0];
  if (coplanar && !known)
    return Status::error(ErrorCode::InvalidInput,
                         "the 3-D points are coplanar: intrinsics and pose cannot both be estimated "
                         "from them; give the focal length (known_focal) or pick points off the plane");

  // Initial camera from a set of correspondences (DLT, or the plane
  // homography for coplanar points with known intrinsics).
  auto initial = [&](const std::vector<int>& idx, Camera& cam) {
    cam = Camera{};
    cam.width = image_width;
    cam.height = image_height;
    if (coplanar) {
      cam.fx = cam.fy = options.known_focal;
      cam.cx = 0.5 * image_width;
      cam.cy = 0.5 * image_height;
      return pose_from_plane(cs, idx, centroid, shape.matrixU(), cam);
    }
    if (!decompose(dlt(cs, idx), cs, idx, cam)) {
      // Face landmarks are shallow (depth ~ half their width): with clicking
      // errors and a head that is not the subject's, DLT can come out
      // mirrored. With known intrinsics the pose of the best-fit plane is a
      // usable start for LM.
      if (!known) return false;
      return multi_start_pose(cs, idx, centroid, shape.matrixU(), options.known_focal, image_width, image_height,
                              options.seen_from, cam);
    }
    cam.width = image_width;
    cam.height = image_height;
    if (known) {
      cam.fx = cam.fy = options.known_focal;
      cam.cx = 0.5 * image_width;
      cam.cy = 0.5 * image_height;
      if (!options.seen_from.isZero() && (cam.center() - centroid).dot(options.seen_from) <= 0)
        return multi_start_pose(cs, idx, centroid, shape.matrixU(), options.known_focal, image_width, image_height,
                                options.seen_from, cam);
    }
    return std::isfinite(cam.fx) && cam.fx > 0 && cam.fy > 0;
  };

  std::vector<int> all(n);
  for (int i = 0; i < n; ++i) all[i] = i;
  const double diag = std::hypot(double(image_width), double(image_height));

  // RANSAC over minimal sets: a 6-point DLT is an exact fit, so hypotheses are
  // scored with a generous threshold; the final threshold comes later.
  std::vector<int> inliers = all;
  if (options.robust && n > 6) {
    const double ransac_px = std::max(4 * options.outlier_px, 0.005 * diag);
    SplitMix64 rng(0x5eed);
    int best = -1;
    double best_sum = 0;
    const int sample = 6;
    int trials = options.ransac_iterations;
    for (int trial = 0; trial < trials; ++trial) {
      std::vector<int> pool = all, pick;
      for (int s = 0; s < sample; ++s) {
        const int j = s + int(rng.next() % std::uint64_t(n - s));
        std::swap(pool[s], pool[j]);
        pick.push_back(pool[s]);
      }
      Camera cam;
      if (!initial(pick, cam)) continue;
      if (!options.separate_focal) cam.fx = cam.fy = 0.5 * (cam.fx + cam.fy);
      cam = refine(cam, FreeParams{!known, options.separate_focal, false, false, false}, cs, pick, 10);
      const std::vector<double> e = errors_of(cam, cs);
      int count = 0;
      double sum = 0;
      for (double v : e)
        if (v < ransac_px) { ++count; sum += v; }
      if (count > best || (count == best && sum < best_sum)) {
        best = count;
        best_sum = sum;
        inliers.clear();
        for (int i = 0; i < n; ++i)
          if (e[i] < ransac_px) inliers.push_back(i);
        trials = std::min(trials, ransac_trials_needed(double(best) / n, sample, options.ransac_confidence,
                                                       options.ransac_iterations));
      }
      if (best == n) break;
    }
    if (best < 6) inliers = all;  // no consensus: let the refinement below decide
  }

  Camera cam;
  if (!initial(inliers, cam))
    return Status::error(ErrorCode::InvalidInput,
                         options.seen_from.isZero()
                             ? "no camera puts the 3-D points in front of it (points behind the camera, "
                               "or mirrored correspondences)"
                             : "no camera on the seen_from side puts the 3-D points in front of it");

  // Refine on the inliers, re-classify every point, repeat until stable.
  std::vector<double> e;
  for (int round = 0; round < 6; ++round) {
    const int m = int(inliers.size());
    FreeParams fp;
    fp.focal = !known;
    fp.separate = options.separate_focal;
    fp.principal = !options.fix_principal_point && m >= 8;
    fp.k1 = options.estimate_k1 && m >= 8;
    fp.k2 = options.estimate_k2 && m >= 10;
    if (!fp.principal) { cam.cx = 0.5 * image_width; cam.cy = 0.5 * image_height; }
    if (!fp.separate) cam.fx = cam.fy = 0.5 * (cam.fx + cam.fy);  // DLT's K has fx != fy
    // With a prior, the pose is first fitted at the prior's focal: closer to
    // the truth than a 12-point DLT's focal, which can be 30 % off.
    if (round == 0 && prior.active()) cam.fx = cam.fy = prior.focal;
    // Pose first (intrinsics held), then everything: a far-off DLT focal
    // with distortion otherwise lets LM wander.
    cam = refine(cam, FreeParams{false, false, false, false, false}, cs, inliers, options.max_lm_iterations);
    cam = refine(cam, fp, cs, inliers, options.max_lm_iterations, prior);
    e = errors_of(cam, cs);
    if (!options.robust) break;
    std::vector<double> in_err;
    for (int i : inliers) in_err.push_back(e[i]);
    const double threshold = std::max(options.outlier_px, 3 * 1.4826 * median(in_err));
    std::vector<int> next;
    for (int i = 0; i < n; ++i)
      if (e[i] < threshold) next.push_back(i);
    if (next.size() < 6 || next == inliers) break;
    inliers = next;
  }

  if (!(cam.fx > 0) || !(cam.fy > 0) || !std::isfinite(cam.fx) || !cam.t.allFinite())
    return Status::error(ErrorCode::NotConverged, "calibration did not converge to a valid camera");
  if (options.known_focal <= 0) {
    const Status plausible = check_focal_plausible(cam.fx, image_width, image_height, "");
    if (!plausible) return plausible;
  }
  int behind = 0;
  for (int i : inliers) behind += cam.to_camera(cs[i].point).z() <= 0;
  if (behind > 0)
    return Status::error(ErrorCode::InvalidInput,
                         std::to_string(behind) + " of the points are behind the calibrated camera");
  if (!options.seen_from.isZero() && (cam.center() - centroid).dot(options.seen_from) <= 0)
    return Status::error(ErrorCode::NotConverged,
                         "the calibrated camera is on the wrong side of the points (seen_from): a mirrored pose");

  result.camera = cam;
  result.errors = e;
  result.outlier.assign(n, 1);
  double sq = 0;
  for (int i : inliers) { result.outlier[i] = 0; sq += e[i] * e[i]; }
  result.num_inliers = int(inliers.size());
  result.rms = std::sqrt(sq / std::max(1, result.num_inliers));
  return Status::success();
}


namespace {

// Joint LM over [f, (w_1, t_1), ..., (w_P, t_P)]: one shared focal, a pose per
// photo (rotation as a local axis-angle update, re-based after each step).
struct JointProblem {
  const std::vector<std::vector<Correspondence>>* photos = nullptr;
  const std::vector<std::vector<int>>* inliers = nullptr;
  FocalPrior prior;
  Eigen::Index rows = 0;

  std::vector<Camera> apply(const std::vector<Camera>& base, const VecX& p) const {
    std::vector<Camera> c = base;
    for (size_t i = 0; i < c.size(); ++i) {
      c[i].fx = c[i].fy = p[0];
      const Vec3 w = p.segment<3>(1 + 6 * Eigen::Index(i));
      c[i].R = rotation_from_vector(w) * base[i].R;
      c[i].t = p.segment<3>(4 + 6 * Eigen::Index(i));
    }
    return c;
  }
  VecX pack(const std::vector<Camera>& c) const {
    VecX p(1 + 6 * Eigen::Index(c.size()));
    p[0] = c[0].fx;
    for (size_t i = 0; i < c.size(); ++i) {
      p.segment<3>(1 + 6 * Eigen::Index(i)) = Vec3::Zero();
      p.segment<3>(4 + 6 * Eigen::Index(i)) = c[i].t;
    }
    return p;
  }
  VecX residuals(const std::vector<Camera>& c) const {
    VecX r(rows);
    Eigen::Index at = 0;
    for (size_t i = 0; i < c.size(); ++i) {
      reprojection(c[i], (*photos)[i], (*inliers)[i], r, at);
      at += 2 * Eigen::Index((*inliers)[i].size());
    }
    if (prior.active()) r[at] = prior.residual(c[0].fx);
    return r;
  }
};

// Each pose only moves its own photo's residuals, but a dense numeric
// Jacobian of ~30 columns by a few hundred rows costs well under 1 ms.
std::vector<Camera> refine_joint(const std::vector<Camera>& base, const JointProblem& jp, int max_iterations) {
  return levenberg_marquardt(
      base, [&](const std::vector<Camera>& c) { return jp.pack(c); },
      [&](const std::vector<Camera>& c, const VecX& p) { return jp.apply(c, p); },
      [&](const std::vector<Camera>& c) { return jp.residuals(c); },
      [](const std::vector<Camera>& c) { return c[0].fx > 0; }, max_iterations);
}

}  // namespace

Status calibrate_cameras_shared(const std::vector<std::vector<Correspondence>>& photos,
                                const std::vector<std::array<int, 2>>& image_sizes, const CalibOptions& options,
                                SharedCalibResult& result) {
  result = SharedCalibResult{};
  const size_t np = photos.size();
  if (np == 0) return Status::error(ErrorCode::InvalidInput, "shared calibration needs at least one photo");
  if (image_sizes.size() != np)
    return Status::error(ErrorCode::InvalidInput, std::to_string(np) + " sets of correspondences for " +
                                                      std::to_string(image_sizes.size()) + " image sizes");
  if (options.separate_focal || !options.fix_principal_point || options.estimate_k1 || options.estimate_k2)
    return Status::error(ErrorCode::InvalidInput,
                         "shared calibration estimates one focal (fx = fy) with centred principal points and "
                         "no distortion: turn off separate_focal, estimate_k1/k2 and keep fix_principal_point");

  // 1. Each photo alone: poses, inlier sets, one focal estimate per photo.
  result.photos.resize(np);
  std::vector<double> focals;
  std::vector<Status> alone(np);
  for (size_t i = 0; i < np; ++i) {
    alone[i] = calibrate_camera(photos[i], image_sizes[i][0], image_sizes[i][1], options, result.photos[i]);
    if (alone[i]) focals.push_back(result.photos[i].camera.fx);
    else if (alone[i].code != ErrorCode::InvalidInput && alone[i].code != ErrorCode::NotConverged)
      return Status::error(alone[i].code, "photo " + std::to_string(i) + ": " + alone[i].message);
  }
  // A photo that cannot be calibrated alone (e.g. shallow, mismatched face
  // landmarks that DLT mirrors) gets its pose at the focal the others (or the
  // prior) give, then joins the joint refinement.
  const double fallback_focal = options.focal_prior > 0 ? options.focal_prior : focals.empty() ? 0 : median(focals);
  for (size_t i = 0; i < np; ++i) {
    if (alone[i]) continue;
    if (fallback_focal <= 0 || options.known_focal > 0 || int(photos[i].size()) < 6 ||
        alone[i].message.find("NaN") != std::string::npos)
      return Status::error(alone[i].code, "photo " + std::to_string(i) + ": " + alone[i].message);
    CalibOptions at_focal = options;
    at_focal.known_focal = fallback_focal;
    const Status s = calibrate_camera(photos[i], image_sizes[i][0], image_sizes[i][1], at_focal, result.photos[i]);
    if (!s) return Status::error(s.code, "photo " + std::to_string(i) + ": " + s.message);
  }
  if (options.known_focal > 0) {  // nothing is shared that is not already known
    result.focal = options.known_focal;
  } else {
    // 2. Start: the prior, else the median single-photo focal; each pose
    // re-fitted at that focal so LM starts near a consistent solution.
    const FocalPrior prior = focal_prior_of(options);
    const double f0 = prior.active() ? prior.focal : median(focals);
    std::vector<Camera> cams(np);
    std::vector<std::vector<int>> inliers(np);
    for (size_t i = 0; i < np; ++i) {
      for (size_t k = 0; k < photos[i].size(); ++k)
        if (!result.photos[i].outlier[k]) inliers[i].push_back(int(k));
      cams[i] = result.photos[i].camera;
      cams[i].fx = cams[i].fy = f0;
      cams[i] = refine(cams[i], FreeParams{false, false, false, false, false}, photos[i], inliers[i],
                       options.max_lm_iterations);
    }
    // 3. Joint refinement; re-classify outliers per photo; repeat until stable.
    JointProblem jp;
    jp.photos = &photos;
    jp.inliers = &inliers;
    jp.prior = prior;
    for (int round = 0; round < 4; ++round) {
      jp.rows = prior.active() ? 1 : 0;
      for (const auto& in : inliers) jp.rows += 2 * Eigen::Index(in.size());
      cams = refine_joint(cams, jp, options.max_lm_iterations);
      if (!options.robust) break;
      bool changed = false;
      for (size_t i = 0; i < np; ++i) {
        const std::vector<double> e = errors_of(cams[i], photos[i]);
        std::vector<double> in_err;
        for (int k : inliers[i]) in_err.push_back(e[size_t(k)]);
        const double threshold = std::max(options.outlier_px, 3 * 1.4826 * median(in_err));
        std::vector<int> next;
        for (size_t k = 0; k < photos[i].size(); ++k)
          if (e[k] < threshold) next.push_back(int(k));
        if (next.size() >= 6 && next != inliers[i]) { inliers[i] = next; changed = true; }
      }
      if (!changed) break;
    }
    if (!(cams[0].fx > 0) || !std::isfinite(cams[0].fx))
      return Status::error(ErrorCode::NotConverged, "shared calibration did not converge to a valid focal");
    result.focal = cams[0].fx;
    for (size_t i = 0; i < np; ++i) {
      const Status plausible = check_focal_plausible(result.focal, image_sizes[i][0], image_sizes[i][1],
                                                     "shared calibration, photo " + std::to_string(i) + ": ");
      if (!plausible) return plausible;
    }
    for (size_t i = 0; i < np; ++i) {
      CalibResult& r = result.photos[i];
      r.camera = cams[i];
      r.errors = errors_of(cams[i], photos[i]);
      r.outlier.assign(photos[i].size(), 1);
      double sq = 0;
      for (int k : inliers[i]) { r.outlier[size_t(k)] = 0; sq += r.errors[size_t(k)] * r.errors[size_t(k)]; }
      r.num_inliers = int(inliers[i].size());
      r.rms = std::sqrt(sq / std::max(1, r.num_inliers));
      for (int k : inliers[i])
        if (cams[i].to_camera(photos[i][size_t(k)].point).z() <= 0)
          return Status::error(ErrorCode::NotConverged,
                               "photo " + std::to_string(i) + ": the shared focal puts points behind the camera");
    }
  }
  double sq = 0;
  int count = 0;
  for (const CalibResult& r : result.photos) {
    sq += r.rms * r.rms * r.num_inliers;
    count += r.num_inliers;
  }
  result.rms = std::sqrt(sq / std::max(1, count));
  return Status::success();
}

}  // namespace lk
