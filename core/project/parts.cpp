#include "project/parts.h"

#include "teeth/synthetic_smile.h"

#include <cmath>

namespace lk {

Status place_head_parts(const TriMesh& head, const GenericHead& generic, HeadParts& out) {
  GenericHead fitted;
  fitted.mesh.positions = head.positions;
  fitted.mesh.triangles = head.triangles;
  fitted.annotations = generic.annotations;
  out = HeadParts{};
  if (Status st = place_components(fitted, generic, out.placement); !st.ok()) return st;
  out.placed = build_placed_components(out.placement);
  // The lower arch (below the bite plane, at the mouth centre) rides on the jaw.
  split_below(out.placed.teeth, out.placement.mouth_center.y(), out.upper_teeth, out.lower_teeth);
  return Status::success();
}

void split_below(const TriMesh& m, double y, TriMesh& above, TriMesh& below) {
  std::vector<int> map_above(m.positions.size(), -1), map_below(m.positions.size(), -1);
  for (const Tri& t : m.triangles) {
    const double cy = (m.positions[t[0]].y() + m.positions[t[1]].y() + m.positions[t[2]].y()) / 3.0;
    TriMesh& part = cy < y ? below : above;
    std::vector<int>& map = cy < y ? map_below : map_above;
    Tri out;
    for (int k = 0; k < 3; ++k) {
      if (map[t[k]] < 0) {
        map[t[k]] = static_cast<int>(part.positions.size());
        part.positions.push_back(m.positions[t[k]]);
        if (m.uvs.size() == m.positions.size()) part.uvs.push_back(m.uvs[t[k]]);
      }
      out[k] = map[t[k]];
    }
    part.triangles.push_back(out);
  }
}

PolarIris generic_polar_iris() {
  PolarIris iris;
  iris.angles = 96;
  iris.radii = 24;
  iris.rgb.resize(static_cast<size_t>(iris.angles) * iris.radii * 3);
  iris.valid.assign(static_cast<size_t>(iris.angles) * iris.radii, 1);
  for (int a = 0; a < iris.angles; ++a)
    for (int r = 0; r < iris.radii; ++r) {
      const double t = r / double(iris.radii - 1);  // 0 at the pupil, 1 at the limbus
      const double streak = 0.85 + 0.15 * std::sin(a * 1.7) * std::sin(a * 0.37 + r * 0.5);
      const double shade = streak * (1.0 - 0.45 * t * t);
      float* px = iris.at(a, r);
      px[0] = static_cast<float>(0.42 * shade);
      px[1] = static_cast<float>(0.27 * shade);
      px[2] = static_cast<float>(0.14 * shade);
    }
  return iris;
}

Status generic_eyeball_texture(const EyeballTextureOptions& options, Image& texture) {
  return eyeball_texture(generic_polar_iris(), 0.35, options, texture);
}

Status teeth_photo_texture(const Image& photo, const TeethOptions& options, TeethResult& teeth,
                           const TeethCompositeOptions* composite_options, Image* composite) {
  if (Status st = teeth_texture_from_photo(photo, options, teeth); !st.ok()) return st;
  if (Status st = check_smile_closeup(teeth, photo.width, photo.height); !st.ok()) return st;
  if (!composite) return Status::success();
  return teeth_composite_generic(teeth, options, composite_options ? *composite_options : TeethCompositeOptions{},
                                 *composite);
}

Status generic_teeth_texture(const TeethCompositeOptions& composite_options, Image& texture) {
  SyntheticSmileOptions smile;
  smile.upper_dip = 40;
  smile.lower_rise = 34;
  TeethResult teeth;
  return teeth_photo_texture(make_synthetic_smile(smile).image, TeethOptions{}, teeth, &composite_options, &texture);
}

}  // namespace lk
