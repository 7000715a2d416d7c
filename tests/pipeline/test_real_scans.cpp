// Every real scan in ../shared/data/head_scans fits without crossing
// itself at the lips and the ears (issue 35). Skipped with a message when
// the folder is absent; the scans are never copied into the repo. Two
// busts do not pass yet (docs/fit_real_scans.md): Plato's level 3 crosses
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

// Folders of scans known to fail (docs/fit_real_scans.md, "Not done").
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
