#include "io/io.h"
#include "io_test_util.h"
#include "test_data.h"

#include <catch2/catch.hpp>

// Declarations only: the implementation is compiled once, in lk_io. The test
// uses stb's JPEG writer to make JPEGs without shipping any.
#include <stb/stb_image_write.h>

using namespace lk;
using lk::test::garbage_bytes;
using lk::test::require_error;

namespace {

Image gradient(int w, int h, int channels) {
  Image im = Image::make(w, h, channels);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < channels; ++c) im.at(x, y)[c] = static_cast<std::uint8_t>((x * 7 + y * 13 + c * 50) % 256);
  return im;
}

void append(void* context, void* data, int size) {
  Bytes* out = static_cast<Bytes*>(context);
  out->insert(out->end(), static_cast<std::uint8_t*>(data), static_cast<std::uint8_t*>(data) + size);
}

Bytes make_jpeg(const Image& im) {
  Bytes out;
  stbi_write_jpg_to_func(append, &out, im.width, im.height, im.channels, im.pixels.data(), 90);
  return out;
}

}  // namespace

TEST_CASE("PNG round trip for gray, RGB and RGBA is exact", "[io][image]") {
  for (int channels : {1, 3, 4}) {
    INFO(channels << " channels");
    const Image im = gradient(37, 23, channels);
    const Bytes png = write_png(im);
    REQUIRE(png.size() > 8);
    CHECK(png[1] == 'P');
    Image back;
    REQUIRE(read_image(png.data(), png.size(), back).ok());
    CHECK(back.width == 37);
    CHECK(back.height == 23);
    CHECK(back.channels == channels);
    CHECK(back.pixels == im.pixels);
  }
  // Asking for other channels converts (gray -> RGB replicates).
  const Image gray = gradient(4, 4, 1);
  const Bytes png = write_png(gray);
  Image rgb;
  REQUIRE(read_image(png.data(), png.size(), rgb, 3).ok());
  CHECK(rgb.channels == 3);
  CHECK(rgb.at(2, 3)[0] == gray.at(2, 3)[0]);
  CHECK(rgb.at(2, 3)[2] == gray.at(2, 3)[0]);
}

TEST_CASE("PNG reader: a 2x2 RGB file made byte by byte (zlib + CRC by hand)", "[io][image]") {
  // Rows: red, green / blue, (10,20,30).
  const Bytes png = {0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a, 0x00, 0x00, 0x00, 0x0d, 0x49, 0x48, 0x44, 0x52,
                     0x00, 0x00, 0x00, 0x02, 0x00, 0x00, 0x00, 0x02, 0x08, 0x02, 0x00, 0x00, 0x00, 0xfd, 0xd4, 0x9a,
                     0x73, 0x00, 0x00, 0x00, 0x13, 0x49, 0x44, 0x41, 0x54, 0x78, 0xda, 0x63, 0xf8, 0xcf, 0xc0, 0xc0,
                     0x00, 0xc2, 0x0c, 0xff, 0xb9, 0x44, 0xe4, 0x00, 0x1a, 0x58, 0x03, 0x3a, 0xe2, 0x92, 0x6e, 0xd9,
                     0x00, 0x00, 0x00, 0x00, 0x49, 0x45, 0x4e, 0x44, 0xae, 0x42, 0x60, 0x82};
  Image im;
  REQUIRE(read_image(png.data(), png.size(), im).ok());
  REQUIRE(im.width == 2);
  REQUIRE(im.height == 2);
  REQUIRE(im.channels == 3);
  CHECK(im.pixels == Bytes{255, 0, 0, 0, 255, 0, 0, 0, 255, 10, 20, 30});
  // Cut before IEND and inside IDAT: both refused.
  Image cut;
  CHECK_FALSE(read_image(png.data(), 50, cut).ok());
  CHECK(cut.empty());
}

TEST_CASE("write_png refuses inconsistent images by returning no bytes", "[io][image][errors]") {
  Image bad = Image::make(4, 4, 3);
  bad.pixels.resize(10);
  CHECK(write_png(bad).empty());
  CHECK(write_png(Image()).empty());
  Image five = Image::make(2, 2, 5);
  CHECK(write_png(five).empty());
}

