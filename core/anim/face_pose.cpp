#include "anim/face_pose.h"

#include "anim/profile.h"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace lk {

namespace {

// Rotations taking +z towards +x (about y) and towards +y (about x).
Mat3 turn_y(double a) {
  Mat3 R;
  R << std::cos(a), 0, std::sin(a), 0, 1, 0, -std::sin(a), 0, std::cos(a);
  return R;
}
Mat3 turn_x(double a) {
  Mat3 R;
  R << 1, 0, 0, 0, std::cos(a), std::sin(a), 0, -std::sin(a), std::cos(a);
  return R;
}

// The shares of the rest gap an eye's upper lid comes down and its lower lid
// comes up (negative: opens), from its lid, lower-lid and pitch channels.
// Together they never exceed kLidClosedShare: the lids meet but do not cross.
void lid_shares(const FaceControls& c, int eye, double& upper, double& lower) {
  const double lid = c[kLidL + eye], low = c[kLowerLidL + eye], pitch = c[kGazePitchL + eye];
  upper = (lid > 0 ? 0.73 * lid : 0.25 * lid) + (pitch < 0 ? -0.3 * pitch : -0.15 * pitch);
  lower = 0.23 * std::max(0.0, lid) + 0.35 * low + (pitch < 0 ? 0.1 * pitch : 0.05 * pitch);
  const double sum = upper + lower;
  if (sum > kLidClosedShare) {
    if (upper > 0 && lower > 0) {
      upper *= kLidClosedShare / sum;
      lower *= kLidClosedShare / sum;
    } else if (upper > 0) {
      upper = kLidClosedShare - lower;
    } else {
      lower = kLidClosedShare - upper;
    }
  }
}

}  // namespace

void FaceControls::clamp() {
  for (int c = 0; c < kChannelCount; ++c) {
    double& v = value[static_cast<std::size_t>(c)];
    v = std::isfinite(v) ? std::clamp(v, channel_signed(c) ? -1.0 : 0.0, 1.0) : 0.0;
  }
}

bool FaceControls::any() const {
  return std::any_of(value.begin(), value.end(), [](double v) { return v != 0; });
}

Mat3 eye_rotation(const FaceControls& controls, int eye) {
  FaceControls c = controls;
  c.clamp();
  return turn_y(c[kGazeYawL + eye] * kGazeAngle) * turn_x(c[kGazePitchL + eye] * kGazeAngle);
}

void jaw_motion(const FaceRig& rig, const FaceControls& controls, Mat3& R, Vec3& t) {
  FaceControls c = controls;
  c.clamp();
  const double open = c[kJawOpen], side = c[kJawSide], forward = c[kJawForward];
  // Opening turns the chin down (a negative turn about x) and glides the
  // jaw forward a little, as the condyles do.
  R = turn_y(0.05 * side) * turn_x(-kJawOpenAngle * open);
  t = rig.scale * Vec3(side * kJawSideShift, 0, open * kJawOpenGlide + forward * kJawForwardShift);
}

std::vector<Vec3> pose_face(const FaceRig& rig, const FaceControls& controls) {
  FaceControls c = controls;
  c.clamp();
  std::vector<Vec3> P = rig.rest;
  for (int ch = 0; ch < kFirstKinematicChannel; ++ch) {
    const double a = c[ch];
    if (a == 0) continue;
    const SparseField& f = rig.field[static_cast<std::size_t>(ch)];
    for (std::size_t i = 0; i < f.index.size(); ++i) P[static_cast<std::size_t>(f.index[i])] += a * f.delta[i];
  }
  if (c[kJawOpen] != 0 || c[kJawSide] != 0 || c[kJawForward] != 0) {
    Mat3 R;
    Vec3 t;
    jaw_motion(rig, c, R, t);
    const Vec3 h = rig.jaw.hinge;
    for (std::size_t i = 0; i < rig.jaw.index.size(); ++i) {
      Vec3& p = P[static_cast<std::size_t>(rig.jaw.index[i])];
      p += rig.jaw.weight[i] * (R * (p - h) + h + t - p);
    }
  }
  for (int eye = 0; eye < 2; ++eye) {
    double upper = 0, lower = 0;
    lid_shares(c, eye, upper, lower);
    const double yaw = 0.2 * c[kGazeYawL + eye] * kGazeAngle;
    if (upper == 0 && lower == 0 && yaw == 0) continue;
    const EyeLids& L = rig.lids[static_cast<std::size_t>(eye)];
    // How far the lids have closed: the rims' radii and x meet as they do.
    const double closed = std::clamp((upper + lower) / kLidClosedShare, 0.0, 1.0);
    for (std::size_t i = 0; i < L.index.size(); ++i) {
      Vec3& p = P[static_cast<std::size_t>(L.index[i])];
      const double w = L.weight[i];
      // The upper lid turns down (negative about x), the lower lid up; while
      // the lids close, a vertex inside the opening by its share of it (the
      // opening's angles map monotonically onto the closed opening's).
      // Opening, each lid turns whole (the two agree where upper + lower = 0).
      const double t = upper + lower > 0 ? L.opening[i] : (L.upper[i] ? 1.0 : 0.0);
      // The rims turn further by their seal as the lids close (1 elsewhere).
      const double f = 1.0 + closed * (L.seal[i] - 1.0);
      const double a = -w * L.gap[i] * f * (t * (upper + lower) - lower);
      const Vec3 d = p - L.center;
      Vec3 e = turn_y(w * yaw) * turn_x(a) * d;
      const double r = d.norm();
      if (closed > 0 && r > 0) {
        e *= (r + w * closed * L.radial[i]) / r;
        e.x() += w * closed * L.shift[i];
      }
      p += e - d;
    }
  }
  // The lips' contact: where a column's lower lip rose above its upper lip,
  // both part by half the overlap (and 0.01 mm) with their skin.
  const FaceLandmarks& lm = rig.landmarks;
  std::vector<std::pair<double, double>> overlap;
  bool any = false;
  for (std::size_t k = 0; k < lm.upper_lip_line.size(); ++k) {
    const double o = P[static_cast<std::size_t>(lm.lower_lip_line[k])].y() - P[static_cast<std::size_t>(lm.upper_lip_line[k])].y();
    overlap.emplace_back(rig.lips.column_x[k], o > 0 ? o + 1e-5 * rig.scale : 0.0);
    any = any || o > 0;
  }
  if (any) {
    for (int corner : lm.mouth_corner) overlap.emplace_back(rig.rest[static_cast<std::size_t>(corner)].x(), 0.0);
    const Profile part = Profile::through(overlap);
    for (const SparseField& side : rig.lips.side)
      for (std::size_t i = 0; i < side.index.size(); ++i) {
        const std::size_t v = static_cast<std::size_t>(side.index[i]);
        P[v] += 0.5 * part(rig.rest[v].x()) * side.delta[i];
      }
  }
  return P;
}

