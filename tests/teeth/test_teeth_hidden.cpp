// Hidden tooth parts (Tarini et al. 2002, Sec. 4.2: "we expand teeth into
// those parts of the gums that have been covered by the lips"). Ground truth:
// a synthetic smile of eight upper and eight lower teeth (arched crown tops,
// a yellower band near the gums, dark interdental gaps and a dark bite line)
// rendered twice: with the lips clear of the teeth, and with the upper lip
// dipping over the left teeth and the lower lip rising over the right ones.
// The texture from the occluded smile is compared, in the band the lips hid,
// with the texture from the clear one.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdlib>
#include <string>

#include "io/io.h"
#include "teeth/synthetic_smile.h"
#include "teeth/teeth.h"
#include "test_data.h"

namespace {

using lk::SyntheticSmile;

SyntheticSmile make_occluded_smile(double upper_dip, double lower_rise) {
  lk::SyntheticSmileOptions o;
  o.upper_dip = upper_dip;
  o.lower_rise = lower_rise;
  return lk::make_synthetic_smile(o);
}

struct BandError {
  int hidden = 0;            // truth tooth pixels under the lips (the band)
  int recovered = 0;         // of those, reconstructed as tooth
  int false_fill = 0;        // reconstructed pixels that are truly gum/lip
  double colour_error = 0;   // mean |RGB difference| (0..255) in the band vs the clear smile's texture
};

BandError band_error(const SyntheticSmile& occluded, const lk::TeethResult& r, const lk::TeethResult& clear) {
  BandError e;
  const int w = occluded.image.width;
  for (size_t i = 0; i < occluded.tooth.size(); ++i) {
    const int x = static_cast<int>(i % w), y = static_cast<int>(i / w);
    if (r.reconstructed.size() == occluded.tooth.size() && r.reconstructed[i] && !occluded.tooth[i] &&
        r.classes[i] == lk::TeethClass::Tooth)
      ++e.false_fill;
    if (!(occluded.tooth[i] && occluded.lip[i])) continue;
    ++e.hidden;
    e.recovered += r.classes[i] == lk::TeethClass::Tooth;
    double d = 0;
    for (int k = 0; k < 3; ++k) d += std::abs(r.texture.at(x, y)[k] - clear.texture.at(x, y)[k]);
    e.colour_error += d / 3;
  }
  if (e.hidden) e.colour_error /= e.hidden;
  return e;
}

}  // namespace

TEST_CASE("teeth: parts hidden by the lips are reconstructed from each tooth's visible pixels", "[teeth][hidden]") {
  const SyntheticSmile clear = make_occluded_smile(0, 0);
  const SyntheticSmile occluded = make_occluded_smile(40, 34);
  lk::TeethOptions with, without;
  without.reconstruct_hidden = false;
  lk::TeethResult r_clear, r_with, r_without;
  REQUIRE(lk::teeth_texture_from_photo(clear.image, with, r_clear).ok());
  // The clear smile has nothing hidden: nothing may be invented.
  CHECK(r_clear.reconstructed_pixels < 100);
  CHECK(std::abs(r_clear.bite_row - 80) <= 2);
  REQUIRE(lk::teeth_texture_from_photo(occluded.image, with, r_with).ok());
  REQUIRE(lk::teeth_texture_from_photo(occluded.image, without, r_without).ok());
  CHECK(std::abs(r_with.bite_row - 80) <= 2);
  if (const char* dump = std::getenv("LK_TEETH_DUMP")) {  // for looking at the case
    (void)lk::save_png_file(std::string(dump) + "/smile_clear.png", clear.image);
    (void)lk::save_png_file(std::string(dump) + "/smile_occluded.png", occluded.image);
    (void)lk::save_png_file(std::string(dump) + "/tex_clear.png", r_clear.texture);
    (void)lk::save_png_file(std::string(dump) + "/tex_with.png", r_with.texture);
    (void)lk::save_png_file(std::string(dump) + "/tex_without.png", r_without.texture);
  }
  const BandError a = band_error(occluded, r_with, r_clear), b = band_error(occluded, r_without, r_clear);
  WARN("hidden band " << a.hidden << " px: reconstructed " << a.recovered << " as tooth ("
       << 100.0 * a.recovered / a.hidden << " %), " << a.false_fill << " px filled outside the truth; colour error "
       << a.colour_error << " (0..255) vs " << b.colour_error << " without reconstruction");
  REQUIRE(a.hidden > 1500);
  CHECK(b.recovered == 0);
  // Measured: 70.4 % of the band recovered, 0 px outside the truth, colour
  // error 25.3 vs 73.6 without. What is missed: the lower lateral, hidden
  // across its whole width, gets 0.85 x its neighbours' height (31 of 38
  // rows); the fill colour is constant, so the yellower cervical band is not
  // reproduced. Bounds with margin:
  CHECK(a.recovered > 0.65 * a.hidden);
  CHECK(a.false_fill < 0.05 * a.hidden);
  CHECK(a.colour_error < 0.45 * b.colour_error);
  CHECK(a.colour_error < 30);
}

