// likeness synth-photos + likeness photos end to end, and their refusals.
#include "image/image.h"
#include "io/io.h"
#include "test_data.h"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <sys/wait.h>

namespace {

using lk::test::read_file_text;
int run(const std::string& args, const std::string& err = "/dev/null") { return lk::test::run_likeness(args, err); }

}  // namespace

TEST_CASE("likeness photos makes a head and cameras from a synthetic session's landmark files", "[photos][cli]") {
  LK_REQUIRE_LIKENESS();
  const std::string dir = lk::test::scratch_dir("photos_cli");
  REQUIRE(run("synth-photos --seed 2 --cameras 6 --no-render --out " + dir + "/s") == 0);
  std::string points;
  for (int i = 0; i < 6; ++i) points += " " + dir + "/s/view_0" + std::to_string(i) + ".json";
  REQUIRE(run("photos --points" + points + " --map " + dir + "/s/map.json --levels 1 --out " + dir + "/out") == 0);
  CHECK(read_file_text(dir + "/out/control.obj").size() > 1000);
  CHECK(read_file_text(dir + "/out/level1.obj").size() > read_file_text(dir + "/out/control.obj").size());
  const auto cams = nlohmann::json::parse(read_file_text(dir + "/out/cameras.json"));
  const auto truth = nlohmann::json::parse(read_file_text(dir + "/s/truth.json"));
  REQUIRE(cams["photos"].size() == 6);
  CHECK(std::abs(cams["focal_px"].get<double>() - truth["focal_px"].get<double>()) < 0.05 * truth["focal_px"].get<double>());
  for (const auto& p : cams["photos"]) CHECK(p["used"] == true);

  // Refusals: without --map the MediaPipe map that ships with the head is
  // used, and these synthetic points (another detector's) are refused; a
  // broken points file (named, left out); the map for another head.
  const std::string err = dir + "/err.txt";
  CHECK(run("photos --points" + points + " --out " + dir + "/o2", err) == 1);
  CHECK(read_file_text(err).find("the map is for 'mediapipe-face-mesh'") != std::string::npos);
  {
    FILE* f = std::fopen((dir + "/broken.json").c_str(), "w");
    REQUIRE(f);
    std::fputs("{\"format\":\"likeness-landmarks\",\"version\":1}", f);
    std::fclose(f);
  }
  const std::string log = dir + "/log.txt";
  CHECK(std::system(("'" + std::string(LK_BIN_DIR) + "/likeness' photos --points" + points + " " + dir +
                     "/broken.json --map " + dir + "/s/map.json --levels 0 --out " + dir + "/o3 > " + log + " 2>&1")
                        .c_str()) == 0);
  CHECK(read_file_text(log).find("broken.json: detector") != std::string::npos);
  CHECK(run("photos --points" + points + " --map " + dir + "/s/view_00.json --out " + dir + "/o4", err) == 1);
  CHECK(read_file_text(err).find("format") != std::string::npos);
  CHECK(run("photos --points" + points + " --map " + dir + "/s/map.json --photos a.jpg --out " + dir + "/o5", err) == 1);
  CHECK(read_file_text(err).find("one points file per photo") != std::string::npos);
}

