#include "photos/synthetic_outlines.h"

#include "texture/synthetic_photo.h"

#include <cstdlib>

namespace lk {

Status synthetic_mask(const TriMesh& person, const Camera& camera, Image& mask) {
  return render_synthetic_photo(
      person, camera, [](const Vec3&, const Vec3&) { return Vec3(1, 1, 1); }, Vec3(0, 0, 0), mask);
}

namespace {

// Each pixel takes the other value where a pixel of it lies within r (a disk).
std::vector<std::uint8_t> grow(const std::vector<std::uint8_t>& m, int w, int h, int r) {
  const std::uint8_t from = r > 0 ? 1 : 0;
  const int a = std::abs(r);
  std::vector<std::uint8_t> out = m;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      if (m[size_t(y) * size_t(w) + size_t(x)] != from) continue;
      bool edge = false;  // only pixels next to the other value spread
      if (x > 0 && m[size_t(y) * size_t(w) + size_t(x - 1)] != from) edge = true;
      if (x + 1 < w && m[size_t(y) * size_t(w) + size_t(x + 1)] != from) edge = true;
      if (y > 0 && m[size_t(y - 1) * size_t(w) + size_t(x)] != from) edge = true;
      if (y + 1 < h && m[size_t(y + 1) * size_t(w) + size_t(x)] != from) edge = true;
      if (!edge) continue;
      for (int dy = -a; dy <= a; ++dy)
        for (int dx = -a; dx <= a; ++dx)
          if (dx * dx + dy * dy <= a * a && x + dx >= 0 && y + dy >= 0 && x + dx < w && y + dy < h)
            out[size_t(y + dy) * size_t(w) + size_t(x + dx)] = from;
    }
  return out;
}

}  // namespace

Status synthetic_outlines(const TriMesh& person, const std::vector<Camera>& cameras, const OutlineOptions& options,
                          std::vector<PhotoOutline>& out, int grow_px) {
  out.assign(cameras.size(), PhotoOutline{});
  for (size_t c = 0; c < cameras.size(); ++c) {
    Image image;
    Status s = synthetic_mask(person, cameras[c], image);
    if (!s) return s;
    std::vector<std::uint8_t> mask = mask_from_image(image);
    if (grow_px != 0) mask = grow(mask, image.width, image.height, grow_px);
    s = extract_outline(mask, image.width, image.height, cameras[c].width, cameras[c].height, options, out[c]);
    if (!s) return s;
  }
  return Status::success();
}

}  // namespace lk
