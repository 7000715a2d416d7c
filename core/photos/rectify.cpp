#include "photos/rectify.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace lk {

Status rectifying_rotation(const Camera& a, const Camera& b, Mat3& R) {
  const Vec3 base = b.center() - a.center();
  if (!(base.norm() > 1e-12)) return Status::error(ErrorCode::InvalidInput, "rectify: the two cameras share one centre");
  const Vec3 x = base.normalized();
  const Vec3 look = (a.R.row(2).transpose() + b.R.row(2).transpose());
  Vec3 y = look.cross(x);
  if (!(y.norm() > 1e-6 * look.norm()) || !(look.norm() > 1e-12))
    return Status::error(ErrorCode::InvalidInput, "rectify: the baseline lies along the look direction");
  y.normalize();
  const Vec3 z = x.cross(y);
  R.row(0) = x.transpose();
  R.row(1) = y.transpose();
  R.row(2) = z.transpose();
  return Status::success();
}

Status rectified_cameras(const Camera& a, const Camera& b, const std::vector<Vec3>& roi, int max_size, int margin_px,
                         RectifiedCameras& out) {
  out = {};
  if (roi.empty()) return Status::error(ErrorCode::InvalidInput, "rectify: no region of interest");
  if (max_size < 16 || margin_px < 0) return Status::error(ErrorCode::InvalidInput, "rectify: size out of range");
  Mat3 R;
  Status s = rectifying_rotation(a, b, R);
  if (!s) return s;
  const Vec3 ca = a.center(), cb = b.center();
  // Normalized image coordinates (focal 1) of the roi in both rectified views.
  double xa0 = std::numeric_limits<double>::infinity(), xa1 = -xa0, xb0 = xa0, xb1 = -xa0, y0 = xa0, y1 = -xa0;
  for (const Vec3& X : roi) {
    const Vec3 pa = R * (X - ca), pb = R * (X - cb);
    if (!(pa.z() > 1e-9) || !(pb.z() > 1e-9))
      return Status::error(ErrorCode::InvalidInput, "rectify: the region lies behind a camera");
    xa0 = std::min(xa0, pa.x() / pa.z());
    xa1 = std::max(xa1, pa.x() / pa.z());
    xb0 = std::min(xb0, pb.x() / pb.z());
    xb1 = std::max(xb1, pb.x() / pb.z());
    y0 = std::min({y0, pa.y() / pa.z(), pb.y() / pb.z()});
    y1 = std::max({y1, pa.y() / pa.z(), pb.y() / pb.z()});
  }
  const double extent = std::max({xa1 - xa0, xb1 - xb0, y1 - y0});
  // Never finer than the photos (mean of both focals), at most max_size on the larger side.
  double f = 0.5 * (0.5 * (a.fx + a.fy) + 0.5 * (b.fx + b.fy));
  if (extent * f > max_size - 2 * margin_px) f = (max_size - 2 * margin_px) / std::max(extent, 1e-12);
  RectifiedCameras& o = out;
  for (Camera* c : {&o.a, &o.b}) {
    c->R = R;
    c->fx = c->fy = f;
    c->k1 = c->k2 = 0;
    c->cy = margin_px - f * y0;
    c->height = int(std::ceil(f * (y1 - y0))) + 2 * margin_px;
  }
  o.a.cx = margin_px - f * xa0;
  o.b.cx = margin_px - f * xb0;
  o.a.width = int(std::ceil(f * (xa1 - xa0))) + 2 * margin_px;
  o.b.width = int(std::ceil(f * (xb1 - xb0))) + 2 * margin_px;
  o.a.t = -R * ca;
  o.b.t = -R * cb;
  o.baseline = (cb - ca).norm();
  return Status::success();
}

ImageF gray_levels(const Image& photo) {
  ImageF g = ImageF::make(photo.width, photo.height, 1);
  for (int y = 0; y < photo.height; ++y)
    for (int x = 0; x < photo.width; ++x) {
      const std::uint8_t* p = photo.at(x, y);
      const float v = photo.channels >= 3 ? 0.299f * p[0] + 0.587f * p[1] + 0.114f * p[2] : float(p[0]);
      *g.at(x, y) = v / 255.f;
    }
  return g;
}

namespace {

// k x k box average (k >= 1); the result's pixel i covers the source's [k i, k i + k).
ImageF box_down(const ImageF& in, int k) {
  if (k <= 1) return in;
  const int w = std::max(1, in.width / k), h = std::max(1, in.height / k);
  ImageF out = ImageF::make(w, h, 1);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      double s = 0;
      int n = 0;
      for (int j = y * k; j < std::min(in.height, y * k + k); ++j)
        for (int i = x * k; i < std::min(in.width, x * k + k); ++i) {
          s += *in.at(i, j);
          ++n;
        }
      *out.at(x, y) = float(s / std::max(1, n));
    }
  return out;
}

}  // namespace

Status resample_rectified(const Image& photo, const Camera& original, const Camera& rect, ImageF& out,
                          std::vector<std::uint8_t>* valid) {
  if (photo.empty() || photo.width != original.width || photo.height != original.height)
    return Status::error(ErrorCode::InvalidInput, "rectify: the photo is " + std::to_string(photo.width) + "x" +
                                                      std::to_string(photo.height) + ", its camera " +
                                                      std::to_string(original.width) + "x" +
                                                      std::to_string(original.height));
  if (rect.width <= 0 || rect.height <= 0) return Status::error(ErrorCode::InvalidInput, "rectify: empty frame");
  const double scale = 0.5 * (original.fx + original.fy) / rect.fx;  // photo pixels per rectified pixel
  const int k = std::max(1, int(std::floor(scale)));
  const ImageF small = box_down(gray_levels(photo), k);
  out = ImageF::make(rect.width, rect.height, 1);
  if (valid) valid->assign(size_t(rect.width) * size_t(rect.height), 0);
  const Vec3 C = rect.center();
  for (int y = 0; y < rect.height; ++y)
    for (int x = 0; x < rect.width; ++x) {
      const Vec3 dir_cam((x + 0.5 - rect.cx) / rect.fx, (y + 0.5 - rect.cy) / rect.fy, 1.0);
      Vec2 uv;
      if (!original.project(C + rect.R.transpose() * dir_cam, uv)) continue;
      // Continuous coordinates in the box-averaged image, pixel centres at integers.
      const double sx = uv.x() / k - 0.5, sy = uv.y() / k - 0.5;
      if (!(sx >= 0 && sy >= 0 && sx <= small.width - 1 && sy <= small.height - 1)) continue;
      const int x0 = std::min(int(sx), small.width - 2 < 0 ? 0 : small.width - 2);
      const int y0 = std::min(int(sy), small.height - 2 < 0 ? 0 : small.height - 2);
      const int x1 = std::min(x0 + 1, small.width - 1), y1 = std::min(y0 + 1, small.height - 1);
      const double fx = sx - x0, fy = sy - y0;
      const double v = (1 - fy) * ((1 - fx) * *small.at(x0, y0) + fx * *small.at(x1, y0)) +
                       fy * ((1 - fx) * *small.at(x0, y1) + fx * *small.at(x1, y1));
      *out.at(x, y) = float(v);
      if (valid) (*valid)[size_t(y) * size_t(rect.width) + size_t(x)] = 1;
    }
  return Status::success();
}

}  // namespace lk
