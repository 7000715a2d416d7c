// Partial scans and odd conventions (align/face_alignment.h through
// fit_head): a frontal face-only capture, the front of a head cropped by
// depth, a head facing +x, and the real Fran (Cyberware face) and James
// (menpo3d face capture) scans when ../shared/data is present.
#include "head/generic_head.h"
#include "io/io.h"
#include "mesh/geometry.h"
#include "pipeline/fit_head.h"
#include "raycast/bvh.h"
#include "smooth_pairs.h"
#include "test_data.h"
#include "test_scan.h"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <fstream>
#include <map>
#include <sstream>

using namespace lk;

namespace {

struct Truth {
  GenericHead generic;
  TruthSurface truth;
  PointCloud whole;    // six stations around the head
  PointCloud frontal;  // one station in front of the face
};

const Truth& truth() {
  static Truth t = [] {
    Truth s;
    s.generic = test::generic_head();
    s.truth = test::make_test_truth(test::make_test_head(4), 1);
    s.whole = test::scan_test_truth(s.truth, 2, 20000);
    ScannerOptions front;
    front.stations = 1;
    front.arc_degrees = 0;
    front.elevations_deg = {0.0};
    s.frontal = test::scan_test_truth(s.truth, 3, 20000, front);
    return s;
  }();
  return t;
}

// The result in the truth's frame (FitHeadOptions::face_frame turns it to
// the aligned face's: the fit is the same, tested in test_fit_head.cpp).
FitHeadOptions quick() {
  FitHeadOptions o;
  o.levels = 1;
  o.face_frame = false;
  return o;
}

// Mean distance (m) from the truth's FACE vertices to a fitted mesh: the
// part a face scan observes must be fitted, whatever the rest does.
double truth_face_to_mesh(const Truth& t, const TriMesh& mesh, double max_depth_behind_tip) {
  double tip = -1e300;
  for (const Vec3& p : t.truth.mesh.positions) tip = std::max(tip, p.z());
  std::vector<Vec3> face;
  for (const Vec3& p : t.truth.mesh.positions)
    if (p.z() > tip - max_depth_behind_tip && p.y() > -0.08) face.push_back(p);
  return point_to_surface_stats(face, mesh, 1.0).mean;
}

// A synthetic head whose eyes, lids and brows sit 8 mm lower than the
// generic head's proportions put them: a smooth field, full within 22 mm
// of either eye socket's centre and gone at 45 mm, so the face between
// (nose bridge, upper cheeks) stretches and nothing folds.
GenericHead head_with_eyes_lowered(const GenericHead& generic, double drop) {
  GenericHead head = test::make_test_head(4, {}, generic);
  const Vec3 eyes[2] = {head.annotations.eye_left.center, head.annotations.eye_right.center};
  for (Vec3& p : head.mesh.positions) {
    const double d = std::min((p - eyes[0]).norm(), (p - eyes[1]).norm());
    const double u = std::clamp((d - 0.022) / (0.045 - 0.022), 0.0, 1.0);
    p.y() -= drop * (1 - u * u * (3 - 2 * u));
  }
  head.annotations.eye_left.center.y() -= drop;
  head.annotations.eye_right.center.y() -= drop;
  return head;
}

}  // namespace

