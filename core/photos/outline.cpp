#include "photos/outline.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <utility>

namespace lk {

std::vector<std::uint8_t> mask_from_image(const Image& image) {
  const size_t n = size_t(std::max(0, image.width)) * size_t(std::max(0, image.height));
  std::vector<std::uint8_t> mask(n, 0);
  const int c = image.channels;
  if (image.empty() || c < 1 || image.pixels.size() < n * size_t(c)) return mask;
  const bool has_alpha = c == 2 || c == 4;
  bool alpha_varies = false;
  if (has_alpha)
    for (size_t i = 0; i < n && !alpha_varies; ++i) alpha_varies = image.pixels[i * size_t(c) + size_t(c - 1)] < 255;
  for (size_t i = 0; i < n; ++i) {
    const std::uint8_t* p = &image.pixels[i * size_t(c)];
    int value;
    if (alpha_varies) value = p[c - 1];
    else if (c >= 3) value = (int(p[0]) + int(p[1]) + int(p[2])) / 3;
    else value = p[0];
    mask[i] = value >= 128 ? 1 : 0;
  }
  return mask;
}

Status mask_from_plain_background(const Image& photo, const PlainBackgroundOptions& o, std::vector<std::uint8_t>& mask) {
  mask.clear();
  if (photo.empty() || photo.channels < 3 || photo.pixels.size() < size_t(photo.width) * size_t(photo.height) * size_t(photo.channels))
    return Status::error(ErrorCode::InvalidInput, "plain background: needs a colour image");
  if (o.frame_px < 1 || 4 * o.frame_px >= std::min(photo.width, photo.height))
    return Status::error(ErrorCode::InvalidInput, "plain background: the image is too small");
  const int w = photo.width, h = photo.height, f = o.frame_px;
  auto in_frame = [&](int x, int y) { return x < f || y < f || x >= w - f || y >= h - f; };
  std::vector<double> ch[3];
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      if (in_frame(x, y))
        for (int k = 0; k < 3; ++k) ch[k].push_back(photo.at(x, y)[k]);
  auto median = [](std::vector<double> v) {
    std::nth_element(v.begin(), v.begin() + long(v.size() / 2), v.end());
    return v[v.size() / 2];
  };
  const Vec3 bg(median(ch[0]), median(ch[1]), median(ch[2]));
  std::vector<double> dist(ch[0].size());
  for (size_t i = 0; i < dist.size(); ++i) dist[i] = (Vec3(ch[0][i], ch[1][i], ch[2][i]) - bg).norm();
  const double spread = median(dist);
  if (spread > o.max_spread)
    return Status::error(ErrorCode::InvalidInput, "the background is not plain (its border varies by " +
                                                      std::to_string(int(std::lround(spread))) +
                                                      " levels): give a mask instead");
  const double threshold = std::max(o.min_distance, o.spread_factor * spread);
  mask.assign(size_t(w) * size_t(h), 0);
  size_t frame_fg = 0, frame_n = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const std::uint8_t* p = photo.at(x, y);
      const bool fg = (Vec3(p[0], p[1], p[2]) - bg).norm() > threshold;
      mask[size_t(y) * size_t(w) + size_t(x)] = fg;
      if (in_frame(x, y)) {
        ++frame_n;
        frame_fg += fg;
      }
    }
  if (double(frame_fg) > o.max_frame_share * double(frame_n))
    return Status::error(ErrorCode::InvalidInput, "the background is not plain (the person covers much of the "
                                                  "image's border): give a mask instead");
  return Status::success();
}

namespace {

std::string size_text(int w, int h) { return std::to_string(w) + "x" + std::to_string(h); }

}  // namespace