// With --photos the skin comes from the recovered cameras: the synthetic
// photos show a skin-coloured head (red above blue) on a blue-grey
// background (blue above red); texels sampled through wrong cameras would
// land on the background.
TEST_CASE("likeness photos --photos textures the head from the recovered cameras", "[photos][cli]") {
  LK_REQUIRE_LIKENESS();
  const std::string dir = lk::test::scratch_dir("photos_cli_texture");
  REQUIRE(run("synth-photos --seed 4 --cameras 5 --out " + dir + "/s") == 0);
  std::string points, photos;
  for (int i = 0; i < 5; ++i) {
    points += " " + dir + "/s/view_0" + std::to_string(i) + ".json";
    photos += " " + dir + "/s/view_0" + std::to_string(i) + ".png";
  }
  REQUIRE(run("photos --points" + points + " --photos" + photos + " --map " + dir +
              "/s/map.json --levels 1 --texture-size 256 --stereo --out " + dir + "/out") == 0);
  CHECK(read_file_text(dir + "/out/textured.obj").find("mtllib textured.mtl") != std::string::npos);
  lk::Image skin;
  REQUIRE(lk::load_image_file(dir + "/out/skin.png", skin, 3));
  REQUIRE(skin.width == 256);
  long colored = 0, skin_like = 0;
  for (size_t p = 0; p + 2 < skin.pixels.size(); p += 3) {
    const int r = skin.pixels[p], b = skin.pixels[p + 2];
    if (r + skin.pixels[p + 1] + b < 30) continue;  // outside the chart
    ++colored;
    skin_like += r > b + 10;
  }
  std::printf("skin texels: %ld of %ld coloured texels red above blue\n", skin_like, colored);
  REQUIRE(colored > 10000);
  CHECK(skin_like > 0.9 * colored);
  // --stereo, five views 45 deg apart: no stereo pair, said so in the report.
  const std::string report = read_file_text(dir + "/out/report.json");
  CHECK(report.find("stereo: no two used photos see the head from 10-40 deg apart") != std::string::npos);
  // The head project beside it, and the GLB for avatar tools from the folder.
  REQUIRE(lk::test::exists(dir + "/out/head.likeness.glb"));
  REQUIRE(run("export --head " + dir + "/out --out " + dir + "/head.glb --level 1") == 0);
  const std::string glb = read_file_text(dir + "/head.glb");
  REQUIRE(glb.size() > 100000);
  CHECK(glb.compare(0, 4, "glTF") == 0);
  CHECK(glb.find("\"jawOpen\"") != std::string::npos);  // the muscle layer's shapes as morph targets
  CHECK(glb.find("\"image/png\"") != std::string::npos);   // the skin (and the eyes' and teeth's textures)
  CHECK(glb.find("\"Talk\"") != std::string::npos);      // the talking demo as a glTF animation (on by default)
  // The head's own eye and teeth textures beside its project (eye.png,
  // teeth.png, as `likeness eye --out` and `likeness teeth --generic-out`
  // write them) go into the GLB in place of the generic ones, pixel for pixel,
  // where the project keeps none from the photos. synth-photos draws the
  // eyes (synth/synthetic_eyes.h), so the iris found in them is kept and
  // the folder's eye.png does not replace it; the teeth stand in.
  {
    lk::Image photos_eye;
    REQUIRE(lk::load_image_file(dir + "/out/eye.png", photos_eye, 3));
    lk::Image eye = lk::Image::make(48, 40, 3), teeth = lk::Image::make(64, 32, 4);
    for (int y = 0; y < eye.height; ++y)
      for (int x = 0; x < eye.width; ++x)
        for (int k = 0; k < 3; ++k) eye.at(x, y)[k] = static_cast<std::uint8_t>((x * 5 + y * 3 + 70 * k) % 251);
    for (int y = 0; y < teeth.height; ++y)
      for (int x = 0; x < teeth.width; ++x)
        for (int k = 0; k < 4; ++k) teeth.at(x, y)[k] = static_cast<std::uint8_t>(k == 3 ? (x % 7 ? 255 : 0) : (x * 3 + y * 9 + 50 * k) % 256);
    REQUIRE(lk::save_png_file(dir + "/out/eye.png", eye).ok());
    REQUIRE(lk::save_png_file(dir + "/out/teeth.png", teeth).ok());
    REQUIRE(run("export --head " + dir + "/out --out " + dir + "/own.glb --level 0 --no-animations") == 0);
    const std::string own = read_file_text(dir + "/own.glb");
    CHECK(own.find("\"Talk\"") == std::string::npos);
    // The GLB's JSON chunk and its binary chunk; each image's PNG decoded.
    REQUIRE(own.size() > 28);
    auto u32 = [&](size_t at) { std::uint32_t v; std::memcpy(&v, own.data() + at, 4); return static_cast<size_t>(v); };
    const size_t json_len = u32(12);
    const auto gltf = nlohmann::json::parse(own.substr(20, json_len));
    const size_t bin = 20 + json_len + 8;
    std::map<std::string, lk::Image> images;
    for (const auto& im : gltf["images"]) {
      const auto& view = gltf["bufferViews"][im["bufferView"].get<size_t>()];
      const size_t at = bin + view.value("byteOffset", size_t(0)), len = view["byteLength"].get<size_t>();
      REQUIRE(at + len <= own.size());
      lk::Image decoded;
      REQUIRE(lk::read_image(reinterpret_cast<const std::uint8_t*>(own.data() + at), len, decoded).ok());
      images[im.value("name", std::string())] = decoded;
    }
    REQUIRE(images.count("eye"));
    REQUIRE(images.count("teeth"));
    CHECK(images["eye"].width == photos_eye.width);
    CHECK(images["eye"].width != eye.width);
    CHECK(images["teeth"].channels == 4);
    CHECK(images["teeth"].pixels == teeth.pixels);
    // A texture given that cannot be read: refused, no file.
    CHECK(run("export --head " + dir + "/out --out " + dir + "/bad.glb --eye-texture " + dir + "/none.png") != 0);
    CHECK_FALSE(lk::test::exists(dir + "/bad.glb"));
    std::remove((dir + "/out/eye.png").c_str());
    std::remove((dir + "/out/teeth.png").c_str());
  }
  // A folder with no project: a message, no file.
  CHECK(run("export --head " + dir + "/s --out " + dir + "/none.glb") != 0);
  CHECK_FALSE(lk::test::exists(dir + "/none.glb"));
  // --no-texture: no skin; no --stereo: none tried (off by default).
  REQUIRE(run("photos --points" + points + " --photos" + photos + " --map " + dir +
              "/s/map.json --levels 1 --no-texture --out " + dir + "/out2") == 0);
  CHECK_FALSE(lk::test::exists(dir + "/out2/skin.png"));
  CHECK(read_file_text(dir + "/out2/report.json").find("no two used photos") == std::string::npos);
}