TEST_CASE("fit_head: eyes 8 mm lower than the generic head's land on the scan's eyes") {
  const GenericHead& generic = truth().generic;
  const GenericHead head = head_with_eyes_lowered(generic, 0.008);
  const PointCloud scan = test::scan_test_truth(test::make_test_truth(head, 1), 5, 30000);
  const std::vector<int>* rims[2] = {&generic.annotations.eye_left.rim, &generic.annotations.eye_right.rim};
  double error[2][2] = {}, local_error[2][2] = {};  // [eye region off, on][eye]: control mesh, after local fitting
  std::ostringstream where;
  for (int on = 0; on < 2; ++on) {
    FitHeadOptions o = quick();
    o.fit_eye_region = on == 1;
    FitHeadResult r;
    const Status st = fit_head(scan, generic, o, r);
    INFO(st.message);
    REQUIRE(st.ok());
    CHECK(r.eye_fit.skipped == (on == 0));
    for (int e = 0; e < 2; ++e) {
      const Vec3 truth_rim = test::vertices_centroid(head.mesh, *rims[e]);
      const Vec3 d = test::vertices_centroid(r.control, *rims[e]) - truth_rim;
      const Vec3 dl = test::vertices_centroid(r.local, *rims[e]) - truth_rim;
      error[on][e] = d.norm();
      local_error[on][e] = dl.norm();
      where << "eye region " << (on ? "on" : "off") << ", eye " << e << ": fitted rim off by (" << 1000 * d.transpose()
            << ") mm, after local fitting (" << 1000 * dl.transpose() << "), aligned generic's ("
            << 1000 * (test::vertices_centroid(r.aligned, *rims[e]) - truth_rim).transpose() << ") mm\n";
    }
    CHECK(turned_triangles(r.aligned.positions, r.control).empty());
    CHECK(r.stages[3].distance.mean_pct < 0.15);
  }
  INFO(where.str());
  // The alignment leaves the generic eyes about 6 mm high; the paper's local
  // fitting keeps them there (no box holds the eyes), the eye region brings
  // them within 2.5 mm (1.8), and the fitted control mesh's rims land within 2 mm
  // (measured: 0.5 and 0.8 mm; global fitting alone gets to 3.7-4.1 mm at
  // a9937b5, closer with later global-fit changes).
  for (int e = 0; e < 2; ++e) {
    CHECK(local_error[0][e] > 0.004);
    CHECK(local_error[1][e] < 0.0025);
    CHECK(error[1][e] < 0.002);
  }
}

TEST_CASE("coverage: whole heads are deep, face captures and the front of a head are shallow") {
  const Truth& t = truth();
  ScanCoverage whole, frontal, cropped;
  REQUIRE(estimate_coverage(t.whole, CoverageOptions{}, whole).ok());
  REQUIRE(estimate_coverage(t.frontal, CoverageOptions{}, frontal).ok());
  const BBox box = bounding_box(t.whole.positions);
  PointCloud front;
  for (const Vec3& p : t.whole.positions)
    if (p.z() > box.max.z() - 0.4 * box.size().z()) front.positions.push_back(p);
  REQUIRE(estimate_coverage(front, CoverageOptions{}, cropped).ok());
  INFO("depth/width: whole " << whole.depth_to_width << ", frontal " << frontal.depth_to_width << ", front 40% "
                             << cropped.depth_to_width);
  CHECK_FALSE(whole.face_only);
  CHECK(whole.depth_to_width > 1.0);
  CHECK(frontal.face_only);
  CHECK(cropped.face_only);
  PointCloud few;
  few.positions.assign(3, Vec3::Zero());
  CHECK(estimate_coverage(few, CoverageOptions{}, whole).code == ErrorCode::InvalidInput);
}

TEST_CASE("fit_head: a frontal face-only capture gives a head, not NotAHead") {
  const Truth& t = truth();
  FitHeadResult r;
  const Status st = fit_head(t.frontal, t.generic, quick(), r);
  INFO(st.message);
  REQUIRE(st.ok());
  CHECK(r.face_only);
  CHECK_FALSE(r.orientation.differs);
  REQUIRE(r.stages.size() == 4);
  for (const auto& s : r.stages) INFO(s.name << " mean " << s.distance.mean_pct << " %");
  INFO("face align rms " << r.face_alignment.rms << " scale " << r.face_alignment.scale);
  CHECK(r.stages[0].distance.mean_pct < 1.0);
  CHECK(r.stages[2].distance.mean_pct < 0.25);
  CHECK(r.stages[3].distance.mean_pct < 0.2);
  const double face_err = truth_face_to_mesh(t, r.control, 0.08);
  INFO("truth face to control: " << face_err * 1000 << " mm");
  CHECK(face_err < 0.003);
  // The unscanned back of the head is still there, head-sized and smooth:
  // the control mesh spans a head's depth, not just the scan's.
  const BBox cb = bounding_box(r.control.positions), tb = bounding_box(t.truth.mesh.positions);
  INFO("control depth " << cb.size().z() << " m, truth depth " << tb.size().z() << " m");
  CHECK(std::abs(cb.size().z() - tb.size().z()) < 0.15 * tb.size().z());
  CHECK(r.notes.size() >= 1);
}

