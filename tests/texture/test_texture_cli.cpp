// likeness texture: synthetic photos + points in, textured.obj/mtl, skin.png,
// report.json out; clear errors (exit 1) for bad photos, bad points files,
// too few points, a photo that sees no head, a missing head; usage errors
// (exit 2) for mismatched counts and unknown options.
#include "test_data.h"

#include "image/image.h"
#include "io/io.h"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdlib>
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

namespace {

// Shares of a photo's head pixels (those unlike its corner, the background)
// that are much darker than the head's median luminance (brows) and clearly
// red (lips).
struct SkinMarks {
  double dark = 0, red = 0;
};

SkinMarks skin_marks(const std::string& path) {
  lk::Image im;
  REQUIRE(lk::load_image_file(path, im, 3).ok());
  const std::uint8_t* bg = im.at(0, 0);
  std::vector<double> lum;
  std::vector<const std::uint8_t*> head;
  for (int y = 0; y < im.height; ++y)
    for (int x = 0; x < im.width; ++x) {
      const std::uint8_t* p = im.at(x, y);
      if (std::abs(p[0] - bg[0]) + std::abs(p[1] - bg[1]) + std::abs(p[2] - bg[2]) < 12) continue;
      head.push_back(p);
      lum.push_back(0.3 * p[0] + 0.59 * p[1] + 0.11 * p[2]);
    }
  REQUIRE(head.size() > 1000);
  std::vector<double> sorted = lum;
  std::nth_element(sorted.begin(), sorted.begin() + long(sorted.size() / 2), sorted.end());
  const double median = sorted[sorted.size() / 2];
  SkinMarks m;
  for (size_t i = 0; i < head.size(); ++i) {
    m.dark += lum[i] < 0.5 * median;
    m.red += head[i][0] > 1.6 * head[i][1] && head[i][0] > 90;
  }
  m.dark /= double(head.size());
  m.red /= double(head.size());
  return m;
}

}  // namespace

// scripts/demo's photos: the synthetic person's skin (brows, lips) on the
// head, so the textured sample shows what texturing does; the faint "skin"
// field has neither.
TEST_CASE("likeness texture --make-synthetic --field person: brows and lips show in the photos", "[texture][cli]") {
  LK_REQUIRE_LIKENESS();
  const std::string dir = lk::test::scratch_dir("texture_cli_person");
  const std::string err = dir + "/err.txt", size = " --photo-width 600 --photo-height 400";
  REQUIRE(run("--head generic --make-synthetic " + dir + "/person --field person" + size, err) == 0);
  REQUIRE(run("--head generic --make-synthetic " + dir + "/skin --field skin" + size, err) == 0);
  const SkinMarks person = skin_marks(dir + "/person/photo0.png"), skin = skin_marks(dir + "/skin/photo0.png");
  INFO("person: dark " << person.dark << ", red " << person.red << "; skin: dark " << skin.dark << ", red " << skin.red);
  CHECK(person.dark > 0.003);
  CHECK(person.red > 0.003);
  CHECK(skin.dark < 0.0005);
  CHECK(skin.red < 0.0005);
  // A head without the generic head's topology cannot carry the person.
  write(dir + "/tri.obj", "v 0 0 0\nv 0.1 0 0\nv 0 0.1 0\nf 1 2 3\n");
  CHECK(run("--head " + dir + "/tri.obj --make-synthetic " + dir + "/tri --field person", err) == 1);
  CHECK(read_file_text(err).find("generic head's topology") != std::string::npos);
}
