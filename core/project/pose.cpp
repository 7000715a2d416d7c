#include "project/pose.h"

#include "anim/face_rig.h"
#include "mesh/geometry.h"

#include <algorithm>
#include <cmath>

namespace lk {

AnimationRig make_animation_rig(const TriMesh& control, const HeadAnnotations& ann) {
  AnimationRig rig;
  const std::vector<Vec3>& P = control.positions;
  const BBox box = bounding_box(P);
  rig.head_size = (box.max - box.min).norm();
  std::vector<char> taken(P.size(), 0);
  auto region = [&](const char* name) {
    auto it = ann.regions.find(name);
    return it == ann.regions.end() ? std::vector<int>{} : it->second;
  };
  for (const char* name : {"lower_lip", "chin", "jaw"})
    for (int v : region(name)) {
      if (v < 0 || v >= static_cast<int>(P.size()) || taken[v]) continue;
      taken[v] = 1;
      rig.moved.push_back(v);
      rig.rest.push_back(P[v]);
      rig.kind.push_back(AnimationRig::Kind::Jaw);
      rig.weight.push_back(1.0);
    }
  const std::vector<int> brow = region("brow");
  const double falloff = 0.03 * rig.head_size;
  for (size_t v = 0; v < P.size(); ++v) {
    if (taken[v] || brow.empty()) continue;
    double nearest = 1e300;
    for (int b : brow)
      if (b >= 0 && b < static_cast<int>(P.size())) nearest = std::min(nearest, (P[v] - P[b]).norm());
    if (nearest >= falloff) continue;
    const double x = 1.0 - nearest / falloff;  // 1 on the brow, 0 at the falloff radius
    rig.moved.push_back(static_cast<int>(v));
    rig.rest.push_back(P[v]);
    rig.kind.push_back(AnimationRig::Kind::Brow);
    rig.weight.push_back(x * x * (3.0 - 2.0 * x));  // smoothstep
  }
  rig.jaw_pivot = jaw_hinge(P, ann);  // the muscle layer's hinge (anim/face_rig.h)
  return rig;
}

double clamp_pose_amount(double amount) { return std::isfinite(amount) ? std::min(1.0, std::max(0.0, amount)) : 0.0; }
double jaw_angle(double amount) { return 0.14 * amount; }  // ~8 degrees open
double brow_lift(const AnimationRig& rig, double amount) { return 0.02 * rig.head_size * amount; }  // ~7 mm

namespace {

// The rotation about the x axis by angle: the chin swings down.
Mat3 jaw_rotation(double angle) {
  const double c = std::cos(angle), s = std::sin(angle);
  Mat3 R;
  R << 1, 0, 0, 0, c, -s, 0, s, c;
  return R;
}

}  // namespace

std::vector<Vec3> rig_targets(const AnimationRig& rig, double jaw_amount, double brow_amount) {
  const double lift = brow_lift(rig, clamp_pose_amount(brow_amount));
  const double angle = jaw_angle(clamp_pose_amount(jaw_amount));
  const double c = std::cos(angle), sn = std::sin(angle);
  std::vector<Vec3> target(rig.moved.size());
  for (size_t i = 0; i < rig.moved.size(); ++i) {
    const Vec3& p = rig.rest[i];
    if (rig.kind[i] == AnimationRig::Kind::Brow) {
      target[i] = p + Vec3(0, lift * rig.weight[i], 0);
    } else {
      const Vec3 d = p - rig.jaw_pivot;
      target[i] = rig.jaw_pivot + Vec3(d.x(), c * d.y() - sn * d.z(), sn * d.y() + c * d.z());
    }
  }
  return target;
}

Status pose_project(HeadProject& project, double amount, int max_level, UpdateFootprint* footprint) {
  MultiresMesh& mr = project.fit.multires;
  if (mr.num_levels() == 0) return Status::error(ErrorCode::InvalidInput, "no fitted head to animate");
  if (max_level < -1 || max_level > mr.num_levels())
    return Status::error(ErrorCode::InvalidInput, "no level " + std::to_string(max_level));
  amount = clamp_pose_amount(amount);
  const AnimationRig& rig = project.rig;
  const std::vector<Vec3> target = rig_targets(rig, amount, amount);
  const Status st = update_control_vertices(mr, rig.moved, target, footprint, max_level);
  if (st.ok()) project.pose = amount;
  return st;
}

Status rest_pose(HeadProject& project) {
  if (project.pose != 0)
    if (Status st = pose_project(project, 0.0); !st.ok()) return st;
  return ensure_current(project.fit.multires);
}

Mat4 jaw_motion(const HeadProject& project, double amount) {
  const HeadFrame& f = project.frame;
  const Mat3 R = jaw_rotation(jaw_angle(clamp_pose_amount(amount)));
  const Vec3 c = project.rig.jaw_pivot;
  Mat4 m = Mat4::Identity();
  m.topLeftCorner<3, 3>() = f.head_to_scan * R * f.head_to_scan.inverse();
  m.topRightCorner<3, 1>() = f.head_to_scan * (c + R * (f.head_offset - c) - f.head_offset);
  return m;
}

}  // namespace lk