TEST_CASE("JPEG: whole files decode, truncated ones are refused", "[io][image][errors]") {
  // A smooth picture, so JPEG's error stays small.
  Image im = Image::make(64, 48, 3);
  for (int y = 0; y < 48; ++y)
    for (int x = 0; x < 64; ++x)
      for (int c = 0; c < 3; ++c) im.at(x, y)[c] = static_cast<std::uint8_t>(2 * x + y + 20 * c);
  const Bytes jpg = make_jpeg(im);
  REQUIRE(jpg.size() > 100);
  Image back;
  REQUIRE(read_image(jpg.data(), jpg.size(), back).ok());
  CHECK(back.width == 64);
  CHECK(back.height == 48);
  int max_error = 0;
  double sum_error = 0;
  for (size_t i = 0; i < im.pixels.size(); ++i) {
    const int e = std::abs(im.pixels[i] - back.pixels[i]);
    max_error = std::max(max_error, e);
    sum_error += e;
  }
  CHECK(max_error < 16);  // lossy, but the same picture
  CHECK(sum_error / im.pixels.size() < 3);

  // Bytes after the end-of-image marker (camera trailers) are fine.
  Bytes trailer = jpg;
  for (char c : std::string("TRAILER DATA")) trailer.push_back(static_cast<std::uint8_t>(c));
  REQUIRE(read_image(trailer.data(), trailer.size(), back).ok());

  // stb would decode these, greying the missing rows; we refuse them.
  for (size_t keep : {jpg.size() / 2, jpg.size() - 2, jpg.size() - 1}) {
    INFO("kept " << keep << " of " << jpg.size() << " bytes");
    require_error(read_image(jpg.data(), keep, back), ErrorCode::Truncated, "truncated JPEG");
    CHECK(back.empty());
  }
}

TEST_CASE("read_image rejects non-images, empty and oversized input", "[io][image][errors]") {
  Image im;
  require_error(read_image(nullptr, 0, im), ErrorCode::Empty, "empty");
  const Bytes one = {0x89};
  require_error(read_image(one.data(), one.size(), im), ErrorCode::InvalidInput, "not an image");
  const std::string ply = "ply\nformat ascii 1.0\nelement vertex 1\n";
  require_error(read_image(reinterpret_cast<const std::uint8_t*>(ply.data()), ply.size(), im), ErrorCode::InvalidInput,
                "not an image");
  const Bytes garbage = garbage_bytes(300);
  require_error(read_image(garbage.data(), garbage.size(), im), ErrorCode::InvalidInput, "not an image");
  const Bytes png = write_png(gradient(100, 100, 3));
  require_error(read_image(png.data(), png.size(), im, 0, 5000), ErrorCode::TooLarge,
                "100x100, over the limit of 5000 pixels");
  require_error(read_image(png.data(), png.size(), im, 7), ErrorCode::InvalidInput, "want_channels");
  // A PNG cut in half.
  require_error(read_image(png.data(), png.size() / 2, im), ErrorCode::Truncated, "truncated PNG");
  CHECK(im.empty());
}

TEST_CASE("read_image: the real Kira photos and the james atlas", "[io][image][shared]") {
  LK_REQUIRE_SHARED("multiview_faces/keentools_kira/0001.jpg");
  for (const char* name : {"0001.jpg", "0004.jpg"}) {
    const std::string path = lk::test::shared_data_dir() + "/multiview_faces/keentools_kira/" + name;
    Image im;
    const Status s = load_image_file(path, im);
    INFO(s.message);
    REQUIRE(s.ok());
    CHECK(im.width == 1800);
    CHECK(im.height == 1200);
    CHECK(im.channels == 3);
    // A photo, not a blank: the pixel values spread.
    int lo = 255, hi = 0;
    for (size_t i = 0; i < im.pixels.size(); i += 97) {
      lo = std::min<int>(lo, im.pixels[i]);
      hi = std::max<int>(hi, im.pixels[i]);
    }
    CHECK(hi - lo > 150);

    // The same photo cut in half is refused, with the path in the message.
    Bytes bytes;
    REQUIRE(read_file(path, bytes).ok());
    const std::string half = lk::test::scratch_dir("io") + "/half_" + name;
    REQUIRE(write_file(half, bytes.data(), bytes.size() / 2).ok());
    Image cut;
    const Status c = load_image_file(half, cut);
    CHECK(c.code == ErrorCode::Truncated);
    CHECK(c.message.rfind(half + ": truncated JPEG", 0) == 0);
  }
  LK_REQUIRE_SHARED("head_scans/james_menpo3d/james.jpg");
  Image atlas;
  REQUIRE(load_image_file(lk::test::shared_data_dir() + "/head_scans/james_menpo3d/james.jpg", atlas).ok());
  CHECK(atlas.width == 2400);
  CHECK(atlas.height == 1600);
}