Status pose_multires(MultiresMesh& mesh, const FaceRig& rig, const FaceControls& controls, int max_level,
                     UpdateFootprint* footprint) {
  if (mesh.control.size() != rig.rest.size())
    return Status::error(ErrorCode::InvalidInput, "the head's control mesh is not the rig's");
  // Only the vertices whose position changes: a blink after a smile
  // recomputes the lids' support, not the mouth's.
  const std::vector<Vec3> P = pose_face(rig, controls);
  std::vector<int> moved;
  std::vector<Vec3> target;
  for (int v : rig.moved)
    if (P[static_cast<std::size_t>(v)] != mesh.control[static_cast<std::size_t>(v)]) {
      moved.push_back(v);
      target.push_back(P[static_cast<std::size_t>(v)]);
    }
  return update_control_vertices(mesh, moved, target, footprint, max_level);
}

}  // namespace lk

namespace lk {

std::vector<Vec3> pose_eye(const FaceRig& rig, const std::vector<Vec3>& eye, const FaceControls& controls, int eye_index) {
  const Mat3 R = eye_rotation(controls, eye_index);
  const Vec3 c = rig.lids[static_cast<std::size_t>(eye_index & 1)].center;
  std::vector<Vec3> out(eye.size());
  for (std::size_t i = 0; i < eye.size(); ++i) out[i] = eye[i] + (R * (eye[i] - c) - (eye[i] - c));
  return out;
}

std::vector<Vec3> pose_lower_teeth(const FaceRig& rig, const std::vector<Vec3>& teeth, const FaceControls& controls) {
  Mat3 R;
  Vec3 t;
  jaw_motion(rig, controls, R, t);
  const Vec3 h = rig.jaw.hinge;
  std::vector<Vec3> out(teeth.size());
  for (std::size_t i = 0; i < teeth.size(); ++i) out[i] = teeth[i] + (R * (teeth[i] - h) + t - (teeth[i] - h));
  return out;
}

std::vector<Vec3> pose_tongue(const FaceRig& rig, const std::vector<Vec3>& tongue, const FaceControls& controls) {
  FaceControls c = controls;
  c.clamp();
  std::vector<Vec3> out = tongue;
  if (c[kTongueOut] != 0 && !tongue.empty()) {
    double z0 = 1e300, z1 = -1e300;
    for (const Vec3& p : tongue) {
      z0 = std::min(z0, p.z());
      z1 = std::max(z1, p.z());
    }
    // Far enough that the tip passes the lower lip's front by 12 mm, and
    // lifted so that the tip's underside rides on the lower lip (in the
    // jaw's frame: the jaw's turn below carries both).
    const Vec3 lip = rig.rest[static_cast<std::size_t>(rig.landmarks.lower_lip_mid)];
    const double travel = std::max(0.02 * rig.scale, lip.z() + 0.012 * rig.scale - z1);
    auto share = [&](const Vec3& p) { return z1 > z0 ? (p.z() - z0) / (z1 - z0) : 1.0; };
    double underside = 1e300;
    for (const Vec3& p : tongue)
      if (share(p) >= 0.8) underside = std::min(underside, p.y());
    const double lift = std::max(0.0, lip.y() + 0.0005 * rig.scale - underside);
    for (Vec3& p : out) {
      const double w = share(p);
      p += c[kTongueOut] * w * w * Vec3(0, lift, travel);
    }
  }
  return pose_lower_teeth(rig, out, c);
}

}  // namespace lk
