// Teeth texture (Tarini et al. 2002, Sec. 4.2) on a synthetic smile: white
// blocks (with a left-to-right brightness gradient) separated by dark gaps,
// on red gums.
#include <catch2/catch.hpp>

#include <cmath>

#include "io/io.h"
#include "project/parts.h"
#include "teeth/teeth.h"
#include "test_data.h"

namespace {

struct Smile {
  lk::Image image;
  std::vector<lk::TeethClass> truth;
};

Smile make_smile(int w = 300, int h = 120) {
  Smile s;
  s.image = lk::Image::make(w, h, 3);
  s.truth.assign(static_cast<size_t>(w) * h, lk::TeethClass::Gum);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      double c[3] = {0.78, 0.30, 0.30};  // gums
      // A little texture on the gums.
      c[0] += 0.03 * std::sin(x * 0.7 + y * 0.3);
      lk::TeethClass k = lk::TeethClass::Gum;
      if (y >= 30 && y < 90) {
        const int cell = x % 40;
        if (cell < 4) { c[0] = c[1] = c[2] = 0.05; k = lk::TeethClass::Void; }
        else if (x >= 10 && x < w - 10) {
          const double b = 0.60 + 0.35 * x / w;  // uneven lighting
          c[0] = b; c[1] = 0.96 * b; c[2] = 0.85 * b;
          k = lk::TeethClass::Tooth;
        }
      }
      for (int j = 0; j < 3; ++j) s.image.at(x, y)[j] = static_cast<std::uint8_t>(std::lround(std::clamp(c[j], 0.0, 1.0) * 255));
      s.truth[static_cast<size_t>(y) * w + x] = k;
    }
  return s;
}

double luma(const std::uint8_t* p) { return (0.299 * p[0] + 0.587 * p[1] + 0.114 * p[2]) / 255.0; }

}  // namespace

TEST_CASE("teeth: synthetic smile is classified, and voids transparent, gums recoloured") {
  const Smile s = make_smile();
  lk::TeethResult r;
  const lk::TeethOptions o;
  REQUIRE(lk::teeth_texture_from_photo(s.image, o, r).ok());
  size_t wrong = 0;
  for (size_t i = 0; i < s.truth.size(); ++i) wrong += r.classes[i] != s.truth[i];
  INFO("void threshold " << r.void_threshold << ", gum threshold " << r.gum_threshold << ", misclassified " << wrong);
  CHECK(wrong < s.truth.size() / 100);
  const int w = s.image.width;
  for (size_t i = 0; i < s.truth.size(); ++i) {
    const int x = static_cast<int>(i % w), y = static_cast<int>(i / w);
    if (s.truth[i] == lk::TeethClass::Void && r.classes[i] == lk::TeethClass::Void) CHECK(r.texture.at(x, y)[3] == 0);
  }
  // A gum pixel carries the standard gum colour's hue (green == blue, red dominant).
  const std::uint8_t* g = r.texture.at(150, 5);
  CHECK(g[3] == 255);
  CHECK(std::abs(g[0] / 255.0 - o.gum_color[0] * (g[1] / 255.0) / o.gum_color[1]) < 0.06);
}

TEST_CASE("teeth: six-stripe equalization removes the left/right brightness gradient") {
  const Smile s = make_smile();
  lk::TeethResult r;
  REQUIRE(lk::teeth_texture_from_photo(s.image, {}, r).ok());
  // Tooth pixels near the left and right ends.
  const int y = 60;
  const double before = luma(s.image.at(275, y)) - luma(s.image.at(25, y));
  const double after = luma(r.texture.at(275, y)) - luma(r.texture.at(25, y));
  INFO("right-left brightness before " << before << ", after " << after);
  CHECK(before > 0.25);
  CHECK(std::abs(after) < before / 4);
  // Teeth brightness moves to the target.
  CHECK(std::abs(luma(r.texture.at(150, y)) - 0.82) < 0.06);
}

TEST_CASE("teeth: bad input gives clear errors") {
  lk::TeethResult r;
  CHECK(lk::teeth_texture_from_photo(lk::Image{}, {}, r).code == lk::ErrorCode::InvalidInput);
  CHECK(lk::teeth_texture_from_photo(lk::Image::make(50, 50, 1, 200), {}, r).code == lk::ErrorCode::InvalidInput);
  // All gums: no teeth.
  lk::Image red = lk::Image::make(80, 60, 3);
  for (int y = 0; y < 60; ++y)
    for (int x = 0; x < 80; ++x) { red.at(x, y)[0] = static_cast<std::uint8_t>(190 + x % 20); red.at(x, y)[1] = 70; red.at(x, y)[2] = 75; }
  const lk::Status s = lk::teeth_texture_from_photo(red, {}, r);
  CHECK(s.code == lk::ErrorCode::NotAHead);
  CHECK(s.message.find("no teeth") != std::string::npos);
}

