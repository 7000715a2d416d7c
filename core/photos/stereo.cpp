#include "photos/stereo.h"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <climits>
#include <cmath>
#include <limits>

namespace lk {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// Summed-area table, (w + 1) x (h + 1).
struct Integral {
  int w = 0, h = 0;
  std::vector<double> s;
  double at(int x, int y) const { return s[size_t(y) * size_t(w + 1) + size_t(x)]; }
  // Sum over the box [x0, x1] x [y0, y1], inclusive.
  double box(int x0, int y0, int x1, int y1) const {
    return at(x1 + 1, y1 + 1) - at(x0, y1 + 1) - at(x1 + 1, y0) + at(x0, y0);
  }
};

template <class F>
Integral integral(int w, int h, F value) {
  Integral I;
  I.w = w;
  I.h = h;
  I.s.assign(size_t(w + 1) * size_t(h + 1), 0.0);
  for (int y = 0; y < h; ++y) {
    double row = 0;
    for (int x = 0; x < w; ++x) {
      row += value(x, y);
      I.s[size_t(y + 1) * size_t(w + 1) + size_t(x + 1)] = I.s[size_t(y) * size_t(w + 1) + size_t(x + 1)] + row;
    }
  }
  return I;
}

// Window mean and standard deviation of every pixel (std -1 where the window leaves the image).
void window_stats(const ImageF& im, int r, std::vector<float>& mean, std::vector<float>& sd) {
  const int w = im.width, h = im.height;
  const Integral S = integral(w, h, [&](int x, int y) { return double(*im.at(x, y)); });
  const Integral S2 = integral(w, h, [&](int x, int y) { return double(*im.at(x, y)) * *im.at(x, y); });
  const double n = double(2 * r + 1) * (2 * r + 1);
  mean.assign(size_t(w) * size_t(h), 0.f);
  sd.assign(size_t(w) * size_t(h), -1.f);
  for (int y = r; y < h - r; ++y)
    for (int x = r; x < w - r; ++x) {
      const double m = S.box(x - r, y - r, x + r, y + r) / n;
      const double v = S2.box(x - r, y - r, x + r, y + r) / n - m * m;
      mean[size_t(y) * size_t(w) + size_t(x)] = float(m);
      sd[size_t(y) * size_t(w) + size_t(x)] = float(std::sqrt(std::max(0.0, v)));
    }
}

std::vector<Vec2> convex_hull(std::vector<Vec2> p) {
  std::sort(p.begin(), p.end(), [](const Vec2& a, const Vec2& b) { return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y()); });
  if (p.size() < 3) return p;
  auto cross = [](const Vec2& o, const Vec2& a, const Vec2& b) {
    return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
  };
  std::vector<Vec2> h(2 * p.size());
  size_t k = 0;
  for (size_t i = 0; i < p.size(); ++i) {
    while (k >= 2 && cross(h[k - 2], h[k - 1], p[i]) <= 0) --k;
    h[k++] = p[i];
  }
  for (size_t i = p.size() - 1, t = k + 1; i > 0; --i) {
    while (k >= t && cross(h[k - 2], h[k - 1], p[i - 1]) <= 0) --k;
    h[k++] = p[i - 1];
  }
  h.resize(k - 1);
  return h;
}

// Inside a convex polygon in counter-clockwise order (as convex_hull gives).
bool inside_convex(const std::vector<Vec2>& hull, const Vec2& q) {
  if (hull.size() < 3) return false;
  for (size_t i = 0; i < hull.size(); ++i) {
    const Vec2& a = hull[i];
    const Vec2& b = hull[(i + 1) % hull.size()];
    if ((b.x() - a.x()) * (q.y() - a.y()) - (b.y() - a.y()) * (q.x() - a.x()) < 0) return false;
  }
  return true;
}

double view_angle_deg(const Camera& a, const Camera& b, const Vec3& centre) {
  const Vec3 u = (a.center() - centre).normalized(), v = (b.center() - centre).normalized();
  return std::acos(std::max(-1.0, std::min(1.0, u.dot(v)))) * 180 / kPi;
}

}  // namespace