TEST_CASE("fit_head: the front 40 % of a head scan fits with a loose bound") {
  const Truth& t = truth();
  const BBox box = bounding_box(t.whole.positions);
  PointCloud front;
  for (const Vec3& p : t.whole.positions)
    if (p.z() > box.max.z() - 0.4 * box.size().z()) front.positions.push_back(p);
  FitHeadResult r;
  const Status st = fit_head(front, t.generic, quick(), r);
  INFO(st.message);
  REQUIRE(st.ok());
  CHECK(r.face_only);
  for (const auto& s : r.stages) INFO(s.name << " mean " << s.distance.mean_pct << " %");
  CHECK(r.stages[3].distance.mean_pct < 0.2);
  const double face_err = truth_face_to_mesh(t, r.control, 0.08);
  INFO("truth face to control: " << face_err * 1000 << " mm");
  CHECK(face_err < 0.003);
}

TEST_CASE("fit_head: a head facing +x is turned round with a note, or refused with the flags to pass") {
  const Truth& t = truth();
  // Facing +x, +y up: head x -> scan -z, head z -> scan +x.
  const Mat3 R = Eigen::AngleAxisd(M_PI / 2, Vec3::UnitY()).toRotationMatrix();
  REQUIRE((R * Vec3::UnitZ()).isApprox(Vec3::UnitX()));
  PointCloud turned;
  for (const Vec3& p : t.whole.positions) turned.positions.push_back(R * p);
  FitHeadOptions o = quick();
  FitHeadResult r;
  Status st = fit_head(turned, t.generic, o, r);
  INFO(st.message);
  REQUIRE(st.ok());
  REQUIRE(r.orientation.differs);
  CHECK((r.scan_to_head.A * Vec3::UnitX()).isApprox(Vec3::UnitZ(), 1e-9));
  CHECK((r.scan_to_head.A * Vec3::UnitY()).isApprox(Vec3::UnitY(), 1e-9));
  REQUIRE_FALSE(r.notes.empty());
  CHECK(r.notes[0].find("+x") != std::string::npos);
  CHECK(r.stages.back().distance.mean_pct < 0.15);

  o.orientation_check = FitHeadOptions::OrientationCheck::Hint;
  st = fit_head(turned, t.generic, o, r);
  CHECK(st.code == ErrorCode::NotAHead);
  CHECK(st.message.find("--facing 1 0 0 --up 0 1 0") != std::string::npos);
}

