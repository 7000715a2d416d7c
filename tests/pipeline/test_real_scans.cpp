// Every real scan in ../shared/data/head_scans fits without crossing
// itself at the lips and the ears (issue 35). Skipped with a message when
// the folder is absent; the scans are never copied into the repo. Two
// busts do not pass yet (docs/design/fit_real_scans.md): Plato's level 3 crosses
// itself at the ears, Gutenberg's alignment is refused as not a head.
// They are fitted and their figures printed (WARN), not required; any
// other scan put in the folder is required to pass.
#include "io/io.h"
#include "pipeline/fit_head.h"
#include "pipeline/fit_quality.h"
#include "test_data.h"
#include "test_scan.h"

#include <catch2/catch.hpp>
#include <algorithm>
#include <filesystem>

using namespace lk;

namespace {

// Every OBJ/PLY/VTK/XYZ file one folder below head_scans/.
std::vector<std::string> real_scans() {
  namespace fs = std::filesystem;
  std::vector<std::string> out;
  std::error_code ec;
  for (const auto& folder : fs::directory_iterator(lk::test::shared_data_dir() + "/head_scans", ec))
    for (const auto& file : fs::directory_iterator(folder.path(), ec)) {
      const std::string ext = file.path().extension().string();
      if (ext == ".obj" || ext == ".ply" || ext == ".vtk" || ext == ".xyz") out.push_back(file.path().string());
    }
  std::sort(out.begin(), out.end());
  return out;
}

// Folders of scans known to fail (docs/design/fit_real_scans.md, "Not done").
bool known_failure(const std::string& path) {
  return path.find("/threedscans_plato/") != std::string::npos ||
         path.find("/threedscans_gutenberg/") != std::string::npos;
}

}  // namespace

TEST_CASE("fit_head: every real scan fits with no crossing pairs at the lips and the ears", "[pipeline][real_scans]") {
  LK_REQUIRE_SHARED("head_scans");
  const std::vector<std::string> scans = real_scans();
  REQUIRE(!scans.empty());
  for (const std::string& path : scans) {
    DYNAMIC_SECTION(path) {
      PointCloud scan;
      REQUIRE(load_point_cloud_file(path, scan).ok());
      FitHeadOptions options;
      options.measure_stages = false;  // the crossings are what is checked
      FitHeadResult r;
      const Status st = fit_head(scan, test::generic_head(), options, r);
      FitQuality q;
      if (st) REQUIRE(measure_fit_quality(r, test::generic_head().annotations, q).ok());
      if (known_failure(path)) {
        if (!st) WARN("known failure, " << path << ": " << st.message);
        else
          WARN("known failure, " << path << ": level " << q.level << " lips " << q.crossings.lips << ", ears "
                                 << q.crossings.ears << " pairs");
        continue;
      }
      INFO(st.message);
      REQUIRE(st.ok());
      INFO("level " << q.level << ": " << q.crossings.total << " pairs (lips " << q.crossings.lips << ", ears "
                    << q.crossings.ears << ", eye sockets " << q.crossings.eye_sockets << ", rest "
                    << q.crossings.rest << ")");
      CHECK(q.level == 3);
      CHECK(q.crossings.lips == 0);
      CHECK(q.crossings.ears == 0);
    }
  }
}

TEST_CASE("fit_head: Plato's ears, under carved hair, cross less when held in the generic shape",
          "[pipeline][real_scans]") {
  // FitHeadOptions::hold_crossing_ears on the scan it was made for
  // (docs/design/fit_real_scans.md): it must lower the ear pairs and add none
  // elsewhere; 0 is not reached yet (Plato stays a known failure above).
  LK_REQUIRE_SHARED("head_scans/threedscans_plato/plato.obj");
  PointCloud scan;
  REQUIRE(load_point_cloud_file(lk::test::shared_data_dir() + "/head_scans/threedscans_plato/plato.obj", scan).ok());
  FitHeadOptions on;
  on.measure_stages = false;
  FitHeadOptions off = on;
  off.hold_crossing_ears = false;
  FitHeadResult free_fit, held_fit;
  REQUIRE(fit_head(scan, test::generic_head(), off, free_fit).ok());
  REQUIRE(fit_head(scan, test::generic_head(), on, held_fit).ok());
  FitQuality free_q, held_q;
  REQUIRE(measure_fit_quality(free_fit, test::generic_head().annotations, free_q).ok());
  REQUIRE(measure_fit_quality(held_fit, test::generic_head().annotations, held_q).ok());
  INFO("ear pairs " << free_q.crossings.ears << " -> " << held_q.crossings.ears << ", all "
                    << free_q.crossings.total << " -> " << held_q.crossings.total);
  REQUIRE(free_q.crossings.ears > 0);  // else there is nothing to hold
  CHECK(held_fit.ears_held > 0);
  CHECK(held_q.crossings.ears < free_q.crossings.ears);
  CHECK(held_q.crossings.total - held_q.crossings.ears <= free_q.crossings.total - free_q.crossings.ears);
}
