// Alignment on the face (core/align/face_refine.h): the generic head's own
// surface, moved by a known similarity, with a "beret" shell over the crown
// and a "beard" blob under the chin, starting from an alignment turned,
// shifted and stretched the way silhouettes of a hat and a beard mislead
// it, must come most of the way back; the knee of a residual curve; bad
// input is refused.
#include "align/face_refine.h"
#include "mesh/geometry.h"
#include "mesh/midpoint_split.h"
#include "raycast/bvh.h"
#include "test_data.h"
#include "test_scan.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <map>
#include <random>

using namespace lk;

namespace {

const double kPi = 3.14159265358979323846;

// Area-uniform samples of the generic head's triangles (pockets included:
// they lie behind the skin the face is matched to).
std::vector<Vec3> head_samples(const TriMesh& m, int count, std::mt19937& rng) {
  std::vector<double> cumulative;
  double total = 0;
  for (int f = 0; f < m.num_triangles(); ++f) {
    total += 0.5 * face_normal_area(m, f).norm();
    cumulative.push_back(total);
  }
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<Vec3> out;
  while (static_cast<int>(out.size()) < count) {
    const int f = std::min(m.num_triangles() - 1, static_cast<int>(std::lower_bound(cumulative.begin(), cumulative.end(),
                                                                                      u(rng) * total) - cumulative.begin()));
    double a = u(rng), b = u(rng);
    if (a + b > 1) a = 1 - a, b = 1 - b;
    const Tri& t = m.triangles[f];
    out.push_back(m.positions[t[0]] + a * (m.positions[t[1]] - m.positions[t[0]]) +
                  b * (m.positions[t[2]] - m.positions[t[0]]));
  }
  return out;
}

// Points on an ellipsoid's surface (centre c, radii r) whose unit-sphere
// direction passes keep(direction).
template <class Keep>
void ellipsoid(const Vec3& c, const Vec3& r, int count, Keep keep, std::mt19937& rng, std::vector<Vec3>& out) {
  std::normal_distribution<double> g(0, 1);
  int added = 0;
  while (added < count) {
    const Vec3 d = Vec3(g(rng), g(rng), g(rng)).normalized();
    if (!keep(d)) continue;
    out.push_back(c + r.cwiseProduct(d));
    ++added;
  }
}

double angle_deg(const Mat3& a, const Mat3& b) {
  const Eigen::AngleAxisd aa(Mat3(a * b.transpose()));
  return std::abs(aa.angle()) * 180 / kPi;
}

// The generic head's own surface with a "beret" and a "beard", moved by a
// known similarity, and a start turned, shifted and stretched the way
// silhouettes of a hat and a beard mislead the alignment.
struct HatAndBeard {
  std::vector<Vec3> cloud;
  double diag = 0;
  Mat3 R_true = Mat3::Identity();
  double s_true = 1;
  Vec3 t_true = Vec3::Zero();
  Mat3 start_linear = Mat3::Identity();
  Vec3 start_translation = Vec3::Zero();
};

HatAndBeard hat_and_beard(const TriMesh& m, const HeadAnnotations& ann) {
  HatAndBeard scene;
  std::vector<Vec3>& cloud = scene.cloud;
  std::mt19937 rng(5);
  cloud = head_samples(m, 30000, rng);
  BBox box = bounding_box(m.positions);
  Vec3 chin = Vec3::Zero();
  const std::vector<int>& chin_ids = ann.regions.at("chin");
  for (int v : chin_ids) chin += m.positions[v];
  chin /= static_cast<double>(chin_ids.size());
  const double width = box.max.x() - box.min.x();
  // A beret: a flat, wide shell over the crown, tilted to one side.
  ellipsoid(Vec3(0.02, box.max.y() - 0.01, 0.0), Vec3(0.75 * width, 0.05, 0.6 * width), 12000,
            [](const Vec3& d) { return d.y() > -0.3; }, rng, cloud);
  // A long beard: a blob from the chin down, in front of the neck.
  ellipsoid(chin + Vec3(0, -0.08, 0.0), Vec3(0.06, 0.08, 0.05), 12000, [](const Vec3&) { return true; }, rng, cloud);
  // The truth: a similarity into the scan's frame.
  scene.R_true = Mat3(Eigen::AngleAxisd(0.15, Vec3(0.3, 1, 0.1).normalized()));
  scene.s_true = 1.08;
  scene.t_true = Vec3(0.03, -0.02, 0.05);
  for (Vec3& p : cloud) p = scene.s_true * scene.R_true * p + scene.t_true;
  scene.diag = bounding_box(cloud).diagonal();

  // The start: turned 9 deg down and 6 deg aside, 12 mm off, stretched
  // 15 % wide and 10 % shallow (what Gutenberg's beret and beard did).
  const Mat3 turn = Mat3(Eigen::AngleAxisd(9 * kPi / 180, Vec3::UnitX())) *
                    Mat3(Eigen::AngleAxisd(6 * kPi / 180, Vec3::UnitY()));
  const Mat3 stretch = Vec3(1.15, 1.0, 0.9).asDiagonal();
  scene.start_linear = scene.s_true * scene.R_true * turn * stretch;
  scene.start_translation = scene.t_true + Vec3(0.012, -0.006, 0.004);
  return scene;
}

// The head with the upper face's triangles on its +x side split 1-to-4 at
// their edges' midpoints: the same surface, about four times the vertices
// on one cheek, brow and side of the nose. A midpoint joins every region
// both its ends are in.
GenericHead split_one_side(const GenericHead& g) {
  GenericHead out = g;
  const TriMesh& m = g.mesh;
  std::vector<char> upper(m.num_vertices(), 0);
  for (int v : upper_face_vertices(m, g.annotations)) upper[v] = 1;
  const Vec3 side = g.annotations.up.normalized().cross(g.annotations.look.normalized());
  std::map<std::string, std::vector<char>> in;
  for (const auto& [name, ids] : g.annotations.regions) {
    std::vector<char>& mask = in[name];
    mask.assign(m.num_vertices(), 0);
    for (int v : ids) mask[v] = 1;
  }
  std::map<std::pair<int, int>, int> mids;
  auto midpoint = [&](int a, int b) {
    const std::pair<int, int> key(std::min(a, b), std::max(a, b));
    if (const auto it = mids.find(key); it != mids.end()) return it->second;
    const int id = static_cast<int>(out.mesh.positions.size());
    out.mesh.positions.push_back(0.5 * (m.positions[a] + m.positions[b]));
    for (auto& [name, mask] : in)
      if (mask[a] && mask[b]) out.annotations.regions[name].push_back(id);
    mids[key] = id;
    return id;
  };
  out.mesh.triangles.clear();
  out.mesh.normals.clear();
  for (const Tri& t : m.triangles) {
    const Vec3 centroid = (m.positions[t[0]] + m.positions[t[1]] + m.positions[t[2]]) / 3.0;
    if (!(upper[t[0]] && upper[t[1]] && upper[t[2]]) || side.dot(centroid) <= 0) {
      out.mesh.triangles.push_back(t);
      continue;
    }
    const int ab = midpoint(t[0], t[1]), bc = midpoint(t[1], t[2]), ca = midpoint(t[2], t[0]);
    out.mesh.triangles.push_back({t[0], ab, ca});
    out.mesh.triangles.push_back({ab, t[1], bc});
    out.mesh.triangles.push_back({ca, bc, t[2]});
    out.mesh.triangles.push_back({ab, bc, ca});
  }
  return out;
}

}  // namespace