TEST_CASE("teeth: hidden-part reconstruction leaves gaps as gaps and stays inside the image", "[teeth][hidden]") {
  // Tiny and degenerate inputs: no crash, nothing outside the buffers.
  lk::TeethOptions o;
  std::vector<lk::TeethClass> classes(6, lk::TeethClass::Tooth);
  std::vector<float> rgb(18, 0.9f);
  std::vector<std::uint8_t> filled;
  CHECK(lk::reconstruct_hidden_teeth(1, 6, o, classes, rgb, filled) == 0);
  // A column whose visible end is an interdental gap stays a gap (void).
  const int w = 40, h = 40;
  classes.assign(static_cast<size_t>(w) * h, lk::TeethClass::Gum);
  rgb.assign(static_cast<size_t>(w) * h * 3, 0.5f);
  for (int x = 5; x < 35; ++x)
    for (int y = 5; y < 20; ++y) {
      // Tooth A (columns 5..19) fully visible up to row 5; column 20 a gap;
      // tooth B (21..34) visible up to row 5 at 30..34, the lip hides its
      // rows above 12 at 21..29.
      const bool hidden = x >= 21 && x < 30 && y < 12;
      if (!hidden) classes[static_cast<size_t>(y) * w + x] = x == 20 ? lk::TeethClass::Void : lk::TeethClass::Tooth;
    }
  o.max_tooth_width = 1;
  o.bite_row = 19;
  o.crown_arc = 0;
  CHECK(lk::reconstruct_hidden_teeth(w, h, o, classes, rgb, filled) == 19);
  CHECK(classes[static_cast<size_t>(8) * w + 25] == lk::TeethClass::Tooth);  // filled up to the tallest column
  CHECK(filled[static_cast<size_t>(8) * w + 25] == 1);
  CHECK(classes[static_cast<size_t>(8) * w + 20] == lk::TeethClass::Void);    // the gap stays a gap
  CHECK(classes[static_cast<size_t>(2) * w + 25] == lk::TeethClass::Gum);     // not beyond the outline
}

TEST_CASE("teeth: an intraoral photo (retracted lips, gums visible) gets little invented", "[teeth][hidden]") {
  // Nothing is hidden by lips in these photos: every reconstructed pixel is
  // invented. Measured: 11.7k (photo 0) and 17.9k (photo 1) pixels, 1.6 % and
  // 2.8 % of the teeth, at premolars whose visible gum line is flat.
  for (const char* name : {"teeth_photos/intraoral_anterior_0-4.png", "teeth_photos/intraoral_anterior_1-4.png"}) {
    LK_REQUIRE_SHARED(name);
    lk::Image im;
    REQUIRE(lk::load_image_file(lk::test::shared_data_dir() + "/" + name, im, 3).ok());
    lk::TeethResult r;
    REQUIRE(lk::teeth_texture_from_photo(im, {}, r).ok());
    INFO(name << ": " << r.reconstructed_pixels << " px reconstructed, " << r.teeth_pixels << " teeth px");
    CHECK(r.reconstructed_pixels < 0.04 * r.teeth_pixels);
  }
}
