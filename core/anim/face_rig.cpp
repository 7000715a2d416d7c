#include "anim/face_rig.h"

#include "anim/muscle.h"
#include "anim/profile.h"
#include "components/components.h"
#include "head/generic_head.h"
#include "mesh/geometry.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

namespace lk {

namespace {

using Region = std::vector<int>;

const Region* find_region(const HeadAnnotations& a, const char* name) {
  auto it = a.regions.find(name);
  return it == a.regions.end() || it->second.empty() ? nullptr : &it->second;
}

const CreaseCurve* find_crease(const HeadAnnotations& a, const char* name) {
  for (const CreaseCurve& c : a.creases)
    if (c.name == name) return &c;
  return nullptr;
}

double nearest_distance(const Vec3& p, const std::vector<Vec3>& P, const Region& set) {
  double best = 1e300;
  for (int v : set) best = std::min(best, (P[static_cast<std::size_t>(v)] - p).squaredNorm());
  return std::sqrt(best);
}

// The vertex of `set` minimizing score (set must not be empty).
template <class F>
int argmin(const Region& set, F score) {
  int best = set.front();
  double value = 1e300;
  for (int v : set) {
    const double s = score(v);
    if (s < value) {
      value = s;
      best = v;
    }
  }
  return best;
}

void push(SparseField& f, int v, const Vec3& d) {
  if (d.squaredNorm() == 0) return;
  f.index.push_back(v);
  f.delta.push_back(d);
}

Status lid_rig(const std::vector<Vec3>& P, const EyeSocket& socket, const Vec3& center, double radius, const LidSeal& seal,
               EyeLids& lids, std::vector<int>& upper, std::vector<int>& lower, const char* name) {
  const std::vector<int>& rim = socket.rim;
  if (rim.size() < 6 || rim.size() % 2)
    return Status::error(ErrorCode::InvalidInput, std::string("the ") + name + " rim needs an even loop of >= 6 vertices");
  const std::size_t m = rim.size() / 2;
  upper.assign(rim.begin(), rim.begin() + static_cast<std::ptrdiff_t>(m));
  lower.assign(rim.rbegin(), rim.rbegin() + static_cast<std::ptrdiff_t>(m));
  auto mean_y = [&](const std::vector<int>& s) {
    double y = 0;
    for (int v : s) y += P[static_cast<std::size_t>(v)].y();
    return y / static_cast<double>(s.size());
  };
  if (mean_y(upper) < mean_y(lower)) std::swap(upper, lower);
  if ((P[upper[0]] - P[lower[0]]).norm() > (P[upper[0]] - P[lower.back()]).norm()) std::reverse(lower.begin(), lower.end());
  lids.center = center;
  lids.radius = radius;
  auto angle = [&](const Vec3& p) { return std::atan2(p.y() - center.y(), p.z() - center.z()); };
  std::vector<std::pair<double, double>> gap, meet, upper_a, lower_a, rim_r, upper_r, lower_r, upper_dx, lower_dx;
  for (std::size_t k = 0; k < m; ++k) {
    const Vec3 &u = P[upper[k]], &l = P[lower[k]];
    const double x = 0.5 * (u.x() + l.x()), g = angle(u) - angle(l);
    if (!(g > -1e-9)) return Status::error(ErrorCode::InvalidInput, std::string("the ") + name + " rim's upper lid is below its lower lid");
    // The corner columns (the canthi) close by 0.6 of theirs: fully closed,
    // the skin just past them pinched and folded at level 2 (9 pairs per
    // blink on the generic head; 0 at 0.6 and 0.65, 4 at 0.75).
    const bool corner = k == 0 || k + 1 == m;
    gap.emplace_back(x, corner ? kCanthusGapShare * g : g);
    meet.emplace_back(x, angle(l) + 0.25 * g);
    upper_a.emplace_back(x, angle(u));
    lower_a.emplace_back(x, angle(l));
    rim_r.emplace_back(x, 0.5 * ((u - center).norm() + (l - center).norm()));
    upper_r.emplace_back(x, (u - center).norm());
    lower_r.emplace_back(x, (l - center).norm());
    upper_dx.emplace_back(x, x - u.x());
    lower_dx.emplace_back(x, x - l.x());
  }
  const Profile gap_at = Profile::through(gap), meet_at = Profile::through(meet), rim_at = Profile::through(rim_r);
  const Profile upper_at = Profile::through(upper_r), lower_at = Profile::through(lower_r);
  const Profile upper_a_at = Profile::through(upper_a), lower_a_at = Profile::through(lower_a);
  const Profile upper_dx_at = Profile::through(upper_dx), lower_dx_at = Profile::through(lower_dx);
  // The corner columns close too (the generic head's canthi are rim edges
  // 1.7 mm long, which stayed open, eyeball showing); past them the lids'
  // weight fades to 0 within a tenth of the eye's radius, so the skin
  // beyond the canthi stays.
  const double x0 = gap_at.x.front(), x1 = gap_at.x.back(), fade = 0.1 * radius;
  // A rim vertex takes its own column's values and lid, not those at its x:
  // a fitted rim's columns need not be upright (Gutenberg's middle upper
  // vertex sits 5 mm along x from its lower one, where the interpolated gap
  // turned it past the lower rim).
  std::map<int, std::pair<double, bool>> on_rim;  // rim vertex -> (its column's x, upper)
  std::map<int, double> rim_seal;                  // rim vertex -> its factor on the closing turn
  for (std::size_t k = 0; k < m; ++k) {
    const double x = 0.5 * (P[upper[k]].x() + P[lower[k]].x());
    on_rim[upper[k]] = {x, true};
    on_rim[lower[k]] = {x, false};
    const bool corner = k == 0 || k + 1 == m;
    const double f = corner ? seal.corner / kCanthusGapShare * (seal.rim / kLidClosedShare) : seal.rim / kLidClosedShare;
    rim_seal[upper[k]] = rim_seal[lower[k]] = std::max(1.0, f);
  }
  for (std::size_t v = 0; v < P.size(); ++v) {
    const Vec3 d = P[v] - center;
    const auto rim_v = on_rim.find(static_cast<int>(v));
    const bool is_rim = rim_v != on_rim.end();
    const double x = is_rim ? rim_v->second.first : P[v].x();
    if (!is_rim && (x <= x0 - fade || x >= x1 + fade)) continue;
    const double past = is_rim ? 0.0 : std::max(x0 - x, x - x1);  // beyond the corner columns (> 0)
    const double rr = rim_at(x), r = d.norm();
    const bool up = is_rim ? rim_v->second.second : angle(P[v]) > meet_at(x);
    const double own = up ? upper_at(x) : lower_at(x);  // this lid's rim radius
    // In front of the eye's centre: 1 within the lid's own rim radius (the
    // rim turns whole where the two rims sit at different radii; the mean
    // of both left a scan's upper rim at 0.9997), fading over 0.8 eye radii
    // outside it. Behind it, fading from that at the centre's plane to 0 at
    // the back: the pocket (inside the rim's radius) from 1, so the pocket
    // next to the margin turns with it rather than being left behind
    // (docs/design/muscles.md, "The lids closed at level 2"), and the skin
    // outside it from its front weight, not cut from that to 0 at the plane
    // (a jump where a fitted head's skin about the eye crosses it; session 50).
    const double front = r <= 1.01 * own ? 1.0 : 1.0 - smoothstep01((r - 1.01 * own) / (0.8 * radius));
    double w = front;
    if (d.z() <= 0)
      w = (r <= 1.01 * std::max(rr, own) ? 1.0 : front) *
          (1.0 - smoothstep01(std::atan2(-d.z(), std::hypot(d.x(), d.y())) / 1.5707963267948966));
    if (is_rim) w = 1.0;
    if (past > 0) w *= 1.0 - smoothstep01(past / fade);
    const double g = gap_at(x);
    if (w <= 0 || g <= 0) continue;
    lids.index.push_back(static_cast<int>(v));
    lids.weight.push_back(w);
    lids.gap.push_back(g);
    lids.upper.push_back(up ? 1 : 0);
    // A fitted head's margin and socket ring may sit inside the opening's
    // angle (Fran's rings 2-3 degrees in front of their rims): turned by
    // their rim's angle they pass the other lid's ring. Inside the opening
    // a vertex turns by its share of it (face_pose.cpp).
    const double a_up = upper_a_at(x), a_low = lower_a_at(x), a = angle(P[v]);
    double t = up ? 1.0 : 0.0;
    if (!is_rim && a_up - a_low > 1e-9 && d.z() > 0) t = std::clamp((a - a_low) / (a_up - a_low), 0.0, 1.0);
    lids.opening.push_back(t);
    lids.seal.push_back(is_rim ? rim_seal[static_cast<int>(v)] : 1.0);
    // Closed, both rims meet at the column's mean radius and x (a scan's
    // lids need not sit at one distance from the eyeball's centre, nor
    // their columns at one x).
    lids.radial.push_back(rr - own);
    lids.shift.push_back(up ? upper_dx_at(x) : lower_dx_at(x));
  }
  return Status::success();
}

}  // namespace

Vec3 jaw_hinge(const std::vector<Vec3>& P, const HeadAnnotations& ann) {
  const BBox box = bounding_box(P);
  Vec3 top_back(0, -1e9, 1e9);
  bool any = false;
  for (const char* name : {"lower_lip", "chin", "jaw"})
    if (const Region* r = find_region(ann, name))
      for (int v : *r)
        if (v >= 0 && v < static_cast<int>(P.size())) {
          top_back.y() = std::max(top_back.y(), P[static_cast<std::size_t>(v)].y());
          top_back.z() = std::min(top_back.z(), P[static_cast<std::size_t>(v)].z());
          any = true;
        }
  if (!any) return box.valid() ? box.center() : Vec3::Zero();
  return Vec3(0.5 * (box.min.x() + box.max.x()), top_back.y(), top_back.z());
}

Status make_face_rig(const TriMesh& control, const GenericHead& generic, FaceRig& out, const LidSeal& seal) {
  const HeadAnnotations& ann = generic.annotations;
  const std::vector<Vec3>& P = control.positions;
  const int n = static_cast<int>(P.size());
  if (n != generic.mesh.num_vertices() || n == 0)
    return Status::error(ErrorCode::InvalidInput, "the head does not have the generic head's vertices (" +
                                                       std::to_string(n) + " vs " +
                                                       std::to_string(generic.mesh.num_vertices()) + ")");
  for (const Vec3& p : P)
    if (!p.allFinite()) return Status::error(ErrorCode::InvalidInput, "the head has a non-finite vertex");
  for (const char* name : {"upper_lip", "lower_lip", "lips", "chin", "jaw", "brow", "nose", "cheeks"})
    if (!find_region(ann, name)) return Status::error(ErrorCode::InvalidInput, std::string("no '") + name + "' region");
  const CreaseCurve* up_line = find_crease(ann, "upper_lip_line");
  const CreaseCurve* low_line = find_crease(ann, "lower_lip_line");
  if (!up_line || !low_line || up_line->vertices.size() < 3 || up_line->vertices.size() != low_line->vertices.size())
    return Status::error(ErrorCode::InvalidInput, "the lip lines (upper_lip_line, lower_lip_line) are missing or unequal");
  for (const auto& [name, r] : ann.regions)
    for (int v : r)
      if (v < 0 || v >= n) return Status::error(ErrorCode::InvalidInput, "region '" + name + "' has an index out of range");

  FaceRig rig;
  rig.rest = P;
  rig.field.assign(kChannelCount, SparseField{});
  FaceLandmarks& lm = rig.landmarks;

  // Eyes where the parts go; their distance sets the rig's scale (its
  // distances are the generic head's, 64 mm between the eyes, times u).
  GenericHead fitted{control, ann};
  ComponentPlacement place;
  if (Status s = place_components(fitted, generic, place); !s.ok()) return s;
  rig.eye_distance = (place.eye_center[0] - place.eye_center[1]).norm();
  if (!(rig.eye_distance > 0)) return Status::error(ErrorCode::InvalidInput, "the eyes coincide");
  const double iod = rig.eye_distance;
  const double u = iod / 0.064;
  rig.scale = u;

  // Mouth: corners at the lip lines' ends, columns between them by x.
  const std::vector<int>& ul = up_line->vertices;
  const std::vector<int>& ll = low_line->vertices;
  const int ca = ul.front(), cb = ul.back();
  lm.mouth_corner = P[ca].x() > P[cb].x() ? std::array<int, 2>{ca, cb} : std::array<int, 2>{cb, ca};
  lm.upper_lip_line.assign(ul.begin() + 1, ul.end() - 1);
  lm.lower_lip_line.assign(ll.begin() + 1, ll.end() - 1);
  auto by_x = [&](int a, int b) { return P[a].x() < P[b].x(); };
  std::sort(lm.upper_lip_line.begin(), lm.upper_lip_line.end(), by_x);
  std::sort(lm.lower_lip_line.begin(), lm.lower_lip_line.end(), by_x);
  const Vec3 cl = P[lm.mouth_corner[0]], cr = P[lm.mouth_corner[1]];
  const double mid_x = 0.5 * (cl.x() + cr.x());
  rig.mouth_width = (cl - cr).norm();
  if (!(rig.mouth_width > 1e-4)) return Status::error(ErrorCode::InvalidInput, "the mouth corners coincide");
  const double mw = rig.mouth_width;
  auto nearest_column = [&](double x) {
    std::size_t best = 0;
    for (std::size_t k = 1; k < lm.upper_lip_line.size(); ++k)
      if (std::abs(P[lm.upper_lip_line[k]].x() - x) < std::abs(P[lm.upper_lip_line[best]].x() - x)) best = k;
    return best;
  };
  const std::size_t mid = nearest_column(mid_x);
  lm.upper_lip_mid = lm.upper_lip_line[mid];
  lm.lower_lip_mid = lm.lower_lip_line[mid];
  for (int s = 0; s < 2; ++s) {
    const double x = mid_x + 0.5 * (P[lm.mouth_corner[s]].x() - mid_x);
    lm.upper_lip_side[s] = lm.upper_lip_line[nearest_column(x)];
    lm.lower_lip_side[s] = lm.lower_lip_line[nearest_column(x)];
  }
  rig.mouth_center = 0.5 * (P[lm.upper_lip_mid] + P[lm.lower_lip_mid]);
  const Vec3 mc = rig.mouth_center;
  std::vector<std::pair<double, double>> line_pts;
  for (int v : ul) line_pts.emplace_back(P[v].x(), P[v].y());
  const Profile lip_y = Profile::through(line_pts);  // the mouth line's height at x

  const Region& upper_lip = *find_region(ann, "upper_lip");
  const Region& lower_lip = *find_region(ann, "lower_lip");
  const Region& chin = *find_region(ann, "chin");
  // The region's extreme y near the midline, in front (within `depth` of the mouth's front).
  auto front_mid = [&](const Region& r, double sign, double depth) {
    Region near;
    for (int v : r)
      if (std::abs(P[v].x() - mid_x) < 0.25 * mw && P[v].z() > mc.z() - depth) near.push_back(v);
    if (near.empty()) near = r;
    return argmin(near, [&](int v) { return -sign * P[v].y(); });
  };
  lm.upper_lip_top = front_mid(upper_lip, +1, 0.003 * u);
  lm.lower_lip_bottom = front_mid(lower_lip, -1, 0.003 * u);
  // The chin's lowest point still facing forward: its region wraps under
  // the jaw, so the lowest of all would be under the chin.
  lm.chin = front_mid(chin, -1, 0.025 * u);

  const EyeSocket* sockets[2] = {&ann.eye_left, &ann.eye_right};
  for (int s = 0; s < 2; ++s)
    if (Status st = lid_rig(P, *sockets[s], place.eye_center[s], place.eye_radius[s], seal, rig.lids[static_cast<std::size_t>(s)],
                            lm.upper_lid[static_cast<std::size_t>(s)], lm.lower_lid[static_cast<std::size_t>(s)],
                            s == 0 ? "left eye" : "right eye");
        !st.ok())
      return st;
  std::vector<double> lid_weight(static_cast<std::size_t>(n), 0.0);
  for (const EyeLids& l : rig.lids)
    for (std::size_t i = 0; i < l.index.size(); ++i) lid_weight[static_cast<std::size_t>(l.index[i])] = l.weight[i];

  // Brows, nose wings, cheeks per side.
  const Region& brow = *find_region(ann, "brow");
  const Region& nose = *find_region(ann, "nose");
  const Region& cheeks = *find_region(ann, "cheeks");
  for (int s = 0; s < 2; ++s) {
    const Vec3 E = place.eye_center[s];
    const double R = place.eye_radius[s], sg = s == 0 ? 1.0 : -1.0;
    Region side_brow;
    double brow_y = 0;
    for (int v : brow)
      if (sg * (P[v].x() - mid_x) > 0 && P[v].z() > E.z()) {
        side_brow.push_back(v);
        brow_y += P[v].y();
      }
    if (side_brow.empty()) return Status::error(ErrorCode::InvalidInput, "the brow region misses a side");
    brow_y /= static_cast<double>(side_brow.size());
    auto near_xy = [&](double x, double y) {
      return [&P, x, y](int v) { return (P[v].x() - x) * (P[v].x() - x) + (P[v].y() - y) * (P[v].y() - y); };
    };
    lm.brow_inner[s] = argmin(side_brow, near_xy(E.x() - sg * 0.8 * R, brow_y));
    lm.brow_outer[s] = argmin(side_brow, near_xy(E.x() + sg * 1.0 * R, brow_y));
    lm.nose_wing[s] = argmin(nose, [&](int v) { return -sg * P[v].x() + (P[v].y() > E.y() - R ? 1.0 : 0.0); });
    lm.cheek[s] = argmin(cheeks, [&](int v) {
      return (P[v].x() - E.x()) * (P[v].x() - E.x()) + (P[v].y() - (E.y() - 2.6 * R)) * (P[v].y() - (E.y() - 2.6 * R)) +
             (P[v].z() < E.z() ? 1.0 : 0.0);
    });
  }

  // Which lip a vertex belongs to: 1 above the mouth line (or on the upper
  // lip), 0 below it (or on the lower lip, chin), a 6 mm blend between.
  const std::vector<char> on_upper = vertex_mask(upper_lip, n), on_lower = vertex_mask(lower_lip, n),
                          on_chin = vertex_mask(chin, n), on_lips = vertex_mask(*find_region(ann, "lips"), n);
  auto upper_side = [&](int v) {
    if (on_upper[v]) return 1.0;
    if (on_lower[v] || on_chin[v]) return 0.0;
    return smoothstep01((P[v].y() - lip_y(P[v].x())) / (0.006 * u) + 0.5);
  };
  auto lower_side = [&](int v) {
    if (on_lower[v] || on_chin[v]) return 1.0;
    if (on_upper[v]) return 0.0;
    return 1.0 - smoothstep01((P[v].y() - lip_y(P[v].x())) / (0.006 * u) + 0.5);
  };
  auto everywhere = [](int) { return 1.0; };
  // The skin muscles leave the lids to the lid rig, and fade in over 1.5
  // eye radii from the nearest rim vertex: past the canthi the lids' weight
  // falls to 0 within a tenth of a radius, and a fitted head's next control
  // vertices sit 5-6 mm out, so a brow lifting them by 1-2 mm sheared the
  // skin against the still corner, which folded into the lid margin at
  // level 2 (James' browOuterUp and surprise; docs/design/muscles.md).
  // 1.5 had the fewest lid pairs over the five real scans' fits of 1, 1.5, 2.
  std::vector<double> near_rim(static_cast<std::size_t>(n), 1.0);
  for (int s = 0; s < 2; ++s)
    for (int v = 0; v < n; ++v) {
      const double d = nearest_distance(P[static_cast<std::size_t>(v)], P, sockets[s]->rim);
      near_rim[static_cast<std::size_t>(v)] =
          std::min(near_rim[static_cast<std::size_t>(v)], smoothstep01(d / (1.5 * place.eye_radius[s])));
    }
  auto off_lids = [&](int v) { return (1.0 - lid_weight[static_cast<std::size_t>(v)]) * near_rim[static_cast<std::size_t>(v)]; };

  // Linear muscles (Waters), per side.
  for (int s = 0; s < 2; ++s) {
    const double sg = s == 0 ? 1.0 : -1.0;
    const Vec3 Bi = P[lm.brow_inner[s]], Bo = P[lm.brow_outer[s]], M = P[lm.mouth_corner[s]];
    const Vec3 up_side = P[lm.upper_lip_side[s]], low_side = P[lm.lower_lip_side[s]];
    auto add = [&](int channel, const Vec3& ins, const Vec3& att, double cone, double reach, double pull,
                   const std::function<double(int)>& mask) {
      rig.field[static_cast<std::size_t>(channel + s)] = linear_muscle_field(LinearMuscle{att, ins, cone, reach, pull}, P, mask);
    };
    add(kFrontalisInnerL, Bi, Bi + Vec3(0, 0.45 * iod, -0.012 * u), 0.9, 0.025 * u, 0.18, off_lids);
    add(kFrontalisOuterL, Bo, Bo + Vec3(0, 0.45 * iod, -0.012 * u), 0.9, 0.025 * u, 0.18, off_lids);
    add(kCorrugatorL, Bi + 0.3 * (Bo - Bi), Vec3(mid_x + sg * 0.1 * iod, Bi.y() - 1.5 * place.eye_radius[s], Bi.z() - 0.01 * u),
        0.5, 0.012 * u, 0.25, off_lids);
    add(kZygomaticMajorL, M, M + Vec3(sg * 0.35 * iod, 0.75 * iod, -0.35 * iod), 0.45, 0.015 * u, 0.2, everywhere);
    const Vec3 zm = up_side + Vec3(0, 0.004 * u, 0);
    add(kZygomaticMinorL, zm, zm + Vec3(sg * 0.3 * iod, 0.6 * iod, -0.25 * iod), 0.35, 0.012 * u, 0.15, upper_side);
    const Vec3 ll_ins = up_side + Vec3(0, 0.004 * u, 0);
    add(kLevatorLabiiL, ll_ins, ll_ins + Vec3(sg * 0.05 * iod, 0.7 * iod, -0.15 * iod), 0.25, 0.012 * u, 0.12, upper_side);
    const Vec3 NW = P[lm.nose_wing[s]];
    add(kLevatorNasiL, NW, NW + Vec3(-sg * 0.05 * iod, 0.55 * iod, -0.1 * iod), 0.4, 0.012 * u, 0.18, upper_side);
    add(kDepressorAnguliL, M, M + Vec3(sg * 0.1 * iod, -0.55 * iod, -0.1 * iod), 0.45, 0.012 * u, 0.2, everywhere);
    const Vec3 dl = low_side + Vec3(0, -0.004 * u, 0);
    add(kDepressorLabiiL, dl, dl + Vec3(sg * 0.05 * iod, -0.5 * iod, -0.1 * iod), 0.35, 0.01 * u, 0.15, lower_side);
    // Mentalis: it lifts the chin's soft tissue, and the lower lip with it;
    // a Waters cone from its origin above the chin cannot reach the lip
    // above its origin, so it is a lift over an ellipse from the chin to the
    // lower lip instead (4 mm up, 2 mm out at its middle).
    {
      const Vec3 mt = 0.5 * (P[lm.lower_lip_bottom] + P[lm.chin]) + Vec3(sg * 0.15 * mw, 0, 0);
      const double a = 0.35 * mw, b = 0.8 * std::abs(P[lm.lower_lip_bottom].y() - P[lm.chin].y());
      SparseField& f = rig.field[static_cast<std::size_t>(kMentalisL + s)];
      for (int v = 0; v < n; ++v) {
        const Vec3 d = P[v] - mt;
        const double rho = std::hypot(d.x() / a, d.y() / b);
        if (rho >= 1 || d.z() < -0.03 * u) continue;
        push(f, v, lower_side(v) * std::cos(1.5707963267948966 * rho) * Vec3(0, 0.004, 0.002) * u);
      }
    }
    add(kBuccinatorL, M, M + Vec3(sg * 0.15 * iod, 0, -0.5 * iod), 0.4, 0.01 * u, 0.12, everywhere);
    add(kRisoriusL, M, M + Vec3(sg * 0.7 * iod, -0.05 * iod, -0.3 * iod), 0.35, 0.01 * u, 0.15, everywhere);

    // Orbicularis oculi: a ring about the eye (from 1.8 to 3.8 eye radii)
    // pulling the skin towards it, by up to 3.5 mm at its middle; the lids
    // and their fading skin inside it are left to the lid rig.
    const Vec3 E = place.eye_center[s];
    const double r_in = 1.8 * place.eye_radius[s], r_out = 3.8 * place.eye_radius[s];
    SparseField& oc = rig.field[static_cast<std::size_t>(kOculiL + s)];
    for (int v = 0; v < n; ++v) {
      const Vec3 d = P[v] - E;
      const double r = std::hypot(d.x(), d.y());
      if (r <= r_in || r >= r_out || d.z() < 0) continue;
      const double t = (r - r_in) / (r_out - r_in);
      push(oc, v, -0.0035 * u * std::sin(3.14159265358979323846 * t) * off_lids(v) * Vec3(d.x() / r, d.y() / r, 0));
    }
  }
  {
    const Vec3 g = 0.5 * (P[lm.brow_inner[0]] + P[lm.brow_inner[1]]);
    rig.field[kProcerus] = linear_muscle_field(LinearMuscle{g + Vec3(0, -0.35 * iod, -0.008 * u), g, 0.5, 0.012 * u, 0.2}, P, off_lids);
  }
  Sphincter oris;
  oris.center = mc;
  oris.a = 0.75 * mw;
  oris.b = 0.5 * mw;
  oris.squeeze = 0.45;
  oris.protrude = 0.008 * u;
  oris.depth = 0.02 * u;
  rig.field[kOrisPucker] = sphincter_field(oris, P, everywhere);

  // Skin actions.
  auto taper = [&](double x) { return std::max(0.0, 1.0 - std::pow((x - mid_x) / (0.5 * mw), 2)); };
  for (int v = 0; v < n; ++v) {
    const Vec3& p = P[v];
    const double below = p.y() - lip_y(p.x());
    if (on_upper[v]) push(rig.field[kRollUpper], v, taper(p.x()) * Vec3(0, -0.5 * below, -0.003 * u));
    if (on_lower[v]) push(rig.field[kRollLower], v, taper(p.x()) * Vec3(0, -0.5 * below, -0.003 * u));
    if (on_upper[v] || on_lower[v])
      for (int s = 0; s < 2; ++s) {
        const double sg = s == 0 ? 1.0 : -1.0;
        const double side = smoothstep01(0.5 + sg * (p.x() - mid_x) / (0.5 * mw));
        push(rig.field[static_cast<std::size_t>(kPressL + s)], v, side * Vec3(0, -0.4 * below, -0.001 * u));
      }
    const Vec3 d = p - mc;
    if (d.z() > -0.02 * u) {
      const double rho = std::hypot(d.x() / mw, d.y() / (0.7 * mw));
      if (rho < 1) push(rig.field[kMouthShift], v, std::cos(1.5707963267948966 * rho) * Vec3(0.006 * u, 0, 0));
      const double rs = std::hypot(d.x() / (0.8 * mw), d.y() / (0.6 * mw));
      if (rs < 1) push(rig.field[kShrugUpper], v, upper_side(v) * std::cos(1.5707963267948966 * rs) * Vec3(0, 0.003, 0.001) * u);
    }
  }
  // Cheeks blown out along their normals: the cheek region's weight,
  // smoothed over the mesh's edges so it fades, none on the lips, lids or
  // ears and the skin next to them (the smoothing reached the ears' roots,
  // whose folds, moved along their normals, crossed at level 2: all of
  // James' 338 pairs were on or against an ear).
  {
    const Region* ears = find_region(ann, "ears");
    const std::vector<char> on_ears = ears ? vertex_mask(*ears, n) : std::vector<char>(static_cast<std::size_t>(n), 0);
    std::vector<double> w(static_cast<std::size_t>(n), 0.0);
    for (int v : cheeks) w[static_cast<std::size_t>(v)] = 1.0;
    std::vector<std::set<int>> ring(static_cast<std::size_t>(n));
    for (const Tri& t : control.triangles)
      for (int k = 0; k < 3; ++k) {
        ring[static_cast<std::size_t>(t[k])].insert(t[(k + 1) % 3]);
        ring[static_cast<std::size_t>(t[k])].insert(t[(k + 2) % 3]);
      }
    for (int it = 0; it < 3; ++it) {
      std::vector<double> next = w;
      for (int v = 0; v < n; ++v) {
        double sum = w[static_cast<std::size_t>(v)];
        for (int nb : ring[static_cast<std::size_t>(v)]) sum += w[static_cast<std::size_t>(nb)];
        next[static_cast<std::size_t>(v)] = sum / static_cast<double>(1 + ring[static_cast<std::size_t>(v)].size());
      }
      w.swap(next);
    }
    // The ears and two rings of skin about them stay.
    std::vector<char> near_ears = on_ears;
    for (int it = 0; it < 2; ++it) {
      std::vector<char> next = near_ears;
      for (int v = 0; v < n; ++v)
        if (near_ears[static_cast<std::size_t>(v)])
          for (int nb : ring[static_cast<std::size_t>(v)]) next[static_cast<std::size_t>(nb)] = 1;
      near_ears.swap(next);
    }
    const std::vector<Vec3> normals = vertex_normals(control);
    for (int v = 0; v < n; ++v)
      if (!on_lips[v] && !near_ears[static_cast<std::size_t>(v)])
        push(rig.field[kCheekPuff], v, 0.006 * u * w[static_cast<std::size_t>(v)] * off_lids(v) * normals[static_cast<std::size_t>(v)]);
  }

  // The jaw: the lower lip, chin and the skin between them whole; the skin around them, the jaw
  // line included, fading over 6 cm from them and over 2 cm below the
  // mouth line (nothing above it, nothing on the upper lip), so the cheeks
  // stretch instead of creasing at a region's edge. The mouth corners stay
  // (both lips hold them): the share grows from 0 there over 40 % of the
  // mouth's width.
  rig.jaw.hinge = jaw_hinge(P, ann);
  Region jaw_core;
  for (const char* name : {"lower_lip", "chin"})
    for (int v : *find_region(ann, name)) jaw_core.push_back(v);
  // ... and the skin between them (below the lower lip, above the chin).
  for (int v = 0; v < n; ++v)
    if (!on_upper[v] && std::abs(P[v].x() - mid_x) < 0.35 * mw && P[v].y() < lip_y(P[v].x()) - 0.002 * u &&
        P[v].y() > P[lm.chin].y() - 0.01 * u && P[v].z() > P[lm.chin].z() - 0.02 * u)
      jaw_core.push_back(v);
  const std::vector<char> on_core = vertex_mask(jaw_core, n);
  const Region corners(lm.mouth_corner.begin(), lm.mouth_corner.end());
  for (int v = 0; v < n; ++v) {
    double w = 0;
    if (on_lips[v] && !on_upper[v] && !on_lower[v]) {
      w = 0.5;  // the mouth bag's seam between the lips: half of each
    } else if (on_core[v] && !on_upper[v]) {
      w = 1;
    } else if (!on_upper[v]) {
      const double band = smoothstep01((lip_y(P[v].x()) - P[v].y()) / (0.02 * u));
      w = band * smoothstep01(1.0 - nearest_distance(P[v], P, jaw_core) / (0.06 * u));
    }
    w *= smoothstep01(nearest_distance(P[v], P, corners) / (0.4 * mw));
    if (w <= 0) continue;
    rig.jaw.index.push_back(v);
    rig.jaw.weight.push_back(w);
  }

  // The lips' contact: each lip with the skin within 1 cm of it on its side.
  for (int v : lm.upper_lip_line) rig.lips.column_x.push_back(P[v].x());
  for (int v = 0; v < n; ++v) {
    if (std::abs(P[v].x() - mid_x) > 0.6 * mw) continue;
    const double above = P[v].y() - lip_y(P[v].x());
    const double wu = on_upper[v] ? 1.0 : (above > 0 && !on_lower[v] ? smoothstep01(1.0 - nearest_distance(P[v], P, upper_lip) / (0.01 * u)) : 0.0);
    const double wl = on_lower[v] ? 1.0 : (above < 0 && !on_upper[v] ? smoothstep01(1.0 - nearest_distance(P[v], P, lower_lip) / (0.01 * u)) : 0.0);
    push(rig.lips.side[0], v, Vec3(0, wu, 0));
    push(rig.lips.side[1], v, Vec3(0, -wl, 0));
  }
  std::vector<char> moves(static_cast<std::size_t>(n), 0);
  for (const SparseField& f : rig.field)
    for (int v : f.index) moves[static_cast<std::size_t>(v)] = 1;
  for (int v : rig.jaw.index) moves[static_cast<std::size_t>(v)] = 1;
  for (const EyeLids& l : rig.lids)
    for (int v : l.index) moves[static_cast<std::size_t>(v)] = 1;
  for (const SparseField& f : rig.lips.side)
    for (int v : f.index) moves[static_cast<std::size_t>(v)] = 1;
  for (int v = 0; v < n; ++v)
    if (moves[static_cast<std::size_t>(v)]) rig.moved.push_back(v);
  out = std::move(rig);
  return Status::success();
}

}  // namespace lk
