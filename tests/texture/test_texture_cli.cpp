// likeness texture: synthetic photos + points in, textured.obj/mtl, skin.png,
// report.json out; clear errors (exit 1) for bad photos, bad points files,
// too few points, a photo that sees no head, a missing head; usage errors
// (exit 2) for mismatched counts and unknown options.
#include "test_data.h"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <fstream>
#include <sstream>

namespace {

using lk::test::read_file_text;

// Exit code; stderr goes to err_file.
int run(const std::string& args, const std::string& err_file) {
  return lk::test::run_likeness("texture " + args, err_file);
}

void write(const std::string& path, const std::string& text) { std::ofstream(path) << text; }

}  // namespace

TEST_CASE("likeness texture: synthetic photos in, textured head out, and clear errors", "[texture][cli]") {
  LK_REQUIRE_LIKENESS();
  const std::string dir = lk::test::scratch_dir("texture_cli");
  const std::string err = dir + "/err.txt";
  REQUIRE(run("--head generic --make-synthetic " + dir + "/in --photo-width 600 --photo-height 400", err) == 0);
  std::string photos, points;
  for (int i = 0; i < 5; ++i) {
    photos += " " + dir + "/in/photo" + std::to_string(i) + ".png";
    points += " " + dir + "/in/points" + std::to_string(i) + ".txt";
  }
  REQUIRE(run("--head generic --photos" + photos + " --points" + points + " --size 256 --same-camera --out " + dir +
                  "/out",
              err) == 0);
  const std::string obj = read_file_text(dir + "/out/textured.obj");
  CHECK(obj.find("mtllib textured.mtl") != std::string::npos);
  CHECK(obj.find("\nvt ") != std::string::npos);
  CHECK(read_file_text(dir + "/out/textured.mtl").find("map_Kd skin.png") != std::string::npos);
  CHECK(read_file_text(dir + "/out/skin.png").size() > 1000);
  const auto rep = nlohmann::json::parse(read_file_text(dir + "/out/report.json"));
  REQUIRE(rep["photos"].size() == 5);
  for (const auto& p : rep["photos"]) {
    CHECK(p["calibration"]["rms_px"].get<double>() < 1.0);  // clicks carry up to 0.5 px of error
    CHECK(p["calibration"]["points"].size() == 15);
    CHECK(p["vertices_valid"].get<int>() > 100);
  }
  CHECK(rep["timings_ms"].contains("spline"));
  CHECK(rep["timings_ms"].contains("resample"));
  CHECK(rep["uv"]["flipped"] == 0);

  const std::string p0 = dir + "/in/photo0.png", q0 = dir + "/in/points0.txt", out = " --out " + dir + "/bad";
  // Not an image.
  write(dir + "/not_image.jpg", "hello");
  CHECK(run("--head generic --photos " + dir + "/not_image.jpg --points " + q0 + out, err) == 1);
  CHECK(read_file_text(err).find("not_image.jpg") != std::string::npos);
  // Garbled points file: names file and line.
  write(dir + "/garbled.txt", "# header\n1 2 3 4 5\n1 2 three 4 5\n");
  CHECK(run("--head generic --photos " + p0 + " --points " + dir + "/garbled.txt" + out, err) == 1);
  CHECK(read_file_text(err).find("garbled.txt: line 3") != std::string::npos);
  // Fewer than 6 points.
  write(dir + "/few.txt", "1 2 3 4 5\n1 2 3 4 6\n1 2 3 4 7\n");
  CHECK(run("--head generic --photos " + p0 + " --points " + dir + "/few.txt" + out, err) == 1);
  CHECK(read_file_text(err).find("at least 6") != std::string::npos);
  // Counts differ: usage error.
  CHECK(run("--head generic --photos " + p0 + " " + p0 + " --points " + q0 + out, err) == 2);
  // A photo whose points are 2 m away from the head: it sees no vertex.
  std::string shifted, line;
  std::istringstream in(read_file_text(dir + "/in/points1.txt"));
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream ls(line);
    double u, v, x, y, z;
    ls >> u >> v >> x >> y >> z;
    shifted += std::to_string(u) + " " + std::to_string(v) + " " + std::to_string(x + 2.0) + " " +
               std::to_string(y) + " " + std::to_string(z) + "\n";
  }
  write(dir + "/shifted.txt", shifted);
  CHECK(run("--head generic --photos " + p0 + " " + dir + "/in/photo1.png --points " + q0 + " " + dir +
                "/shifted.txt" + out,
            err) == 1);
  CHECK(read_file_text(err).find("photo1.png sees no vertex") != std::string::npos);
  // Missing head directory, unknown option.
  CHECK(run("--head " + dir + "/no_such_fit --photos " + p0 + " --points " + q0 + out, err) == 1);
  CHECK(read_file_text(err).find("no_such_fit") != std::string::npos);
  CHECK(run("--head generic --photos " + p0 + " --points " + q0 + out + " --bogus", err) == 2);
}
