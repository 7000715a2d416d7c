#include "photos/synthetic_outlines.h"

#include "texture/synthetic_photo.h"

namespace lk {

Status synthetic_mask(const TriMesh& person, const Camera& camera, Image& mask) {
  return render_synthetic_photo(
      person, camera, [](const Vec3&, const Vec3&) { return Vec3(1, 1, 1); }, Vec3(0, 0, 0), mask);
}

Status synthetic_outlines(const TriMesh& person, const std::vector<Camera>& cameras, const OutlineOptions& options,
                          std::vector<PhotoOutline>& out) {
  out.assign(cameras.size(), PhotoOutline{});
  for (size_t c = 0; c < cameras.size(); ++c) {
    Image mask;
    Status s = synthetic_mask(person, cameras[c], mask);
    if (s) s = outline_from_mask_image(mask, cameras[c].width, cameras[c].height, options, out[c]);
    if (!s) return s;
  }
  return Status::success();
}

}  // namespace lk