Status extract_outline(const std::vector<std::uint8_t>& mask, int width, int height, int expected_width,
                       int expected_height, const OutlineOptions& o, PhotoOutline& out) {
  out = {};
  if (width <= 0 || height <= 0 || mask.size() != size_t(width) * size_t(height))
    return Status::error(ErrorCode::InvalidInput, "mask: empty or unreadable image");
  if (width != expected_width || height != expected_height)
    return Status::error(ErrorCode::InvalidInput, "mask is " + size_text(width, height) + ", its photo is " +
                                                      size_text(expected_width, expected_height));
  if (!(o.spacing_px > 0) || !(o.border_px >= 0) || o.normal_radius_px < 1)
    return Status::error(ErrorCode::InvalidInput, "outline: an option is out of range");
  const auto idx = [width](int x, int y) { return size_t(y) * size_t(width) + size_t(x); };

  // The largest 8-connected foreground component.
  std::vector<int> label(mask.size(), -1);
  std::vector<size_t> stack;
  int best = -1;
  size_t best_size = 0;
  int next_label = 0;
  for (size_t start = 0; start < mask.size(); ++start) {
    if (!mask[start] || label[start] >= 0) continue;
    const int l = next_label++;
    size_t size = 0;
    label[start] = l;
    stack.assign(1, start);
    while (!stack.empty()) {
      const size_t i = stack.back();
      stack.pop_back();
      ++size;
      const int x = int(i % size_t(width)), y = int(i / size_t(width));
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int nx = x + dx, ny = y + dy;
          if (nx < 0 || ny < 0 || nx >= width || ny >= height) continue;
          const size_t j = idx(nx, ny);
          if (mask[j] && label[j] < 0) {
            label[j] = l;
            stack.push_back(j);
          }
        }
    }
    if (size > best_size) {
      best_size = size;
      best = l;
    }
  }
  if (best < 0) return Status::error(ErrorCode::InvalidInput, "mask has no foreground (an empty mask)");

  // Holes filled: background (4-connected, the dual of 8) not reached from the border is foreground.
  std::vector<std::uint8_t> fg(mask.size(), 0), outside(mask.size(), 0);
  for (size_t i = 0; i < mask.size(); ++i) fg[i] = label[i] == best;
  stack.clear();
  for (int x = 0; x < width; ++x)
    for (int y : {0, height - 1}) stack.push_back(idx(x, y));
  for (int y = 0; y < height; ++y)
    for (int x : {0, width - 1}) stack.push_back(idx(x, y));
  while (!stack.empty()) {
    const size_t i = stack.back();
    stack.pop_back();
    if (fg[i] || outside[i]) continue;
    outside[i] = 1;
    const int x = int(i % size_t(width)), y = int(i / size_t(width));
    if (x > 0) stack.push_back(i - 1);
    if (x + 1 < width) stack.push_back(i + 1);
    if (y > 0) stack.push_back(i - size_t(width));
    if (y + 1 < height) stack.push_back(i + size_t(width));
  }
  size_t count = 0;
  for (size_t i = 0; i < fg.size(); ++i) {
    fg[i] = outside[i] ? 0 : 1;
    count += fg[i];
  }
  out.width = width;
  out.height = height;
  out.foreground_share = double(count) / double(fg.size());
  if (out.foreground_share > o.max_foreground_share)
    return Status::error(ErrorCode::InvalidInput, "mask covers " + std::to_string(int(std::lround(100 * out.foreground_share))) +
                                                      " % of the image (all white?): not a head's outline");

  // Edges between a foreground and a background pixel (not the image's
  // border), one kept per spacing-sized cell.
  std::map<std::pair<long, long>, char> taken;
  const int r = o.normal_radius_px;
  auto add = [&](double px, double py, double nx, double ny) {
    if (px < o.border_px || py < o.border_px || px > width - o.border_px || py > height - o.border_px) return;
    const std::pair<long, long> cell(long(std::floor(px / o.spacing_px)), long(std::floor(py / o.spacing_px)));
    if (!taken.emplace(cell, 1).second) return;
    // Outward normal: away from the foreground's first moment around the point.
    Vec2 m = Vec2::Zero();
    for (int dy = -r; dy < r; ++dy)
      for (int dx = -r; dx < r; ++dx) {
        const int x = int(std::floor(px)) + dx, y = int(std::floor(py)) + dy;
        const Vec2 d(x + 0.5 - px, y + 0.5 - py);
        if (d.squaredNorm() > double(r * r)) continue;
        const bool f = x >= 0 && y >= 0 && x < width && y < height && fg[idx(x, y)];
        if (f) m += d;
      }
    OutlinePoint p;
    p.pixel = Vec2(px, py);
    p.normal = m.norm() > 1e-9 ? Vec2(-m / m.norm()) : Vec2(nx, ny);
    out.points.push_back(p);
  };
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      if (!fg[idx(x, y)]) continue;
      if (x + 1 < width && !fg[idx(x + 1, y)]) add(x + 1.0, y + 0.5, 1, 0);
      if (x > 0 && !fg[idx(x - 1, y)]) add(x, y + 0.5, -1, 0);
      if (y + 1 < height && !fg[idx(x, y + 1)]) add(x + 0.5, y + 1.0, 0, 1);
      if (y > 0 && !fg[idx(x, y - 1)]) add(x + 0.5, y, 0, -1);
    }
  if (int(out.points.size()) < o.min_points)
    return Status::error(ErrorCode::InvalidInput, "mask leaves " + std::to_string(out.points.size()) +
                                                      " outline points away from the image border (fewer than " +
                                                      std::to_string(o.min_points) + "): not a head's outline");
  return Status::success();
}

Status outline_from_plain_photo(const Image& image, int photo_width, int photo_height, int max_side,
                                const PlainBackgroundOptions& background, const OutlineOptions& options,
                                PhotoOutline& out) {
  out = {};
  if (image.empty() || photo_width < image.width || photo_height < image.height)
    return Status::error(ErrorCode::InvalidInput, "plain background: the image is larger than its photo");
  const double scale = max_side > 0 ? std::min(1.0, double(max_side) / std::max(image.width, image.height)) : 1.0;
  Image shrunk;
  if (scale < 1.0) {
    shrunk = resized(image, std::max(1, int(std::lround(image.width * scale))),
                     std::max(1, int(std::lround(image.height * scale))));
    if (shrunk.empty()) return Status::error(ErrorCode::Internal, "plain background: the photo could not be shrunk");
  }
  const Image& im = scale < 1.0 ? shrunk : image;
  std::vector<std::uint8_t> mask;
  Status s = mask_from_plain_background(im, background, mask);
  if (s) s = extract_outline(mask, im.width, im.height, im.width, im.height, options, out);
  if (!s) return s;
  // Pixel corners: x in the shrunk image is x * photo_width / its width in the photo.
  const double kx = double(photo_width) / im.width, ky = double(photo_height) / im.height;
  for (OutlinePoint& p : out.points) p.pixel = Vec2(p.pixel.x() * kx, p.pixel.y() * ky);
  out.width = photo_width;
  out.height = photo_height;
  return Status::success();
}

Status outline_from_mask_image(const Image& mask_image, int photo_width, int photo_height, const OutlineOptions& options,
                               PhotoOutline& out) {
  if (mask_image.empty()) return Status::error(ErrorCode::InvalidInput, "mask: empty image");
  return extract_outline(mask_from_image(mask_image), mask_image.width, mask_image.height, photo_width, photo_height,
                         options, out);
}

}  // namespace lk