// --masks: each photo's mask gives its outline (silhouettes); a mask of the
// wrong size costs that photo its outline, not the photo.
TEST_CASE("likeness photos --masks fits the outlines and names a bad mask", "[photos][cli]") {
  LK_REQUIRE_LIKENESS();
  const std::string dir = lk::test::scratch_dir("photos_cli_masks");
  REQUIRE(run("synth-photos --seed 2 --cameras 6 --out " + dir + "/s") == 0);
  std::string points, masks;
  for (int i = 0; i < 6; ++i) {
    points += " " + dir + "/s/view_0" + std::to_string(i) + ".json";
    masks += " " + dir + "/s/" + (i == 3 ? "small.png" : "mask_0" + std::to_string(i) + ".png");
  }
  lk::Image small = lk::Image::make(64, 48, 1, 0);
  for (int y = 10; y < 40; ++y)
    for (int x = 10; x < 50; ++x) small.at(x, y)[0] = 255;
  REQUIRE(lk::save_png_file(dir + "/s/small.png", small));
  const std::string log = dir + "/log.txt";
  CHECK(std::system(("'" + std::string(LK_BIN_DIR) + "/likeness' photos --points" + points + " --masks" + masks +
                     " --map " + dir + "/s/map.json --levels 0 --out " + dir + "/out > " + log + " 2>&1")
                        .c_str()) == 0);
  CHECK(read_file_text(log).find("small.png: mask is 64x48, its photo is 1200x1600 (its outline not used)") !=
        std::string::npos);
  const auto rep = nlohmann::json::parse(read_file_text(dir + "/out/report.json"));
  CHECK(rep["photos_used"] == 6);
  REQUIRE(rep.contains("silhouettes"));
  const auto d = rep["silhouettes"]["rim_to_outline_mean_px"];
  std::printf("--masks: rim to outline %.2f -> %.2f px\n", d[0].get<double>(), d[1].get<double>());
  CHECK(d[1].get<double>() < 0.5 * d[0].get<double>());
  const std::string err = dir + "/err.txt";
  CHECK(run("photos --points" + points + " --masks " + dir + "/s/mask_00.png --map " + dir + "/s/map.json --out " +
                dir + "/o2", err) == 1);
  CHECK(read_file_text(err).find("give one mask per photo") != std::string::npos);
}

