// The shape fit's pulls on the face's sides (photos/fit_pulls.h): which
// observation group moves the cheeks and the jaw outward.
#include "photos/fit_pulls.h"
#include "photos/photos_job.h"
#include "photos_scenario.h"
#include "test_data.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>

namespace lk {
namespace {

const FitPullGroup* group(const FitPulls& p, const std::string& name) {
  for (const FitPullGroup& g : p.groups)
    if (g.name == name) return &g;
  return nullptr;
}

TEST_CASE("fit pulls: only the group whose points lie outside the head pulls, and outward", "[photos][pulls]") {
  test::PhotoScenario sc = test::make_photo_scenario(3);
  const GenericHead& g = sc.generic;
  const Vec3 lateral = g.annotations.up.cross(g.annotations.look).normalized();
  // Each mapped landmark seen by every camera at the generic head's own
  // projection (zero residual), except the cheeks group's, seen 3 mm
  // farther out from the midline.
  std::vector<FeatureObservation> obs;
  std::vector<std::string> row_groups;
  int cheek_points = 0;
  for (size_t c = 0; c < sc.session.cameras.size(); ++c)
    for (size_t m = 0; m < sc.landmarks.size(); ++m) {
      if (!sc.landmarks[m].valid()) continue;
      const std::string grp = landmark_pull_group(g, sc.landmarks[m], int(m), false);
      Vec3 X = surface_position(g.mesh, sc.landmarks[m]);
      if (grp == "cheeks") {
        X += (X.dot(lateral) > 0 ? 1.0 : -1.0) * 0.003 * lateral;
        ++cheek_points;
      }
      FeatureObservation o;
      o.camera = int(c);
      o.point = sc.landmarks[m];
      o.landmark = int(m);
      if (!sc.session.cameras[c].project(X, o.pixel)) continue;
      obs.push_back(o);
      row_groups.push_back(grp);
      row_groups.push_back(grp);
    }
  REQUIRE(cheek_points > 20);
  std::vector<std::unique_ptr<ObservationSet>> sets;
  sets.push_back(std::make_unique<FeatureSet>(g.mesh, sc.session.cameras, obs, 4.0));
  const std::vector<PullRegion> regions = lateral_pull_regions(g);
  REQUIRE(regions.size() == 3);
  REQUIRE(regions[0].name == "cheeks");
  REQUIRE(regions[0].vertices.size() > 50);
  FitPulls p;
  double unit = 0;
  REQUIRE(measure_fit_pulls(g.mesh, g.mesh.positions, sets, {0.3}, {row_groups}, ShapeFitOptions{}, 100, regions,
                            lateral, unit, p));
  const FitPullGroup* cheeks = group(p, "cheeks");
  REQUIRE(cheeks);
  std::printf("cheek points 3 mm out: the first step moves the cheeks %+.3f mm, the jaw %+.3f mm; cheeks group %+.3f / %+.3f\n",
              1000 * p.explained_m[0], 1000 * p.explained_m[1], 1000 * cheeks->share_m[0], 1000 * cheeks->share_m[1]);
  CHECK(cheeks->share_m[0] > 1e-4);  // outward, and a tenth of a millimetre at least
  CHECK(cheeks->force[0] > 0.2);
  for (const FitPullGroup& q : p.groups)
    if (q.name != "cheeks" && q.name != "stiffness")
      for (size_t k = 0; k < regions.size(); ++k) CHECK(std::abs(q.share_m[k]) < 1e-9);  // zero residual: no pull
  CHECK(p.explained_m[0] == Approx(cheeks->share_m[0]));
  CHECK(p.displacement_m[0] == 0);
}

TEST_CASE("fit pulls: at the end of a fit the groups' shares add up to the fitted displacement", "[photos][pulls]") {
  test::PhotoScenario sc = test::make_photo_scenario(2);
  PhotosJobOptions opt;
  PhotosJobResult r;
  REQUIRE(run_photos_job(sc.generic, sc.map, sc.session.photos, opt, r));
  PhotosFitPulls pulls;
  REQUIRE(measure_photos_fit_pulls(sc.generic, sc.landmarks, sc.session.photos, r.calib, opt, r.fit.mesh.positions, pulls));
  REQUIRE(pulls.regions.size() == 3);
  for (size_t k = 0; k < 2; ++k) {
    std::printf("%s: fitted %+.3f mm outward, the shares' sum %+.3f mm, the first step %+.3f mm\n",
                pulls.regions[k].name.c_str(), 1000 * pulls.end.displacement_m[k], 1000 * pulls.end.explained_m[k],
                1000 * pulls.start.explained_m[k]);
    for (const FitPullGroup& q : pulls.end.groups)
      std::printf("  %-12s %5d rows: share %+.3f mm, force %+.3f\n", q.name.c_str(), q.rows, 1000 * q.share_m[k], q.force[k]);
    // A fitted shape is a minimum of its last stage: the linearized split is
    // exact up to the fit's tolerance and the lips' bag kept inside after it.
    CHECK(std::abs(pulls.end.displacement_m[k]) > 2e-4);
    CHECK(pulls.end.explained_m[k] == Approx(pulls.end.displacement_m[k]).epsilon(0.1).margin(5e-5));
    // At the end the stiffness holds the observations' outward force back.
    double obs_force = 0;
    for (const FitPullGroup& q : pulls.end.groups)
      if (q.name != "stiffness") obs_force += q.force[k];
    const FitPullGroup* s = group(pulls.end, "stiffness");
    REQUIRE(s);
    CHECK(s->force[k] * obs_force < 0);
  }
}

TEST_CASE("likeness photos --pulls writes the split into report.json", "[photos][pulls][cli]") {
  LK_REQUIRE_LIKENESS();
  const std::string dir = test::scratch_dir("photos_pulls_cli");
  REQUIRE(test::run_likeness("synth-photos --seed 2 --cameras 6 --no-render --out " + dir + "/s") == 0);
  std::string points;
  for (int i = 0; i < 6; ++i) points += " " + dir + "/s/view_0" + std::to_string(i) + ".json";
  REQUIRE(test::run_likeness("photos --points" + points + " --map " + dir + "/s/map.json --levels 0 --pulls --out " + dir +
                             "/out") == 0);
  const auto rep = nlohmann::json::parse(test::read_file_text(dir + "/out/report.json"));
  REQUIRE(rep.contains("fit_pulls"));
  for (const char* region : {"cheeks", "jaw", "ears"}) {
    const auto& r = rep["fit_pulls"]["regions"][region];
    const double fitted = r["fitted_mm"].get<double>(), explained = r["explained_mm"].get<double>();
    std::printf("--pulls %s: fitted %+.3f mm, the shares' sum %+.3f mm\n", region, fitted, explained);
    CHECK(std::abs(fitted - explained) < 0.1 * std::abs(fitted) + 0.05);
    CHECK(r["groups"].contains("stiffness"));
    CHECK(r["groups"].size() >= 4);
  }
}

}  // namespace
}  // namespace lk