Status compute_disparity(const ImageF& left, const ImageF& right, const std::vector<std::uint8_t>& mask, int d_min,
                         int d_max, const DisparityOptions& o, DisparityMap& out) {
  out = {};
  if (left.empty() || right.empty() || left.channels != 1 || right.channels != 1)
    return Status::error(ErrorCode::InvalidInput, "disparity: empty or non-grey image");
  if (left.height != right.height)
    return Status::error(ErrorCode::InvalidInput, "disparity: the rectified images differ in height");
  if (!mask.empty() && mask.size() != size_t(left.width) * size_t(left.height))
    return Status::error(ErrorCode::InvalidInput, "disparity: the mask is not the left image's size");
  if (d_min > d_max || o.radius < 1 || o.lr_tolerance < 0)
    return Status::error(ErrorCode::InvalidInput, "disparity: empty disparity range or bad option");
  const int W = left.width, Wr = right.width, H = left.height, r = o.radius;
  const double n = double(2 * r + 1) * (2 * r + 1);
  std::vector<float> mL, sL, mR, sR;
  window_stats(left, r, mL, sL);
  window_stats(right, r, mR, sR);
  const size_t NL = size_t(W) * size_t(H), NR = size_t(Wr) * size_t(H);
  std::vector<float> best_c(NL, -2.f), c_minus(NL, kNaN), c_plus(NL, kNaN), last_c(NL, kNaN);
  std::vector<int> best_d(NL, INT_MIN), last_d(NL, INT_MIN);
  std::vector<float> bestR_c(NR, -2.f);
  std::vector<int> bestR_d(NR, INT_MIN);
  for (int d = d_min; d <= d_max; ++d) {
    const Integral P = integral(W, H, [&](int x, int y) {
      const int xr = x - d;
      return xr >= 0 && xr < Wr ? double(*left.at(x, y)) * *right.at(xr, y) : 0.0;
    });
    for (int y = r; y < H - r; ++y)
      for (int x = std::max(r, d + r); x < std::min(W - r, Wr - r + d); ++x) {
        const size_t i = size_t(y) * size_t(W) + size_t(x), j = size_t(y) * size_t(Wr) + size_t(x - d);
        if (sL[i] < o.min_std || sR[j] < o.min_std) continue;
        const double cov = P.box(x - r, y - r, x + r, y + r) / n - double(mL[i]) * mR[j];
        const float c = float(cov / (double(sL[i]) * sR[j]));
        if (c > best_c[i]) {
          best_c[i] = c;
          c_minus[i] = last_d[i] == d - 1 ? last_c[i] : kNaN;
          c_plus[i] = kNaN;
          best_d[i] = d;
        } else if (best_d[i] == d - 1) {
          c_plus[i] = c;
        }
        last_c[i] = c;
        last_d[i] = d;
        if (c > bestR_c[j]) {
          bestR_c[j] = c;
          bestR_d[j] = d;
        }
      }
  }
  out.width = W;
  out.height = H;
  out.d.assign(NL, kNaN);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      const size_t i = size_t(y) * size_t(W) + size_t(x);
      if (!mask.empty() && !mask[i]) continue;
      ++out.searched;
      if (sL[i] < o.min_std || best_d[i] == INT_MIN) {
        ++out.low_texture;
        continue;
      }
      if (best_c[i] < o.min_ncc) {
        ++out.low_score;
        continue;
      }
      if (std::isnan(c_minus[i]) || std::isnan(c_plus[i])) {  // best at the end of the head's depth range
        ++out.at_range_end;
        continue;
      }
      const int x2 = x - best_d[i];
      if (x2 < 0 || x2 >= Wr || std::abs(bestR_d[size_t(y) * size_t(Wr) + size_t(x2)] - best_d[i]) > o.lr_tolerance) {
        ++out.lr_rejected;
        continue;
      }
      // Parabola through the scores at d - 1, d, d + 1: its vertex.
      const double den = double(c_minus[i]) - 2.0 * best_c[i] + c_plus[i];
      const double off = den < 0 ? std::max(-0.5, std::min(0.5, 0.5 * (double(c_minus[i]) - c_plus[i]) / den)) : 0.0;
      out.d[i] = float(best_d[i] + off);
      ++out.valid;
    }
  return Status::success();
}