TEST_CASE("face refinement: a head with a beret and a beard is aligned on its face") {
  const GenericHead& generic = test::generic_head();
  const TriMesh& m = generic.mesh;
  const HeadAnnotations& ann = generic.annotations;
  const HatAndBeard scene = hat_and_beard(m, ann);
  const std::vector<Vec3>& cloud = scene.cloud;
  const double diag = scene.diag;
  const Mat3& R_true = scene.R_true;
  const double s_true = scene.s_true;
  const Vec3& t_true = scene.t_true;
  const Mat3& start_linear = scene.start_linear;
  const Vec3& start_translation = scene.start_translation;

  const std::vector<int> face = upper_face_vertices(m, ann);
  REQUIRE(face.size() > 50);
  auto face_error_mm = [&](const Mat3& A, const Vec3& t) {
    double sum = 0;
    for (int v : face) sum += ((A * m.positions[v] + t) - (s_true * R_true * m.positions[v] + t_true)).norm();
    return 1000 * sum / face.size();
  };
  const double start_error = face_error_mm(start_linear, start_translation);
  INFO("start: face " << start_error << " mm off");
  REQUIRE(start_error > 10);  // the start is far enough to need the refinement

  FaceRefineResult r;
  REQUIRE(refine_alignment_on_face(m, ann, cloud, {}, start_linear, start_translation, diag, FaceRefineOptions{}, r).ok());
  const Eigen::JacobiSVD<Mat3> svd(r.linear, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Mat3 R = svd.matrixU() * svd.matrixV().transpose();
  const double scale = svd.singularValues().mean();
  const double error = face_error_mm(r.linear, r.translation);
  INFO("after: face " << error << " mm off, turned " << angle_deg(R, R_true) << " deg, scale " << scale << " (truth "
                      << s_true << "), " << r.kept_fraction << " of the face pulled, score " << r.score);
  // The knee trims hard and stops short of the truth (face_refine.h): the
  // face must come most of the way, turned and scaled nearer the truth
  // than the start, and the result must be a similarity.
  const Eigen::JacobiSVD<Mat3> start_svd(start_linear, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Mat3 start_R = start_svd.matrixU() * start_svd.matrixV().transpose();
  CHECK(error < 0.4 * start_error);
  CHECK(angle_deg(R, R_true) < 0.5 * angle_deg(start_R, R_true));
  CHECK(std::abs(scale / s_true - 1) < 0.035);  // even samples: 1.0474 against 1.08, the face 6.3 mm off (vertices: 8.8 mm)
  CHECK(svd.singularValues().maxCoeff() / svd.singularValues().minCoeff() < 1.0 + 1e-9);
  CHECK(r.near_fraction > 0.9);
}

TEST_CASE("face refinement: the knee of a residual curve, and bad input is refused") {
  // 80 small residuals, then 20 large ones: the knee is at the last small one.
  std::vector<double> d;
  for (int i = 0; i < 80; ++i) d.push_back(0.001 * i / 80.0);
  for (int i = 0; i < 20; ++i) d.push_back(0.02 + 0.001 * i);
  CHECK(residual_knee(d) == 79);
  CHECK(residual_knee({1.0, 2.0}) == 0);
  CHECK(residual_knee({1.0, 1.0, 1.0}) == 2);

  const GenericHead& generic = test::generic_head();
  FaceRefineResult r;
  std::vector<Vec3> cloud(100, Vec3::Zero());
  for (int i = 0; i < 100; ++i) cloud[i] = Vec3(0.001 * i, 0.002 * (i % 7), 0.003 * (i % 5));
  CHECK(refine_alignment_on_face(generic.mesh, generic.annotations, {}, {}, Mat3::Identity(), Vec3::Zero(), 0.3, {}, r)
            .code == ErrorCode::Empty);
  CHECK(refine_alignment_on_face(generic.mesh, generic.annotations, cloud, {}, Mat3::Identity(), Vec3::Zero(), 0, {}, r)
            .code == ErrorCode::InvalidInput);
  CHECK(refine_alignment_on_face(generic.mesh, generic.annotations, cloud, {{0, 1, 500}}, Mat3::Identity(),
                                 Vec3::Zero(), 0.3, {}, r)
            .code == ErrorCode::InvalidInput);
  cloud[3].x() = std::nan("");
  CHECK(refine_alignment_on_face(generic.mesh, generic.annotations, cloud, {}, Mat3::Identity(), Vec3::Zero(), 0.3, {}, r)
            .code == ErrorCode::InvalidInput);
}

TEST_CASE("upper_face_near_fraction: all of the face on its own surface, none when moved off, the face's share "
          "when a cheek is missing") {
  // fit_head keeps the silhouettes' alignment when this share holds though
  // the face's own match went astray (docs/design/fit_real_scans.md).
  const GenericHead& generic = test::generic_head();
  const TriMesh& m = generic.mesh;
  const HeadAnnotations& ann = generic.annotations;
  const double diag = bounding_box(m.positions).diagonal();
  const Mat3 I = Mat3::Identity();
  double share = -1;
  // On its own triangles (and on points spread over them, the cloud's
  // path): every sample of the face lies on the scan.
  REQUIRE(upper_face_near_fraction(m, ann, m.positions, m.triangles, I, Vec3::Zero(), diag, 0.02, share).ok());
  CHECK(share == 1.0);
  std::mt19937 rng(3);
  REQUIRE(upper_face_near_fraction(m, ann, head_samples(m, 30000, rng), {}, I, Vec3::Zero(), diag, 0.02, share).ok());
  CHECK(share == 1.0);
  // Moved 10 % of the diagonal along the look direction: off the surface.
  REQUIRE(upper_face_near_fraction(m, ann, m.positions, m.triangles, I, 0.1 * diag * ann.look.normalized(), diag,
                                   0.02, share)
              .ok());
  CHECK(share < 0.2);
  // The scan without the triangles of the face's +x half: about half the face.
  const std::vector<int> face = upper_face_vertices(m, ann);
  REQUIRE(face.size() > 50);
  TriMesh half = m;
  half.triangles.clear();
  const Vec3 side = ann.up.normalized().cross(ann.look.normalized());
  for (const Tri& t : m.triangles) {
    bool keep = false;
    for (int v : t) keep = keep || side.dot(m.positions[v]) < 0;
    if (keep) half.triangles.push_back(t);
  }
  REQUIRE(upper_face_near_fraction(m, ann, half.positions, half.triangles, I, Vec3::Zero(), diag, 0.001, share).ok());
  CHECK(share > 0.35);
  CHECK(share < 0.65);
  // Bad input is refused with a message.
  CHECK(upper_face_near_fraction(m, ann, {}, {}, I, Vec3::Zero(), diag, 0.02, share).code == ErrorCode::Empty);
  CHECK(upper_face_near_fraction(m, ann, m.positions, m.triangles, I, Vec3::Zero(), 0, 0.02, share).code ==
        ErrorCode::InvalidInput);
  CHECK(upper_face_near_fraction(m, ann, m.positions, {{0, 1, 1 << 30}}, I, Vec3::Zero(), diag, 0.02, share).code ==
        ErrorCode::InvalidInput);
}

TEST_CASE("face refinement: the match does not depend on how densely the grid covers the face") {
  // Another person's surface (the generic head deformed, so the best
  // similarity is a compromise over the face), from a start 3 deg and 3 mm
  // off: the generic head with four times the vertices on one side of its
  // face (the same surface) must be placed where the head as it is is. A
  // match that weighs every vertex alike pulls towards the crowded side
  // (issue 35: a faired face, whose vertices crowd and thin elsewhere,
  // turned Gutenberg away).
  const GenericHead& generic = test::generic_head();
  const GenericHead split = split_one_side(generic);
  REQUIRE(split.mesh.num_vertices() > generic.mesh.num_vertices() + 100);
  const GenericHead person = test::make_test_head(3);
  std::mt19937 rng(9);
  const std::vector<Vec3> cloud = head_samples(person.mesh, 30000, rng);
  const double diag = bounding_box(cloud).diagonal();
  const Mat3 start = Mat3(Eigen::AngleAxisd(3 * kPi / 180, Vec3(0.2, 1, 0.3).normalized()));
  const Vec3 shift(0.002, -0.002, 0.001);
  FaceRefineOptions o;
  o.polish_iterations = 200;  // each to its minimum, so the minima are compared
  FaceRefineResult a, b;
  REQUIRE(refine_alignment_on_face(generic.mesh, generic.annotations, cloud, {}, start, shift, diag, o, a).ok());
  REQUIRE(refine_alignment_on_face(split.mesh, split.annotations, cloud, {}, start, shift, diag, o, b).ok());
  // Both maps applied to the (unsplit) upper face: how far apart they put it.
  const std::vector<int> face = upper_face_vertices(generic.mesh, generic.annotations);
  double apart = 0;
  for (int v : face) {
    const Vec3& p = generic.mesh.positions[v];
    apart += ((a.linear * p + a.translation) - (b.linear * p + b.translation)).norm();
  }
  apart *= 1000.0 / face.size();
  INFO("the two alignments put the face " << apart << " mm apart");
  CHECK(apart < 0.6);  // vertices weighed alike: 1.04 mm; even samples 0.41 mm (the split flattens the Phong surface)
  // The share of the face near a scan: the same face, the same share.
  const HatAndBeard scene = hat_and_beard(generic.mesh, generic.annotations);
  double share_a = 0, share_b = 0;
  REQUIRE(upper_face_near_fraction(generic.mesh, generic.annotations, scene.cloud, {}, scene.start_linear,
                                   scene.start_translation, scene.diag, 0.02, share_a)
              .ok());
  REQUIRE(upper_face_near_fraction(split.mesh, split.annotations, scene.cloud, {}, scene.start_linear,
                                   scene.start_translation, scene.diag, 0.02, share_b)
              .ok());
  INFO("upper face near the hat-and-beard scan from its start: " << share_a << " and " << share_b);
  CHECK(std::abs(share_a - share_b) < 0.02);
}

TEST_CASE("upper_face_samples: even over the face's area, the same points each time") {
  // Split or not, each half of the face gets a share of the samples close
  // to its share of the area; and the samples are a fixed function of the mesh.
  const GenericHead& generic = test::generic_head();
  const GenericHead split = split_one_side(generic);
  const Vec3 side = generic.annotations.up.normalized().cross(generic.annotations.look.normalized());
  auto plus_share = [&](const std::vector<Vec3>& pts) {
    int plus = 0;
    for (const Vec3& p : pts) plus += side.dot(p) > 0;
    return double(plus) / pts.size();
  };
  const std::vector<Vec3> a = upper_face_samples(generic.mesh, generic.annotations, 1500);
  const std::vector<Vec3> b = upper_face_samples(split.mesh, split.annotations, 1500);
  REQUIRE(a.size() > 1000);
  REQUIRE(b.size() > 1000);
  CHECK(a.size() < 2000);
  CHECK(b.size() < 2000);
  // The face is mirror-symmetric: about half on each side, split or not
  // (its vertices: well over half on the split side).
  std::vector<Vec3> split_vertices;
  for (int v : upper_face_vertices(split.mesh, split.annotations)) split_vertices.push_back(split.mesh.positions[v]);
  INFO("+x share: samples " << plus_share(a) << " (as is), " << plus_share(b) << " (split); vertices (split) "
                             << plus_share(split_vertices));
  CHECK(plus_share(split_vertices) > 0.6);
  CHECK(std::abs(plus_share(a) - 0.5) < 0.05);
  CHECK(std::abs(plus_share(b) - 0.5) < 0.05);
  const std::vector<Vec3> again = upper_face_samples(generic.mesh, generic.annotations, 1500);
  REQUIRE(again.size() == a.size());
  int moved = 0;
  for (size_t i = 0; i < a.size(); ++i) moved += (again[i] - a[i]).norm() != 0.0;
  CHECK(moved == 0);
}

TEST_CASE("face refinement: from a wrong pitch, the candidate with most of the scan near the head is the true pose") {
  // A virtual scan of a synthetic person (in the generic head's frame: the
  // true pose is about the identity) with a beret and a beard, the start
  // turned 75 deg head-down about the face's centre. From there the face's
  // own match ends with its whole face on the scan (beret, beard and skull
  // carry face-like surface) in a wrong pose, as Gutenberg's does from some
  // of his silhouettes' minima (docs/design/align.md); the pitch candidates
  // rated by the share of the scan near the head find the true pose. (On
  // this scan the match alone comes back from up to 60 deg.)
  const GenericHead& generic = test::generic_head();
  const TriMesh& m = generic.mesh;
  const HeadAnnotations& ann = generic.annotations;
  const test::TestScan person = test::make_test_scan(3, 40000);
  std::vector<Vec3> cloud = person.scan.positions;
  {
    // Gutenberg's beret and beard (as in hat_and_beard above): surface that
    // the face's match can take for a face.
    std::mt19937 rng(11);
    const TriMesh& h = person.head.mesh;
    const BBox box = bounding_box(h.positions);
    Vec3 chin = Vec3::Zero();
    for (int v : ann.regions.at("chin")) chin += h.positions[v];
    chin /= static_cast<double>(ann.regions.at("chin").size());
    const double width = box.max.x() - box.min.x();
    ellipsoid(Vec3(0.02, box.max.y() - 0.01, 0.0), Vec3(0.75 * width, 0.05, 0.6 * width), 12000,
              [](const Vec3& d) { return d.y() > -0.3; }, rng, cloud);
    ellipsoid(chin + Vec3(0, -0.08, 0.0), Vec3(0.06, 0.08, 0.05), 12000, [](const Vec3&) { return true; }, rng, cloud);
  }
  const double diag = bounding_box(cloud).diagonal();
  MeshBvh head_bvh;
  auto whole = [&](const Mat3& A, const Vec3& t) {
    TriMesh moved = m;
    for (Vec3& p : moved.positions) p = A * p + t;
    REQUIRE(build_bvh(moved, head_bvh).ok());
    int near = 0;
    for (size_t i = 0; i < cloud.size(); i += 4) near += closest_point(head_bvh, cloud[i]).distance <= 0.02 * diag;
    return double(near) / ((cloud.size() + 3) / 4);
  };
  const std::vector<Vec3> face = upper_face_samples(m, ann, 800);
  Vec3 centre = Vec3::Zero();
  for (const Vec3& g : face) centre += g;
  centre /= static_cast<double>(face.size());
  const Vec3 side = ann.up.normalized().cross(ann.look.normalized());
  const Mat3 turn(Eigen::AngleAxisd(75 * kPi / 180, side));
  const Mat3 start_linear = turn;
  const Vec3 start_translation = centre - turn * centre;

  // The truth: the face's match from the true pose.
  FaceRefineResult truth, alone, chosen;
  REQUIRE(refine_alignment_on_face(m, ann, cloud, {}, Mat3::Identity(), Vec3::Zero(), diag, {}, truth).ok());
  REQUIRE(refine_alignment_on_face(m, ann, cloud, {}, start_linear, start_translation, diag, {}, alone).ok());
  REQUIRE(refine_alignment_on_face(m, ann, cloud, {}, start_linear, start_translation, diag, {}, chosen, whole).ok());
  auto apart_mm = [&](const FaceRefineResult& a, const Mat3& A, const Vec3& t) {
    double sum = 0;
    for (const Vec3& g : face) sum += ((a.linear * g + a.translation) - (A * g + t)).norm();
    return 1000 * sum / face.size();
  };
  auto turned_deg = [&](const FaceRefineResult& a) {
    const Eigen::JacobiSVD<Mat3> x(a.linear, Eigen::ComputeFullU | Eigen::ComputeFullV), y(truth.linear, Eigen::ComputeFullU | Eigen::ComputeFullV);
    return angle_deg(x.matrixU() * x.matrixV().transpose(), y.matrixU() * y.matrixV().transpose());
  };
  const double truth_from_identity = apart_mm(truth, Mat3::Identity(), Vec3::Zero());
  const double alone_off = apart_mm(alone, truth.linear, truth.translation);
  const double chosen_off = apart_mm(chosen, truth.linear, truth.translation);
  INFO("truth: face " << truth_from_identity << " mm from the identity, " << 100 * whole(truth.linear, truth.translation)
                      << " % of the scan near; from the wrong pitch alone: " << alone_off << " mm, " << turned_deg(alone)
                      << " deg off, " << 100 * whole(alone.linear, alone.translation) << " % near, face "
                      << alone.near_fraction << "; with the candidates: " << chosen_off << " mm, " << turned_deg(chosen)
                      << " deg off, candidate " << chosen.chosen);
  std::string candidates;
  for (const FaceRefineCandidate& c : chosen.candidates)
    candidates += std::to_string(c.pitch_deg) + " deg: " + std::to_string(100 * c.measure) + " % near, face " +
                  std::to_string(c.near_fraction) + "; ";
  INFO("candidates " << candidates);
  CHECK(truth_from_identity < 5);  // the person differs from the generic head, the pose does not
  // Without the candidates the face's match stays in a wrong pose with the
  // face on the scan: its own score cannot tell.
  CHECK(alone.near_fraction > 0.9);
  CHECK(alone_off > 15);
  CHECK(turned_deg(alone) > 10);
  // With them: the true pose, and the candidate that turned the start back.
  REQUIRE(chosen.chosen >= 0);
  REQUIRE(chosen.candidates.size() == FaceRefineOptions{}.candidate_pitches_deg.size());
  CHECK(chosen_off < 1.5);
  CHECK(turned_deg(chosen) < 1.0);
  CHECK(chosen.candidates[chosen.chosen].pitch_deg < 0);
  for (const FaceRefineCandidate& c : chosen.candidates) CHECK(c.measure <= chosen.candidates[chosen.chosen].measure);
}

// FaceRefineOptions::screen_iterations (successive halving): a screened
// start that goes on gives the bits it gives run through (every start kept:
// the same result, iterations and all); with a few kept, the hat-and-beard
// scene's winner is among them (the same result in fewer iterations); bad
// screening options are refused.
TEST_CASE("face refinement: screening the starts keeps the winner's result to the bit") {
  const GenericHead& generic = test::generic_head();
  const HatAndBeard scene = hat_and_beard(generic.mesh, generic.annotations);
  auto refine = [&](int screen_iterations, int screen_keep, FaceRefineResult& r) {
    FaceRefineOptions o;
    o.screen_iterations = screen_iterations;
    o.screen_keep = screen_keep;
    return refine_alignment_on_face(generic.mesh, generic.annotations, scene.cloud, {}, scene.start_linear,
                                    scene.start_translation, scene.diag, o, r);
  };
  FaceRefineResult full, all_kept, few_kept;
  REQUIRE(refine(0, 3, full).ok());
  REQUIRE(refine(10, 27, all_kept).ok());
  REQUIRE(refine(10, 3, few_kept).ok());
  CHECK(all_kept.linear == full.linear);
  CHECK(all_kept.translation == full.translation);
  CHECK(all_kept.score == full.score);
  CHECK(all_kept.iterations == full.iterations);
  INFO("iterations: full " << full.iterations << ", 3 kept " << few_kept.iterations);
  CHECK(few_kept.linear == full.linear);
  CHECK(few_kept.translation == full.translation);
  CHECK(few_kept.iterations < full.iterations);
  FaceRefineResult bad;
  CHECK(refine(-1, 3, bad).code == ErrorCode::InvalidInput);
  CHECK(refine(10, 0, bad).code == ErrorCode::InvalidInput);
}

TEST_CASE("face refinement: a fine mesh's vertices place the face where its triangles do, a coarse mesh's do not") {
  // FitHeadOptions::face_match_vertices_edge: on a mesh whose edges are
  // short against the head, the face is matched to the vertices (a nearest
  // point costs far less there than a nearest triangle), which must put it
  // where the triangles put it; on a coarse mesh the vertices lie too far
  // apart for that, which is why the triangles are the default.
  const GenericHead& generic = test::generic_head();
  const GenericHead person = test::make_test_head(3);
  PointCloud coarse;
  coarse.positions = person.mesh.positions;
  coarse.faces = person.mesh.triangles;
  const PointCloud fine = split_at_midpoints(split_at_midpoints(split_at_midpoints(split_at_midpoints(coarse))));
  const double diag = bounding_box(coarse.positions).diagonal();
  INFO("mean edge: coarse " << mean_edge_length(coarse.positions, coarse.faces) / diag << ", fine "
                            << mean_edge_length(fine.positions, fine.faces) / diag << " of the diagonal");
  const Mat3 start = Mat3(Eigen::AngleAxisd(3 * kPi / 180, Vec3(0.2, 1, 0.3).normalized()));
  const Vec3 shift(0.002, -0.002, 0.001);
  FaceRefineOptions o;
  o.polish_iterations = 200;
  const std::vector<int> face = upper_face_vertices(generic.mesh, generic.annotations);
  auto apart_mm = [&](const FaceRefineResult& a, const FaceRefineResult& b) {
    double sum = 0;
    for (int v : face) {
      const Vec3& p = generic.mesh.positions[v];
      sum += ((a.linear * p + a.translation) - (b.linear * p + b.translation)).norm();
    }
    return 1000 * sum / face.size();
  };
  FaceRefineResult on_triangles, on_fine_vertices, on_coarse_vertices;
  const TriMesh& g = generic.mesh;
  const HeadAnnotations& ann = generic.annotations;
  REQUIRE(refine_alignment_on_face(g, ann, fine.positions, fine.faces, start, shift, diag, o, on_triangles).ok());
  REQUIRE(refine_alignment_on_face(g, ann, fine.positions, {}, start, shift, diag, o, on_fine_vertices).ok());
  REQUIRE(refine_alignment_on_face(g, ann, coarse.positions, {}, start, shift, diag, o, on_coarse_vertices).ok());
  const double fine_apart = apart_mm(on_triangles, on_fine_vertices);
  const double coarse_apart = apart_mm(on_triangles, on_coarse_vertices);
  INFO("the face placed by the fine mesh's vertices " << fine_apart << " mm from where its triangles place it, by the "
                                                       "coarse mesh's vertices " << coarse_apart << " mm");
  CHECK(fine_apart < 0.3);               // 0.20 mm at a mean edge of 0.0019 of the diagonal
  CHECK(coarse_apart > 2 * fine_apart);  // 0.72 mm at 0.030
}

TEST_CASE("face refinement: the symmetric turn's start keeps a face the starts reach") {
  // The beret-and-beard scene from a start turned 40 deg about the face's
  // vertical axis: the starts reach the face here (the trap of a turned
  // bust is tested on the real Gutenberg, tests/pipeline/test_real_scans),
  // and the symmetric turn's start must not move it off.
  const GenericHead& generic = test::generic_head();
  const TriMesh& m = generic.mesh;
  const HeadAnnotations& ann = generic.annotations;
  const HatAndBeard scene = hat_and_beard(m, ann);
  const std::vector<Vec3> face = upper_face_samples(m, ann, 800);
  Vec3 c = Vec3::Zero();
  for (const Vec3& p : face) c += scene.s_true * scene.R_true * p + scene.t_true;
  c /= double(face.size());
  const Mat3 turn = Mat3(Eigen::AngleAxisd(40 * kPi / 180, scene.R_true * ann.up.normalized()));
  const Mat3 start_linear = turn * scene.s_true * scene.R_true;
  const Vec3 start_translation = turn * (scene.t_true - c) + c;
  auto off_deg = [&](const FaceRefineResult& r) {
    const Eigen::JacobiSVD<Mat3> svd(r.linear, Eigen::ComputeFullU | Eigen::ComputeFullV);
    return angle_deg(svd.matrixU() * svd.matrixV().transpose(), scene.R_true);
  };
  FaceRefineOptions without;
  without.symmetry_yaw_start = false;
  FaceRefineResult a, b;
  REQUIRE(refine_alignment_on_face(m, ann, scene.cloud, {}, start_linear, start_translation, scene.diag, without, a)
              .ok());
  FaceRefineOptions with;
  with.symmetry_yaw_start = true;
  REQUIRE(refine_alignment_on_face(m, ann, scene.cloud, {}, start_linear, start_translation, scene.diag, with, b)
              .ok());
  INFO("without the symmetric start " << off_deg(a) << " deg off (score " << a.score << "), with it " << off_deg(b)
                                      << " deg (score " << b.score << ", symmetric at " << b.symmetry_yaw_deg << " deg, "
                                      << b.symmetry_score << ")");
  CHECK(off_deg(b) < 6);
  CHECK(b.score <= a.score);
  CHECK(b.symmetry_score > 0.9);  // measured at the first search's winner
  CHECK(std::fabs(b.symmetry_yaw_deg) <= 5);
}
