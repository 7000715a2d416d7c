// EXIF focal tags from crafted JPEGs (both byte orders), the focal in pixels
// each rule gives, and malformed bytes: every truncation, random byte
// mutations, a directory loop. The real Kira photos carry no EXIF.
#include "io/exif.h"
#include "exif_builder.h"
#include "test_data.h"

#include "common/prng.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

using namespace lk;
using namespace lk::exif_test;

TEST_CASE("EXIF focal tags are read in both byte orders", "[io][exif]") {
  for (bool big : {false, true}) {
    INFO("big endian " << big);
    const Bytes jpeg = jpeg_with(camera_tags(big).build());
    ExifInfo e;
    REQUIRE(read_jpeg_exif(jpeg.data(), jpeg.size(), e).ok());
    CHECK(e.present);
    CHECK(e.make == "Canon");
    CHECK(e.model == "Canon EOS 80D");
    CHECK(e.orientation == 1);
    CHECK(e.focal_length_mm == 50.0);
    CHECK(e.focal_length_35mm == 80);
    CHECK(e.focal_plane_x_resolution == Approx(6000 * 254 / 236.0));
    CHECK(e.focal_plane_resolution_unit == 2);
    CHECK(e.pixel_x_dimension == 6000);
    CHECK(e.pixel_y_dimension == 4000);
    // Downscaled to 1800x1200 (as the Kira photos are): 50 mm over a 23.6 mm
    // wide sensor of 1800 px is 3813.6 px.
    std::string source;
    CHECK(exif_focal_pixels(e, 1800, 1200, 0, &source) == Approx(50 / 23.6 * 1800).epsilon(1e-9));
    CHECK(source == "FocalLength and FocalPlaneXResolution");
    // Portrait photo of the same camera: the same focal in pixels.
    CHECK(exif_focal_pixels(e, 1200, 1800) == Approx(50 / 23.6 * 1800).epsilon(1e-9));
    CHECK(exif_focal_pixels(e, 1800, 1200, 22.3, &source) == Approx(50 / 22.3 * 1800));
    CHECK(source == "FocalLength and the given sensor width");
    // Without the focal-plane tags: the 35-mm equivalent over the diagonal.
    e.focal_plane_x_resolution = 0;
    CHECK(exif_focal_pixels(e, 1800, 1200, 0, &source) == Approx(80 / 43.2666 * std::hypot(1800.0, 1200.0)));
    CHECK(source == "FocalLengthIn35mmFilm");
    e.focal_length_35mm = 0;
    CHECK(exif_focal_pixels(e, 1800, 1200) == 0);
  }
}

TEST_CASE("a JPEG without EXIF, and bytes that are not a JPEG", "[io][exif]") {
  const Bytes plain = jpeg_with({}, false);
  ExifInfo e;
  REQUIRE(read_jpeg_exif(plain.data(), plain.size(), e).ok());
  CHECK_FALSE(e.present);
  CHECK(exif_focal_pixels(e, 1800, 1200) == 0);
  const std::string png = "\x89PNG\r\n\x1a\n0000";
  Status s = read_jpeg_exif(reinterpret_cast<const std::uint8_t*>(png.data()), png.size(), e);
  CHECK(s.code == ErrorCode::InvalidInput);
  CHECK(s.message.find("not a JPEG") != std::string::npos);
  CHECK(read_jpeg_exif(nullptr, 0, e).code == ErrorCode::InvalidInput);
}

TEST_CASE("truncated, mutated and looping EXIF gives errors, never a crash", "[io][exif]") {
  const Bytes good = jpeg_with(camera_tags(false).build());
  const size_t exif_end = good.size() - 14;  // before the DQT/SOS/EOI tail
  // Every prefix that cuts the APP1 segment must be refused.
  for (size_t n = 0; n < exif_end; ++n) {
    ExifInfo e;
    const Status s = read_jpeg_exif(good.data(), n, e);
    INFO("prefix " << n);
    CHECK_FALSE(s.ok());
  }
  // Random single- and multi-byte mutations: any status, sane values.
  SplitMix64 rng(7);
  int failures = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    Bytes b = good;
    const int flips = 1 + int(rng.next() % 4);
    for (int k = 0; k < flips; ++k) b[rng.next() % b.size()] = std::uint8_t(rng.next());
    ExifInfo e;
    failures += !read_jpeg_exif(b.data(), b.size(), e).ok();
    CHECK(e.focal_length_35mm >= 0);
    CHECK(std::isfinite(exif_focal_pixels(e, 1800, 1200)));
  }
  CHECK(failures > 0);
  // The Exif IFD pointer aimed back at IFD0.
  TiffBuilder t = camera_tags(true);
  Bytes tiff = t.build();
  // IFD0's last entry is the Exif pointer: its value (4 bytes) ends 4 bytes
  // before IFD0's next-IFD offset.
  const size_t pointer_value = 8 + 2 + 12 * t.ifd0.size() + 8;
  tiff[pointer_value] = 0; tiff[pointer_value + 1] = 0; tiff[pointer_value + 2] = 0; tiff[pointer_value + 3] = 8;
  const Bytes looping = jpeg_with(tiff);
  ExifInfo e;
  const Status s = read_jpeg_exif(looping.data(), looping.size(), e);
  CHECK(s.code == ErrorCode::InvalidInput);
  CHECK(s.message.find("loop") != std::string::npos);
}

// fuzz_exif's first finding (tests/fuzz/regressions/exif/): an orientation
// or resolution unit stored as a LONG past INT_MAX was converted to int,
// undefined behaviour; such a tag now reads as absent.
TEST_CASE("integer tags too large for an int read as absent", "[io][exif]") {
  for (bool big : {false, true}) {
    TiffBuilder t = camera_tags(big);
    t.ifd0.back() = t.lng(0x0112, 3774873600u);
    t.exif.push_back(t.lng(0xA210, 4000000000u));
    t.exif.erase(t.exif.begin() + 4);  // the SHORT resolution unit
    const Bytes jpeg = jpeg_with(t.build());
    ExifInfo e;
    REQUIRE(read_jpeg_exif(jpeg.data(), jpeg.size(), e).ok());
    CHECK(e.orientation == 0);
    CHECK(e.focal_plane_resolution_unit == 0);
    CHECK(e.focal_length_mm == 50.0);  // the rest as before
  }
}

TEST_CASE("the Kira photos carry no EXIF (the known focal comes from the tutorial)", "[io][exif]") {
  LK_REQUIRE_SHARED("multiview_faces/keentools_kira/0001.jpg");
  for (const char* name : {"0001.jpg", "0002.jpg", "0009.jpg"}) {
    std::ifstream in(lk::test::shared_data_dir() + "/multiview_faces/keentools_kira/" + name, std::ios::binary);
    const Bytes b((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    ExifInfo e;
    REQUIRE(read_jpeg_exif(b.data(), b.size(), e).ok());
    CHECK_FALSE(e.present);
  }
}