bool triangulate_rectified(const RectifiedCameras& rc, double x, double y, double d, Vec3& X) {
  const double f = rc.a.fx;
  const double den = d - rc.a.cx + rc.b.cx;  // = f baseline / depth
  if (!(den > 1e-9)) return false;
  const double Z = f * rc.baseline / den;
  const Vec3 p((x + 0.5 - rc.a.cx) * Z / f, (y + 0.5 - rc.a.cy) * Z / f, Z);
  X = rc.a.center() + rc.a.R.transpose() * p;
  return true;
}

bool fit_plane_robust(const std::vector<Vec3>& points, double min_sigma, Vec3& centre, Vec3& normal, int& inliers,
                      double& rms) {
  auto fit = [&](const std::vector<Vec3>& p) {
    if (p.size() < 3) return false;
    Vec3 c = Vec3::Zero();
    for (const Vec3& q : p) c += q;
    c /= double(p.size());
    Mat3 cov = Mat3::Zero();
    for (const Vec3& q : p) cov += (q - c) * (q - c).transpose();
    Eigen::SelfAdjointEigenSolver<Mat3> es(cov);
    const Vec3 ev = es.eigenvalues();  // ascending
    if (!(ev[1] > 1e-6 * ev[2]) || !(ev[2] > 0)) return false;  // collinear or a single point
    centre = c;
    normal = es.eigenvectors().col(0).normalized();
    return true;
  };
  if (!fit(points)) return false;
  std::vector<double> res(points.size());
  for (size_t i = 0; i < points.size(); ++i) res[i] = std::abs(normal.dot(points[i] - centre));
  std::vector<double> sorted = res;
  std::nth_element(sorted.begin(), sorted.begin() + long(sorted.size() / 2), sorted.end());
  const double sigma = std::max(1.4826 * sorted[sorted.size() / 2], min_sigma);
  std::vector<Vec3> kept;
  for (size_t i = 0; i < points.size(); ++i)
    if (res[i] <= 2.5 * sigma) kept.push_back(points[i]);
  if (!fit(kept)) return false;
  double s2 = 0;
  for (const Vec3& q : kept) s2 += std::pow(normal.dot(q - centre), 2);
  inliers = int(kept.size());
  rms = std::sqrt(s2 / double(kept.size()));
  return true;
}