// The real scans: bounds from what we measured, with margin (docs/journal.md).
TEST_CASE("fit_head: the real Fran (Cyberware face patch) is turned to face +z and fitted") {
  LK_REQUIRE_SHARED("head_scans/fran_cyberware/fran_cut.vtk");
  PointCloud fran;
  REQUIRE(load_point_cloud_file(lk::test::shared_data_dir() + "/head_scans/fran_cyberware/fran_cut.vtk", fran).ok());
  FitHeadResult r;
  const Status st = fit_head(fran, truth().generic, quick(), r);
  INFO(st.message);
  for (const auto& n : r.notes) INFO(n);
  REQUIRE(st.ok());
  for (const auto& s : r.stages) INFO(s.name << " mean " << s.distance.mean_pct << " %");
  // It looks about 45 degrees between +x and -z, upright.
  CHECK(r.orientation.differs);
  CHECK(r.orientation.up.isApprox(Vec3::UnitY()));
  CHECK(r.orientation.facing.x() > 0.5);
  CHECK(r.orientation.facing.z() < -0.5);
  CHECK(r.face_only);
  CHECK(r.near_fraction > 0.7);
  // 0.116 measured (docs/journal.md); 0.138 -> 0.143 with the eyes' socket
  // rings as creases (docs/design/muscles.md, "The lids closed at level 2").
  CHECK(r.stages[2].distance.mean_pct < 0.145);
  CHECK(r.stages[3].distance.mean_pct < 0.2);
  // At one level the guard leaves the pairs away from the lips and ears
  // alone (4 here): its steps for them moved 21 control vertices toward the
  // generic shape, that no finer level gave back (global fit 0.128 -> 0.172 %).
  INFO("guard: " << r.feature_guard.other_pairs_before << " pairs elsewhere, " << r.feature_guard.moved_vertices
                 << " control vertices moved");
  CHECK(r.feature_guard.other_pairs_after == r.feature_guard.other_pairs_before);
  CHECK_FALSE(r.feature_guard.remeasured);
  // No control triangle turned over against the aligned generic head (11
  // did before the fold guard).
  CHECK(turned_triangles(r.aligned.positions, r.control).empty());
  // Her mouth corner lies 3.5 mm behind where local fitting put it: with the
  // mouth bag held there, the bag came out through her lower lip (35 lip
  // pairs on the smooth level 3); the bag now follows the lips.
  CHECK(test::smooth_region_pairs(r.control, truth().generic, 3, "lips") == 0);
}

TEST_CASE("fit_head: the real James (menpo3d face capture in mm)") {
  LK_REQUIRE_SHARED("head_scans/james_menpo3d/james.obj");
  PointCloud james;
  REQUIRE(load_point_cloud_file(lk::test::shared_data_dir() + "/head_scans/james_menpo3d/james.obj", james).ok());
  FitHeadResult r;
  FitHeadOptions o = quick();
  o.fit_eye_region = true;  // off by default (fit_head.h); its rims are checked below
  const Status st = fit_head(james, truth().generic, o, r);
  INFO(st.message);
  for (const auto& n : r.notes) INFO(n);
  REQUIRE(st.ok());
  for (const auto& s : r.stages) INFO(s.name << " mean " << s.distance.mean_pct << " %");
  CHECK(r.unit_to_metres == 0.001);
  CHECK_FALSE(r.orientation.differs);
  // 0.116 measured (docs/journal.md); 0.138 -> 0.143 with the eyes' socket
  // rings as creases (docs/design/muscles.md, "The lids closed at level 2").
  CHECK(r.stages[2].distance.mean_pct < 0.145);
  CHECK(r.stages[3].distance.mean_pct < 0.2);
  // The crease band from the eye corners to the ears was 36 control
  // triangles turned over against the aligned generic head (local fitting
  // handed 12 over); the fold guard and the rest shape repair leave none.
  INFO("turned by local fitting: " << r.global_fit.turned_before);
  CHECK(r.global_fit.turned_before > 0);
  CHECK(r.global_fit.turned_after == 0);
  CHECK(turned_triangles(r.aligned.positions, r.control).empty());
  // The mouth bag follows his lips (10 lip pairs on the smooth level 3 while
  // it was held where local fitting put it).
  CHECK(test::smooth_region_pairs(r.control, truth().generic, 3, "lips") == 0);
  // His ears keep their shape (bound edges): their flaps folded onto the
  // hair and their own bowls, 13 crossing control pairs and 262 ear pairs on
  // the smooth level 3 when free (measured bound: 0 and 39).
  std::vector<std::array<int, 2>> control_pairs;
  REQUIRE(find_self_intersections(r.control, control_pairs).ok());
  CHECK(control_pairs.size() <= 3);
  CHECK(test::smooth_region_pairs(r.control, truth().generic, 3, "ears") < 100);

  // The eyes land on his eyes: the eye rims' centroids against the centroids
  // of the six iBUG landmarks around each eye (james.ljson; the fit does not
  // read them). The alignment leaves the generic eyes 10 mm too high.
  LK_REQUIRE_SHARED("head_scans/james_menpo3d/james.ljson");
  std::ifstream file(lk::test::shared_data_dir() + "/head_scans/james_menpo3d/james.ljson");
  nlohmann::json landmarks;
  REQUIRE_NOTHROW(file >> landmarks);
  const auto& group = landmarks["groups"]["LJSON"];
  // iBUG "leye" is the eye on the image's left: the subject's right (-x).
  const std::pair<const char*, const EyeSocket*> eyes[2] = {{"reye", &truth().generic.annotations.eye_left},
                                                            {"leye", &truth().generic.annotations.eye_right}};
  for (const auto& [label, socket] : eyes) {
    Vec3 expected = Vec3::Zero();
    int count = 0;
    for (const auto& l : group["labels"])
      if (l["label"] == label)
        for (int i : l["mask"]) {
          const auto& p = group["landmarks"]["points"][i];
          expected += r.scan_to_head.apply(Vec3(p[0].get<double>(), p[1].get<double>(), p[2].get<double>()));
          ++count;
        }
    REQUIRE(count == 6);
    expected /= count;
    const Vec3 aligned = test::vertices_centroid(r.aligned, socket->rim) - expected;
    const Vec3 fitted = test::vertices_centroid(r.control, socket->rim) - expected;
    INFO(label << ": rim centroid off by (" << 1000 * fitted.transpose() << ") mm, aligned generic's ("
               << 1000 * aligned.transpose() << ") mm");
    CHECK(aligned.y() > 0.008);
    CHECK(std::abs(fitted.y()) < 0.003);
    CHECK(fitted.norm() < 0.0045);
  }
}