// --iris-photo NAME (the page's face photo set to "Eye (iris)", issue 37) on
// Kira's nine landmark files and photos (../shared/data, skipped where
// absent): the iris is looked for in 0003.jpg alone, so the report line and
// eye.png come from it, not from 0001.jpg, the most frontal eye the search
// picks when no photo is named. A name among none of the photos is refused
// before the fit, with the name and exit code 1.
TEST_CASE("likeness photos --iris-photo takes the iris from the named photo of Kira", "[photos][cli][shared][kira]") {
  LK_REQUIRE_LIKENESS();
  LK_REQUIRE_SHARED("multiview_faces/keentools_kira/0001.jpg");
  const std::string dir = lk::test::scratch_dir("photos_cli_iris_photo");
  std::string points = " --points", jpgs = " --photos";
  for (const char* n : {"0001", "0002", "0003", "0004", "0006", "0007", "0008", "0009", "0010"}) {
    points += " " + lk::test::source_dir() + "/tests/photos/data/kira/" + n + ".json";
    jpgs += " " + lk::test::shared_data_dir() + "/multiview_faces/keentools_kira/" + n + ".jpg";
  }
  const std::string inputs = points + jpgs;
  // stdout (the report) and stderr kept; the exit code returned.
  auto photos = [&](const std::string& extra, const std::string& out) {
    const int rc = std::system(("'" + std::string(LK_BIN_DIR) + "/likeness' photos" + inputs + extra + " --out " + dir + "/" +
                                out + " > " + dir + "/" + out + ".log 2> " + dir + "/" + out + ".err")
                                   .c_str());
    return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
  };

  CHECK(photos(" --iris-photo 0042", "unknown") == 1);
  CHECK(read_file_text(dir + "/unknown.err").find("--iris-photo 0042: no photo of that name among the 9 given") !=
        std::string::npos);
  CHECK_FALSE(lk::test::exists(dir + "/unknown/eye.png"));

  REQUIRE(photos(" --iris-photo 0003 --texture-size 256", "marked") == 0);
  REQUIRE(photos(" --texture-size 256", "frontal") == 0);
  const std::string marked = read_file_text(dir + "/marked.log"), frontal = read_file_text(dir + "/frontal.log");
  INFO(marked);
  INFO(frontal);
  CHECK(marked.find("eyes: the iris from 0003.jpg's right eye") != std::string::npos);
  CHECK(frontal.find("eyes: the iris from 0001.jpg's left eye") != std::string::npos);
  lk::Image eye_marked, eye_frontal;
  REQUIRE(lk::load_image_file(dir + "/marked/eye.png", eye_marked, 3));
  REQUIRE(lk::load_image_file(dir + "/frontal/eye.png", eye_frontal, 3));
  REQUIRE(eye_marked.pixels.size() == eye_frontal.pixels.size());
  // Another photo's iris, not 0001.jpg's again: the textures differ (by
  // the mean over all texels, most of which are the same generic white).
  double diff = 0;
  for (size_t i = 0; i < eye_marked.pixels.size(); ++i) diff += std::abs(eye_marked.pixels[i] - eye_frontal.pixels[i]);
  diff /= double(eye_marked.pixels.size());
  std::printf("eye.png from 0003.jpg against from 0001.jpg: mean |difference| %.2f levels\n", diff);
  CHECK(diff > 3);  // 12.0 measured; 0.0 when the name is ignored
}