Status stereo_pair(const StereoView& a, const StereoView& b, const TriMesh& head, const StereoOptions& o,
                   StereoResult& out, int index_a, int index_b) {
  StereoPairReport rep;
  rep.a = index_a;
  rep.b = index_b;
  auto refuse = [&](const std::string& why) {
    rep.refusal = why;
    out.pairs.push_back(rep);
    return Status::error(ErrorCode::InvalidInput, "stereo " + a.name + " + " + b.name + ": " + why);
  };
  for (const StereoView* v : {&a, &b}) {
    if (!v->image || v->image->empty()) return refuse(v->name + " has no image");
    if (v->image->width != v->camera.width || v->image->height != v->camera.height)
      return refuse(v->name + " is " + std::to_string(v->image->width) + "x" + std::to_string(v->image->height) +
                    ", its camera " + std::to_string(v->camera.width) + "x" + std::to_string(v->camera.height));
    if (std::min(v->image->width, v->image->height) < 32)
      return refuse(v->name + " is too small for stereo (" + std::to_string(v->image->width) + "x" +
                    std::to_string(v->image->height) + ", at least 32 pixels a side)");
  }
  // The region to search in a: its landmarks' hull, grown; none given: the whole photo.
  std::vector<Vec2> hull;
  if (a.region.size() >= 3) {
    hull = convex_hull(a.region);
    Vec2 c = Vec2::Zero();
    for (const Vec2& p : hull) c += p;
    c /= double(std::max<size_t>(1, hull.size()));
    for (Vec2& p : hull) p = c + o.region_grow * (p - c);
  } else {
    hull = {Vec2(0, 0), Vec2(a.camera.width, 0), Vec2(a.camera.width, a.camera.height), Vec2(0, a.camera.height)};
    hull = convex_hull(hull);
  }
  // The head's vertices both photos see (facing both, inside a's region and b's frame).
  std::vector<Vec3> vn(head.positions.size(), Vec3::Zero());
  for (const Tri& t : head.triangles) {
    const Vec3 n = (head.positions[size_t(t[1])] - head.positions[size_t(t[0])])
                       .cross(head.positions[size_t(t[2])] - head.positions[size_t(t[0])]);
    for (int v : t) vn[size_t(v)] += n;
  }
  const Vec3 Ca = a.camera.center(), Cb = b.camera.center();
  std::vector<Vec3> roi;
  for (size_t v = 0; v < head.positions.size(); ++v) {
    const Vec3& X = head.positions[v];
    if (vn[v].dot(Ca - X) <= 0 || vn[v].dot(Cb - X) <= 0) continue;
    Vec2 ua, ub;
    if (!a.camera.project(X, ua) || !b.camera.project(X, ub)) continue;
    if (!inside_convex(hull, ua) || ub.x() < 0 || ub.y() < 0 || ub.x() > b.camera.width || ub.y() > b.camera.height)
      continue;
    roi.push_back(X);
  }
  if (roi.size() < 10) return refuse("no overlap: the two photos share no part of the head's region");
  Vec3 roi_centre = Vec3::Zero();
  for (const Vec3& X : roi) roi_centre += X;
  rep.angle_deg = view_angle_deg(a.camera, b.camera, roi_centre / double(roi.size()));
  RectifiedCameras rc;
  Status s = rectified_cameras(a.camera, b.camera, roi, o.max_size, o.disparity.radius + 2, rc);
  if (!s) return refuse(s.message);
  rep.width = rc.a.width;
  rep.height = rc.a.height;
  if (std::min({rc.a.width, rc.b.width, rc.a.height}) < 4 * o.disparity.radius + 4)
    return refuse("the shared region is too small in the photos (" + std::to_string(rc.a.width) + "x" +
                  std::to_string(rc.a.height) + " rectified pixels)");
  ImageF ra, rb;
  std::vector<std::uint8_t> va, vb;
  s = resample_rectified(*a.image, a.camera, rc.a, ra, &va);
  if (s) s = resample_rectified(*b.image, b.camera, rc.b, rb, &vb);
  if (!s) return refuse(s.message);
  // Search mask: rectified pixels of a that come from inside its region.
  std::vector<std::uint8_t> mask(va.size(), 0);
  for (int y = 0; y < rc.a.height; ++y)
    for (int x = 0; x < rc.a.width; ++x) {
      const size_t i = size_t(y) * size_t(rc.a.width) + size_t(x);
      if (!va[i]) continue;
      Vec2 uv;
      const Vec3 dir((x + 0.5 - rc.a.cx) / rc.a.fx, (y + 0.5 - rc.a.cy) / rc.a.fy, 1.0);
      if (a.camera.project(Ca + rc.a.R.transpose() * dir, uv) && inside_convex(hull, uv)) mask[i] = 1;
    }
  // Disparity range from the head's depth range (+- margin) in the rectified frame.
  double z0 = std::numeric_limits<double>::infinity(), z1 = 0;
  for (const Vec3& X : roi) {
    const double z = (rc.a.R * (X - Ca)).z();
    z0 = std::min(z0, z);
    z1 = std::max(z1, z);
  }
  z0 = std::max(z0 - o.depth_margin, 0.05 * z0);
  z1 += o.depth_margin;
  const double f = rc.a.fx, off = rc.a.cx - rc.b.cx;
  rep.d_min = int(std::floor(f * rc.baseline / z1 + off)) - 1;
  rep.d_max = int(std::ceil(f * rc.baseline / z0 + off)) + 1;
  s = compute_disparity(ra, rb, mask, rep.d_min, rep.d_max, o.disparity, rep.disparity);
  if (!s) return refuse(s.message);
  // 3-D points, then a robust plane per cell.
  const int W = rc.a.width, H = rc.a.height, P = std::max(2, o.patch_px);
  const int first = int(out.patches.size()), pair_index = int(out.pairs.size());
  for (int cy = 0; cy + P <= H; cy += P)
    for (int cx = 0; cx + P <= W; cx += P) {
      std::vector<Vec3> pts;
      for (int y = cy; y < cy + P; ++y)
        for (int x = cx; x < cx + P; ++x) {
          const float d = rep.disparity.at(x, y);
          Vec3 X;
          if (!std::isnan(d) && triangulate_rectified(rc, x, y, d, X)) pts.push_back(X);
        }
      rep.points += int(pts.size());
      if (double(pts.size()) < o.min_patch_fill * P * P) continue;
      // The depth step of 0.1 px of disparity at this depth: below it, scatter is quantization.
      const double Z = (rc.a.R * (pts[pts.size() / 2] - Ca)).z();
      StereoPatch patch;
      if (!fit_plane_robust(pts, 0.1 * Z * Z / (f * rc.baseline), patch.centre, patch.normal, patch.points, patch.rms))
        continue;
      if (patch.rms > o.max_patch_rms || patch.points < o.min_patch_fill * P * P) continue;
      const Vec3 view = (Ca - patch.centre).normalized();
      if (patch.normal.dot(view) < 0) patch.normal = -patch.normal;
      if (patch.normal.dot(view) < std::cos(o.max_patch_slant_deg * kPi / 180)) continue;
      patch.pair = pair_index;
      out.patches.push_back(patch);
    }
  rep.patches = int(out.patches.size()) - first;
  if (rep.patches == 0) rep.refusal = "no surface patch (too little texture or agreement between the photos)";
  out.pairs.push_back(rep);
  if (rep.patches == 0) return Status::error(ErrorCode::NotConverged, "stereo " + a.name + " + " + b.name + ": " + rep.refusal);
  return Status::success();
}