TEST_CASE("fit_head: the real James's ear folds are refined as creases") {
  // Where his plate ears meet his head a control edge bends 105-141 deg and
  // the smooth level 3 pleats there (14-18 ear pairs with the eye-ring
  // corners at 45 deg, 4 with the asset's even corners; the fold relief's
  // umbrella steps leave them at every share). The global fit hands such
  // edges to the subdivision as creases (GlobalFitResult::fold_crease_edges).
  LK_REQUIRE_SHARED("head_scans/james_menpo3d/james.obj");
  PointCloud james;
  REQUIRE(load_point_cloud_file(lk::test::shared_data_dir() + "/head_scans/james_menpo3d/james.obj", james).ok());
  const HeadAnnotations& ann = truth().generic.annotations;
  FitHeadResult r;
  // The control mesh the global fit hands on, with and without the creases.
  TriMesh fitted_with, fitted_without;
  FitStageObserver with_observer, without_observer;
  with_observer.finished = [&](const std::string& stage, const TriMesh& m) {
    if (stage == "global_fitting") fitted_with = m;
  };
  without_observer.finished = [&](const std::string& stage, const TriMesh& m) {
    if (stage == "global_fitting") fitted_without = m;
  };
  REQUIRE(fit_head(james, truth().generic, quick(), r, with_observer).ok());
  INFO(r.global_fit.fold_crease_edges.size() << " fold creases; relief folds " << r.global_fit.relief_folds_before
                                             << " -> " << r.global_fit.relief_folds_after);
  REQUIRE_FALSE(r.global_fit.fold_crease_edges.empty());
  CHECK(r.global_fit.fold_crease_edges.size() <= 4);
  // The creases are the fit's: refined with them, the ears no longer cross;
  // the same control mesh with the head's curves alone still does.
  const int with = test::smooth_region_pairs(r.control, r.multires.creases, ann, 3, "ears");
  const int without = test::smooth_region_pairs(r.control, truth().generic, 3, "ears");
  INFO("smooth level-3 ear pairs: " << with << " with the fold creases, " << without << " without");
  CHECK(with == 0);
  CHECK(without >= 3);  // 4 measured (16 with the corner-45 head)
  // Off, and the smooth surface untangled on level 2 only (as before
  // face_untangle_level): no creases handed over, the ears cross.
  FitHeadOptions off = quick();
  off.global.smooth_guard_crease_max_edges = 0;
  off.face_untangle_level = 2;
  FitHeadResult r_off;
  REQUIRE(fit_head(james, truth().generic, off, r_off, without_observer).ok());
  CHECK(r_off.global_fit.fold_crease_edges.empty());
  // Choosing the creases moves no vertex: the global fit's positions are
  // the same to the bit without the search (what the scanned neck's fit,
  // which uses only its positions, relies on to skip it: fit_head.cpp).
  REQUIRE(fitted_with.num_vertices() > 0);
  CHECK(fitted_without.positions == fitted_with.positions);
  CHECK(test::smooth_region_pairs(r_off.control, r_off.multires.creases, ann, 3, "ears") >= 3);
  // Untangling level 3 (the default on face captures) opens them too.
  off.face_untangle_level = 3;
  REQUIRE(fit_head(james, truth().generic, off, r_off).ok());
  CHECK(r_off.untangle.pairs_before > 0);
  CHECK(test::smooth_region_pairs(r_off.control, r_off.multires.creases, ann, 3, "ears") == 0);
}

