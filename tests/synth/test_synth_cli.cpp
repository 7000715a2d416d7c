// The synth-head / synth-scan commands: files written, same seed -> same
// bytes, different seed -> different scan, usage errors exit with 2.
#include "test_data.h"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>


namespace {

using lk::test::read_file_text;

int run(const std::string& args) { return lk::test::run_likeness(args); }

}  // namespace

TEST_CASE("synth-scan writes the scan and its truth, deterministically", "[synth][cli]") {
  LK_REQUIRE_LIKENESS();
  const std::string dir = lk::test::scratch_dir("synth_cli");
  REQUIRE(run("synth-scan --seed 3 --points 20000 --out " + dir + "/a") == 0);
  REQUIRE(run("synth-scan --seed 3 --points 20000 --out " + dir + "/b") == 0);
  REQUIRE(run("synth-scan --seed 4 --points 20000 --out " + dir + "/c") == 0);
  for (const char* f : {"scan.ply", "truth.obj", "truth_control.obj", "truth_annotations.json", "scan_info.json"}) {
    INFO(f);
    const std::string a = read_file_text(dir + "/a/" + f);
    CHECK(a.size() > 100);
    CHECK(a == read_file_text(dir + "/b/" + f));
  }
  CHECK(read_file_text(dir + "/a/scan.ply") != read_file_text(dir + "/c/scan.ply"));
  CHECK(read_file_text(dir + "/a/truth_control.obj") != read_file_text(dir + "/c/truth_control.obj"));
  const auto info = nlohmann::json::parse(read_file_text(dir + "/a/scan_info.json"));
  CHECK(info["seed"] == 3);
  CHECK(info["points"].get<int>() >= 19400);
  CHECK(info["points"].get<int>() <= 20000);
  CHECK(info["stations"].size() == 6);
  CHECK(info["head_parameters"].contains("nose_length"));

  REQUIRE(run("synth-head --seed 3 --out " + dir + "/h.obj --annotations " + dir + "/h.json") == 0);
  CHECK(read_file_text(dir + "/h.obj") == read_file_text(dir + "/a/truth_control.obj"));
  CHECK(run("synth-head --seed -1 --out " + dir + "/x.obj") == 2);
  CHECK(run("synth-head --seed 3") == 2);
  CHECK(run("synth-scan --seed 3 --out " + dir + "/d --points 0") == 2);  // out of range: a usage error, like --seed -1
  CHECK(run("synth-scan --seed 3 --out " + dir + "/d --bogus 1") == 2);
  CHECK(run("synth-head --seed 3 --out /nonexistent/dir/h.obj") == 1);
}