TEST_CASE("teeth: real intraoral photo gives a texture with teeth kept") {
  LK_REQUIRE_SHARED("teeth_photos/intraoral_anterior_0-4.png");
  lk::Image im;
  REQUIRE(lk::load_image_file(lk::test::shared_data_dir() + "/teeth_photos/intraoral_anterior_0-4.png", im, 3).ok());
  lk::TeethResult r;
  const lk::Status s = lk::teeth_texture_from_photo(im, {}, r);
  INFO(s.message);
  REQUIRE(s.ok());
  // The central incisors (around the photo centre, a little above) are teeth.
  CHECK(r.classes[static_cast<size_t>(im.height * 48 / 100) * im.width + im.width / 2 - im.width / 20] == lk::TeethClass::Tooth);
}

TEST_CASE("teeth: composite into the generic texture along a curved boundary") {
  const Smile s = make_smile();
  lk::TeethResult r;
  const lk::TeethOptions o;
  REQUIRE(lk::teeth_texture_from_photo(s.image, o, r).ok());
  lk::TeethCompositeOptions co;
  lk::Image tex;
  std::vector<float> mask;
  REQUIRE(lk::teeth_composite_generic(r, o, co, tex, &mask).ok());
  REQUIRE(tex.width == co.width);
  REQUIRE(tex.channels == 4);
  // Centre: the photo; far left/right: generic.
  CHECK(mask[static_cast<size_t>(co.height / 2) * co.width + co.width / 2] == 1.0f);
  CHECK(mask[static_cast<size_t>(co.height / 2) * co.width + 5] == 0.0f);
  // The boundary is curved: the photo spans fewer columns near the top than at the bite line.
  auto span = [&](int y) {
    int n = 0;
    for (int x = 0; x < co.width; ++x) n += mask[static_cast<size_t>(y) * co.width + x] > 0.5f;
    return n;
  };
  CHECK(span(co.height / 2) > span(co.height / 20) + co.width / 20);
  // Generic side teeth carry the teeth target colour (recoloured), near the bite line.
  bool found = false;
  for (int x = 10; x < co.width / 5 && !found; ++x) {
    const std::uint8_t* p = tex.at(x, co.height / 2 - 10);
    found = p[3] == 255 && std::abs(p[0] / 255.0 - r.target_color[0]) < 0.2 && std::abs(p[2] / 255.0 - r.target_color[2]) < 0.2 &&
            p[0] > 150;
  }
  CHECK(found);
  lk::TeethResult empty;
  CHECK_FALSE(lk::teeth_composite_generic(empty, o, co, tex).ok());
}

TEST_CASE("teeth: portraits and a closed mouth are refused as smile photos, and intraoral photos are taken", "[shared]") {
  // Issue 36, class 9: a whole portrait exited 0 with the photo recoloured.
  const std::string dir = lk::test::shared_data_dir() + "/multiview_faces/keentools_kira/";
  LK_REQUIRE_SHARED("multiview_faces/keentools_kira/0001.jpg");
  for (const char* name : {"0001.jpg", "0002.jpg", "0003.jpg", "0004.jpg", "0005.jpg", "0006.jpg", "0007.jpg",
                           "0008.jpg", "0009.jpg", "0010.jpg"}) {
    lk::Image im;
    REQUIRE(lk::load_image_file(dir + name, im, 3).ok());
    lk::TeethResult r;
    const lk::Status s = lk::teeth_photo_texture(im, {}, r);
    INFO(name << ": " << s.message);
    CHECK(s.code == lk::ErrorCode::NotAHead);
    CHECK(s.message.find("no open mouth in close-up") != std::string::npos);
  }
  // The closed mouth of 0001, cut out: no teeth.
  lk::Image face;
  REQUIRE(lk::load_image_file(dir + "0001.jpg", face, 3).ok());
  lk::Image mouth = lk::Image::make(230, 130, 3);
  for (int y = 0; y < 130; ++y)
    for (int x = 0; x < 230; ++x)
      for (int k = 0; k < 3; ++k) mouth.at(x, y)[k] = face.at(800 + x, 790 + y)[k];
  lk::TeethResult r;
  CHECK(lk::teeth_photo_texture(mouth, {}, r).code == lk::ErrorCode::NotAHead);
  for (const char* name : {"intraoral_anterior_0-4.png", "intraoral_anterior_1-4.png"}) {
    LK_REQUIRE_SHARED(std::string("teeth_photos/") + name);
    lk::Image im;
    REQUIRE(lk::load_image_file(lk::test::shared_data_dir() + "/teeth_photos/" + name, im, 3).ok());
    const lk::Status s = lk::teeth_photo_texture(im, {}, r);
    INFO(name << ": " << s.message);
    CHECK(s.ok());
  }
}