TEST_CASE("fit_head: the fold relief takes out folds of the real James's smooth level 3") {
  // His fitted control mesh has sliver faces with sharp kinks (a cheek face
  // 36/8/136 deg, dihedral 84 deg where the template has 0.3): level 2 is
  // clean after the guard, level 3 folds inside faces sharing a corner. The
  // relief steps those corners' umbrella vectors towards the template's.
  // The fold creases are off in both fits, so the relief is measured alone.
  // Fitted with the generic head as it was until 22 Nov (eye-ring corners
  // at 45 deg): with the asset's even corners James folds in 6 places the
  // relief cannot better, and this test would have no subject.
  LK_REQUIRE_SHARED("head_scans/james_menpo3d/james.obj");
  PointCloud james;
  REQUIRE(load_point_cloud_file(lk::test::shared_data_dir() + "/head_scans/james_menpo3d/james.obj", james).ok());
  const GenericHead& generic = test::corner45_generic_head();
  const HeadAnnotations& ann = generic.annotations;
  FitHeadOptions on = quick(), off = quick();
  on.global.smooth_guard_crease_max_edges = 0;
  off.global.smooth_guard_crease_max_edges = 0;
  off.global.smooth_guard_relief_steps = 0;
  // The untangling's restore after the global fit (four rings since 24
  // Nov) takes out what either fit leaves (0 and 0 pairs), so the relief is
  // measured before it: 12 and 37 pairs with the restore off.
  on.untangle_restore_rings = off.untangle_restore_rings = -1;
  FitHeadResult r_on, r_off;
  REQUIRE(fit_head(james, generic, on, r_on).ok());
  REQUIRE(fit_head(james, generic, off, r_off).ok());
  INFO("relief: folds " << r_on.global_fit.relief_folds_before << " -> " << r_on.global_fit.relief_folds_after << " in "
                        << r_on.global_fit.relief_steps << " steps, " << r_on.global_fit.relief_vertices << " vertices");
  CHECK(r_on.global_fit.relief_searched);  // James's folds turn level-3 triangles
  CHECK(r_on.global_fit.relief_folds_before >= 20);  // 61 measured
  CHECK(r_on.global_fit.relief_folds_after < r_on.global_fit.relief_folds_before);
  CHECK(r_on.global_fit.relief_steps > 0);
  CHECK(r_on.global_fit.relief_vertices > 0);
  CHECK(r_on.global_fit.relief_vertices <= 40);  // local: 9 of 1366 control vertices measured
  CHECK(r_off.global_fit.relief_steps == 0);
  // Counted independently on the smooth level 3: fewer pairs outside the
  // lips and ears (the relief's folds are cheek, brow and eye-rim pleats).
  const int rest_on = test::smooth_region_pairs(r_on.control, r_on.multires.creases, ann, 3, "face");
  const int rest_off = test::smooth_region_pairs(r_off.control, r_off.multires.creases, ann, 3, "face");
  INFO("smooth level-3 pairs touching the face: " << rest_on << " with the relief, " << rest_off << " without");
  CHECK(rest_on < rest_off);
}