Status run_stereo(const std::vector<StereoView>& views, const TriMesh& head, const StereoOptions& o,
                  StereoResult& out) {
  out = {};
  if (!(o.min_angle_deg >= 0) || !(o.max_angle_deg >= o.min_angle_deg) || o.max_pairs_per_photo < 1 ||
      o.max_size < 16 || o.patch_px < 2 || !(o.max_patch_rms > 0))
    return Status::error(ErrorCode::InvalidInput, "stereo: an option is out of range");
  if (head.positions.empty()) return Status::error(ErrorCode::InvalidInput, "stereo: empty head mesh");
  Vec3 centre = Vec3::Zero();
  for (const Vec3& p : head.positions) centre += p;
  centre /= double(head.positions.size());
  struct Candidate {
    int a, b;
    double angle;
  };
  std::vector<Candidate> cand;
  for (size_t i = 0; i < views.size(); ++i)
    for (size_t j = i + 1; j < views.size(); ++j) {
      if (!views[i].image || !views[j].image) continue;
      const double ang = view_angle_deg(views[i].camera, views[j].camera, centre);
      if (ang >= o.min_angle_deg && ang <= o.max_angle_deg) cand.push_back({int(i), int(j), ang});
    }
  const double mid = 0.5 * (o.min_angle_deg + o.max_angle_deg);
  std::stable_sort(cand.begin(), cand.end(),
                   [&](const Candidate& p, const Candidate& q) { return std::abs(p.angle - mid) < std::abs(q.angle - mid); });
  std::vector<int> uses(views.size(), 0);
  for (const Candidate& c : cand) {
    if (uses[size_t(c.a)] >= o.max_pairs_per_photo || uses[size_t(c.b)] >= o.max_pairs_per_photo) continue;
    ++uses[size_t(c.a)];
    ++uses[size_t(c.b)];
    stereo_pair(views[size_t(c.a)], views[size_t(c.b)], head, o, out, c.a, c.b);  // a refusal stays in its report
    out.pairs.back().angle_deg = c.angle;  // at the head's centre, as the pair was chosen
  }
  return Status::success();
}

}  // namespace lk
