#include "align/face_symmetry.h"

#include "align/face_refine.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

namespace lk {

namespace {

// The scan's relief over one view: heights toward the viewer per cell
// (NaN: nothing drawn there), less the best quadric, clipped.
struct Relief {
  int cols = 0, rows = 0;
  double x0 = 0, cell = 0;
  std::vector<double> h;
};

bool detrend_and_clip(Relief& map, double clip_sigmas) {
  std::vector<int> valid;
  for (int k = 0; k < int(map.h.size()); ++k)
    if (std::isfinite(map.h[k])) valid.push_back(k);
  if (valid.size() < 12) return false;
  Eigen::MatrixXd A(valid.size(), 6);
  Eigen::VectorXd b(valid.size());
  for (size_t r = 0; r < valid.size(); ++r) {
    const int k = valid[r];
    // In cells, so the normal equations stay well scaled.
    const double x = (k % map.cols) - 0.5 * map.cols, y = (k / map.cols) - 0.5 * map.rows;
    A.row(r) << 1, x, y, x * x, x * y, y * y;
    b(r) = map.h[k] / map.cell;
  }
  const Eigen::VectorXd q = A.colPivHouseholderQr().solve(b);
  const Eigen::VectorXd res = b - A * q;
  std::vector<double> dev(res.data(), res.data() + res.size());
  std::nth_element(dev.begin(), dev.begin() + dev.size() / 2, dev.end());
  const double median = dev[dev.size() / 2];
  for (double& d : dev) d = std::fabs(d - median);
  std::nth_element(dev.begin(), dev.begin() + dev.size() / 2, dev.end());
  const double sigma = 1.4826 * dev[dev.size() / 2];
  const double limit = clip_sigmas * std::max(sigma, 1e-12);
  for (size_t r = 0; r < valid.size(); ++r) map.h[valid[r]] = std::clamp(res(r) - median, -limit, limit);
  return true;
}

// The best correlation of the map with its mirror image about vertical
// midlines within max_shift of x = 0 (the face's centre); -2 when no
// midline pairs enough cells.
double best_mirror_correlation(const Relief& map, double max_shift, double min_paired, double& midline) {
  int valid = 0;
  for (double v : map.h) valid += std::isfinite(v);
  double best = -2;
  // Midline m = x0 + k * cell / 2 mirrors column i onto k - i - 1.
  const int k_lo = static_cast<int>(std::ceil((-max_shift - map.x0) * 2 / map.cell));
  const int k_hi = static_cast<int>(std::floor((max_shift - map.x0) * 2 / map.cell));
  for (int k = k_lo; k <= k_hi; ++k) {
    double sa = 0, sb = 0, saa = 0, sbb = 0, sab = 0;
    int n = 0;
    for (int r = 0; r < map.rows; ++r)
      for (int i = 0; i < map.cols; ++i) {
        const int j = k - i - 1;
        if (j < 0 || j >= map.cols || j == i) continue;
        const double a = map.h[r * map.cols + i], b = map.h[r * map.cols + j];
        if (!std::isfinite(a) || !std::isfinite(b)) continue;
        sa += a, sb += b, saa += a * a, sbb += b * b, sab += a * b, ++n;
      }
    if (n < 12 || n < min_paired * valid) continue;
    const double cov = sab - sa * sb / n, va = saa - sa * sa / n, vb = sbb - sb * sb / n;
    if (!(va > 0 && vb > 0)) continue;
    const double c = cov / std::sqrt(va * vb);
    if (c > best) best = c, midline = map.x0 + k * map.cell / 2;
  }
  return best;
}

}  // namespace

Status face_symmetry_yaw(const std::vector<Vec3>& face_samples, const Vec3& view, const Vec3& up,
                         const MeshBvh& surface, const std::vector<Vec3>& cloud, const FaceSymmetryOptions& o,
                         FaceSymmetry& out) {
  out = FaceSymmetry{};
  if (face_samples.size() < 10) return Status::error(ErrorCode::InvalidInput, "face symmetry: too few face samples");
  if (!(o.yaw_range_deg >= 0) || !(o.yaw_step_deg > 0) || o.cells_across < 8 || !(o.margin >= 0) ||
      !(o.max_midline_shift >= 0) || !(o.clip_sigmas > 0) || !(o.min_paired >= 0 && o.min_paired <= 1))
    return Status::error(ErrorCode::InvalidInput, "face symmetry: bad options");
  Vec3 centre = Vec3::Zero();
  for (const Vec3& p : face_samples) {
    if (!p.allFinite()) return Status::error(ErrorCode::InvalidInput, "face symmetry: non-finite face sample");
    centre += p;
  }
  centre /= double(face_samples.size());
  const Vec3 v0 = view.normalized();
  const Vec3 u = (up - up.dot(v0) * v0).normalized();
  if (!v0.allFinite() || !u.allFinite() || !(std::fabs(up.normalized().dot(v0)) < 0.99))
    return Status::error(ErrorCode::InvalidInput, "face symmetry: bad view or up direction");

  const double kDeg = 3.14159265358979323846 / 180.0;
  const int steps = static_cast<int>(std::floor(o.yaw_range_deg / o.yaw_step_deg + 1e-9));
  for (int s = -steps; s <= steps; ++s) {
    const double yaw = s * o.yaw_step_deg;
    const Vec3 v = Eigen::AngleAxisd(yaw * kDeg, u) * v0;
    const Vec3 x_axis = u.cross(v);
    double xlo = 1e300, xhi = -1e300, ylo = 1e300, yhi = -1e300, zlo = 1e300, zhi = -1e300;
    for (const Vec3& p : face_samples) {
      const Vec3 d = p - centre;
      xlo = std::min(xlo, x_axis.dot(d)), xhi = std::max(xhi, x_axis.dot(d));
      ylo = std::min(ylo, u.dot(d)), yhi = std::max(yhi, u.dot(d));
      zlo = std::min(zlo, v.dot(d)), zhi = std::max(zhi, v.dot(d));
    }
    const double width = xhi - xlo, height = yhi - ylo;
    if (!(width > 0 && height > 0)) return Status::error(ErrorCode::InvalidInput, "face symmetry: flat face samples");
    Relief map;
    map.cols = o.cells_across;
    map.cell = width * (1 + 2 * o.margin) / map.cols;
    map.x0 = xlo - o.margin * width;
    const double y0 = ylo - o.margin * height;
    map.rows = std::max(1, static_cast<int>(std::ceil(height * (1 + 2 * o.margin) / map.cell)));
    map.h.assign(size_t(map.cols) * map.rows, std::numeric_limits<double>::quiet_NaN());
    // The cell a point (less the centre) falls in, false outside the map.
    auto cell_of = [&](const Vec3& d, int& i, int& r) {
      i = static_cast<int>(std::floor((x_axis.dot(d) - map.x0) / map.cell));
      r = static_cast<int>(std::floor((u.dot(d) - y0) / map.cell));
      return i >= 0 && i < map.cols && r >= 0 && r < map.rows;
    };
    // Only the cells the face's samples cover (dilated by one) are drawn:
    // the relief of a beard, a beret or hair beside the face is not the face's.
    std::vector<char> covered(map.h.size(), 0);
    for (const Vec3& p : face_samples) {
      int i = 0, r = 0;
      cell_of(p - centre, i, r);
      for (int dr = -1; dr <= 1; ++dr)
        for (int di = -1; di <= 1; ++di)
          if (i + di >= 0 && i + di < map.cols && r + dr >= 0 && r + dr < map.rows)
            covered[(r + dr) * map.cols + i + di] = 1;
    }
    // Surface within half the face's width in front of and behind its samples.
    const double z_front = zhi + 0.5 * width, z_back = zlo - 0.5 * width;
    if (!surface.empty()) {
      for (int r = 0; r < map.rows; ++r)
        for (int i = 0; i < map.cols; ++i) {
          if (!covered[r * map.cols + i]) continue;
          Ray ray;
          ray.origin = centre + (map.x0 + (i + 0.5) * map.cell) * x_axis + (y0 + (r + 0.5) * map.cell) * u + z_front * v;
          ray.direction = -v;
          ray.t_max = z_front - z_back;
          const RayHit hit = intersect_first(surface, ray);
          if (hit.hit()) map.h[r * map.cols + i] = z_front - hit.t;
        }
    } else {
      for (const Vec3& p : cloud) {
        const Vec3 d = p - centre;
        const double z = v.dot(d);
        int i = 0, r = 0;
        if (!(z >= z_back && z <= z_front) || !cell_of(d, i, r) || !covered[r * map.cols + i]) continue;
        double& h = map.h[r * map.cols + i];
        if (!(h >= z)) h = z;  // NaN or lower
      }
    }
    double score = -2, midline = 0;
    if (detrend_and_clip(map, o.clip_sigmas))
      score = best_mirror_correlation(map, o.max_midline_shift * width, o.min_paired, midline);
    out.yaws_deg.push_back(yaw);
    out.scores.push_back(score);
    if (score > out.score) out.score = score, out.yaw_deg = yaw, out.midline_shift = midline;
  }
  if (!(out.score > -1.5)) return Status::error(ErrorCode::Empty, "face symmetry: no view drew enough of the scan");
  return Status::success();
}

Status face_symmetry_of_alignment(const TriMesh& generic, const HeadAnnotations& ann, const std::vector<Vec3>& cloud,
                                  const std::vector<Tri>& faces, const Mat3& linear, const Vec3& translation,
                                  const FaceSymmetryOptions& options, FaceSymmetry& out) {
  out = FaceSymmetry{};
  if (!linear.allFinite() || !translation.allFinite())
    return Status::error(ErrorCode::InvalidInput, "face symmetry: bad alignment");
  std::vector<Vec3> face = upper_face_samples(generic, ann, FaceRefineOptions{}.samples);
  for (Vec3& p : face) p = linear * p + translation;
  TriMesh scan;
  scan.positions = cloud;
  scan.triangles = faces;
  MeshBvh surface;
  if (!faces.empty()) {
    const Status st = build_bvh(scan, surface);
    if (!st) return st;
  }
  return face_symmetry_yaw(face, linear * ann.look, linear * ann.up, surface, cloud, options, out);
}

}  // namespace lk