// Edges of the control mesh's smooth level 3 (with its creases) that bend
// by more than 90 deg where the aligned generic head's bend by less than
// 45: pleats (global_fit.h, "Pleat relief").
int smooth_pleat_edges(const FitHeadResult& r) {
  MultiresMesh fit, generic;
  REQUIRE(build_multires(r.control, r.multires.creases, 3, fit).ok());
  REQUIRE(build_multires(r.aligned, r.multires.creases, 3, generic).ok());
  const TriMesh a = level_mesh(fit, 3), b = level_mesh(generic, 3);
  const std::vector<Vec3> na = face_normals(a), nb = face_normals(b);
  std::map<std::pair<int, int>, std::vector<int>> faces_of_edge;
  for (int f = 0; f < a.num_triangles(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int u = a.triangles[f][k], v = a.triangles[f][(k + 1) % 3];
      faces_of_edge[{std::min(u, v), std::max(u, v)}].push_back(f);
    }
  int pleats = 0;
  for (const auto& [edge, faces] : faces_of_edge)
    if (faces.size() == 2 && na[faces[0]].dot(na[faces[1]]) < 0 && nb[faces[0]].dot(nb[faces[1]]) > std::sqrt(0.5))
      ++pleats;
  return pleats;
}

TEST_CASE("fit_head: the pleat relief takes the slit out of the real Fran's right cheek") {
  // Her fitted control mesh crumples under the right eye: its smooth level
  // 3 folds into a 10 mm pleat (edges bending 105-165 deg where the generic
  // head's bend by 4) that crosses nothing, so the fold relief does not see
  // it, and every render shows a dark slit there.
  LK_REQUIRE_SHARED("head_scans/fran_cyberware/fran_cut.vtk");
  PointCloud fran;
  REQUIRE(load_point_cloud_file(lk::test::shared_data_dir() + "/head_scans/fran_cyberware/fran_cut.vtk", fran).ok());
  const HeadAnnotations& ann = truth().generic.annotations;
  FitHeadOptions on = quick(), off = quick();
  off.global.smooth_guard_pleat_steps = 0;
  FitHeadResult r_on, r_off;
  REQUIRE(fit_head(fran, truth().generic, on, r_on).ok());
  REQUIRE(fit_head(fran, truth().generic, off, r_off).ok());
  const GlobalFitResult& g = r_on.global_fit;
  const int pleats_on = smooth_pleat_edges(r_on), pleats_off = smooth_pleat_edges(r_off);
  INFO("pleat relief: " << g.pleats_before << " -> " << g.pleats_after << " in " << g.pleat_steps
                        << " steps; counted on the smooth level 3: " << pleats_off << " without, " << pleats_on << " with");
  CHECK(g.pleats_before >= 8);  // 16 measured
  CHECK(g.pleat_steps > 0);
  CHECK(g.pleats_after < g.pleats_before);
  CHECK(r_off.global_fit.pleat_steps == 0);
  CHECK(pleats_on < pleats_off);
  // Not at the price of crossings, nor of her fit (Table 1 of the control
  // mesh within 10 %). On an AVX-512 EPYC (session 48) the relief's steps
  // held 4 face pairs on her smooth level 3 that the untangling takes out
  // without them; the steps near those pairs are undone there
  // (FitHeadOptions::pleat_undo_where_crossing; without it this fails).
  // The count itself moves with the machine (0 both ways there, 4 both
  // ways on an EPYC without AVX-512, session 50), so the check is that the
  // relief adds none.
  const int face_pairs_on = test::smooth_region_pairs(r_on.control, r_on.multires.creases, ann, 3, "face");
  const int face_pairs_off = test::smooth_region_pairs(r_off.control, r_off.multires.creases, ann, 3, "face");
  INFO("face pairs on the smooth level 3: " << face_pairs_off << " without the relief, " << face_pairs_on
                                            << " with; pleat steps undone: " << r_on.pleat_steps_undone);
  CHECK(face_pairs_on <= face_pairs_off);
  CHECK(r_on.stages[2].distance.mean_pct < 1.1 * r_off.stages[2].distance.mean_pct);
}

TEST_CASE("fit_head: the real James's columella base comes out of his nose (E_back's normal ray)") {
  // His columella drops 13 mm over 17 mm where the generic nose's underside
  // is level: the generic columella base stayed 8.5 mm up inside his nose,
  // where no point is nearest to it and its 16 nearest points hold a fold
  // (columella, nostril floor, lip), so E_back's patch gave it no plane.
  // Its normal line meets his subnasale 10 mm down (global_fit.h).
  LK_REQUIRE_SHARED("head_scans/james_menpo3d/james.obj");
  PointCloud james;
  REQUIRE(load_point_cloud_file(lk::test::shared_data_dir() + "/head_scans/james_menpo3d/james.obj", james).ok());
  const GenericHead& generic = truth().generic;
  // Each nose control vertex's distance from his triangles.
  auto nose_off_scan = [&](const PointCloud& scan, double reach, int& rays) {
    FitHeadOptions o = quick();
    o.global.back_ray_edges = reach;
    FitHeadResult r;
    REQUIRE(fit_head(scan, generic, o, r).ok());
    rays = r.global_fit.back_ray_planes;
    TriMesh his;  // his triangles, whatever the fit was given
    his.triangles = james.faces;
    for (const Vec3& p : james.positions) his.positions.push_back(r.scan_to_head.apply(p));
    MeshBvh bvh;
    REQUIRE(build_bvh(his, bvh).ok());
    std::map<int, double> off;
    for (int v : generic.annotations.regions.at("nose")) off[v] = closest_point(bvh, r.control.positions[v]).distance;
    return off;
  };
  auto farthest = [](const std::map<int, double>& d) {
    return std::max_element(d.begin(), d.end(), [](const auto& a, const auto& b) { return a.second < b.second; });
  };
  // As a mesh (rays meet his triangles) and as raw points (rays marched
  // until they meet a point); measured against his triangles both times.
  PointCloud points = james;
  points.faces.clear();
  for (const PointCloud* scan : {&james, &points}) {
    int rays_off = 0, rays_on = 0;
    const std::map<int, double> off = nose_off_scan(*scan, 0.0, rays_off), on = nose_off_scan(*scan, 1.0, rays_on);
    // Without rays the farthest is the columella base; with them, that
    // vertex and the whole nose.
    const auto base = farthest(off), worst_on = farthest(on);
    INFO((scan == &james ? "mesh" : "points") << ": the nose's control vertex farthest from his triangles without rays, "
                                              << base->first << ": " << 1e3 * base->second << " mm; with rays ("
                                              << rays_on << " ray planes) " << 1e3 * on.at(base->first)
                                              << " mm; the farthest with rays, " << worst_on->first << ": "
                                              << 1e3 * worst_on->second << " mm");
    CHECK(rays_off == 0);
    CHECK(rays_on >= 1);
    CHECK(base->second > 0.006);         // 8.5-8.6 mm measured, both
    CHECK(on.at(base->first) < 0.003);   // 1.5 mm measured, both
    // With the regular nape (23 Nov) the mesh fit leaves the top of the
    // nose's bridge 3.1 mm off (the generic head's vertex 600; 1.5 mm with
    // the head before): chaotic, not the columella.
    CHECK(worst_on->second < 0.004);
  }
}
