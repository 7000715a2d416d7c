// Untrusted photos (issue 36, classes 5 and 6): minimal reproducers made
// here, byte by byte. Before the guard in core/io/image_io.cpp each of these
// reached stb_image unchecked: a heap over-read (16-bit PGM named .jpg), a
// write past an array inside stbi_info (Huffman counts over 256), PNM header
// overflow, and tiny files decoding into 8192x8192 images of filler.
#include "io/io.h"
#include "io_test_util.h"
#include "test_data.h"

#include <catch2/catch.hpp>

#include <stb/stb_image_write.h>

#include <string>

using namespace lk;
using lk::test::require_error;

namespace {

Bytes bytes(const std::string& s) { return Bytes(s.begin(), s.end()); }

void append(void* context, void* data, int size) {
  Bytes* out = static_cast<Bytes*>(context);
  out->insert(out->end(), static_cast<std::uint8_t*>(data), static_cast<std::uint8_t*>(data) + size);
}

// A w x h JPEG of four flat quadrants (red, green / blue, white).
Image quadrants(int w, int h) {
  Image im = Image::make(w, h, 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const int q = (y >= h / 2) * 2 + (x >= w / 2);
      const std::uint8_t colours[4][3] = {{255, 0, 0}, {0, 255, 0}, {0, 0, 255}, {255, 255, 255}};
      for (int c = 0; c < 3; ++c) im.at(x, y)[c] = colours[q][c];
    }
  return im;
}

Bytes jpeg_of(const Image& im) {
  Bytes out;
  stbi_write_jpg_to_func(append, &out, im.width, im.height, im.channels, im.pixels.data(), 95);
  return out;
}

// Offset of the first segment with this marker (after SOI), or 0.
size_t find_marker(const Bytes& jpg, std::uint8_t marker) {
  size_t i = 2;
  while (i + 4 <= jpg.size() && jpg[i] == 0xFF) {
    if (jpg[i + 1] == marker) return i;
    i += 2 + (size_t(jpg[i + 2]) << 8 | jpg[i + 3]);
  }
  return 0;
}

// An APP1 Exif segment (little-endian TIFF, one IFD0 entry: Orientation).
Bytes with_orientation(const Bytes& jpg, int orientation) {
  const Bytes app1 = {0xFF, 0xE1, 0x00, 0x22, 'E', 'x', 'i', 'f', 0, 0,            // marker, length 34, "Exif\0\0"
                      'I', 'I', 42, 0, 8, 0, 0, 0,                                // TIFF header, IFD0 at 8
                      1, 0,                                                       // one entry
                      0x12, 0x01, 3, 0, 1, 0, 0, 0, std::uint8_t(orientation), 0, 0, 0,  // 0x0112 SHORT 1
                      0, 0, 0, 0};                                                // no next IFD
  Bytes out;
  out.reserve(jpg.size() + app1.size());
  out.push_back(jpg[0]);  // SOI, then the segment, then the rest
  out.push_back(jpg[1]);
  for (std::uint8_t b : app1) out.push_back(b);
  for (size_t i = 2; i < jpg.size(); ++i) out.push_back(jpg[i]);
  return out;
}

}  // namespace

TEST_CASE("images other than JPEG and PNG are refused by name before any decoder runs", "[io][image][untrusted]") {
  Image im;
  // Class 5: a 16-bit PGM (stb 2.27 over-read the heap on it in eye/teeth).
  Bytes pgm = bytes("P5\n4 4\n65535\n");
  pgm.resize(pgm.size() + 32, 0x7F);
  require_error(read_image(pgm.data(), pgm.size(), im), ErrorCode::Unsupported,
                "this is a PGM image; Likeness reads JPEG and PNG");
  CHECK(im.empty());
  // Named photo.jpg on disk: the message starts with the path.
  const std::string path = lk::test::scratch_dir("io") + "/photo.jpg";
  REQUIRE(write_file(path, pgm).ok());
  const Status s = load_image_file(path, im, 3);
  CHECK(s.code == ErrorCode::Unsupported);
  CHECK(s.message == path + ": this is a PGM image; Likeness reads JPEG and PNG");
  // Class 5: a PNM header whose size overflows int arithmetic.
  const Bytes ppm = bytes("P6\n4294967295 4294967295\n255\n\x01\x02\x03");
  require_error(read_image(ppm.data(), ppm.size(), im), ErrorCode::Unsupported, "a PPM image");
  // Class 6: 18-60 byte HDR, GIF and TGA files that declared 8192x8192.
  const Bytes hdr = bytes("#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 8192 +X 8192\n\x02\x02\x20\x00");
  require_error(read_image(hdr.data(), hdr.size(), im), ErrorCode::Unsupported, "a Radiance HDR image");
  Bytes gif = bytes("GIF89a");
  for (int v : {0x00, 0x20, 0x00, 0x20, 0x80, 0, 0, 0, 0, 0, 0xFF, 0xFF, 0xFF, 0x2C, 0, 0, 0, 0, 0, 0x20, 0, 0x20, 0,
                2, 2, 0x44, 0x01, 0, 0x3B})
    gif.push_back(static_cast<std::uint8_t>(v));
  require_error(read_image(gif.data(), gif.size(), im), ErrorCode::Unsupported, "a GIF image");
  const Bytes tga = {0, 0, 10, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0x00, 0x20, 0x00, 0x20, 24, 0, 0xFF, 1, 2, 3};
  require_error(read_image(tga.data(), tga.size(), im), ErrorCode::Unsupported, "probably a TGA image");
  const Bytes bmp = {'B', 'M', 0x46, 0, 0, 0, 0, 0, 0, 0, 0x36, 0, 0, 0, 0x28, 0, 0, 0};
  require_error(read_image(bmp.data(), bmp.size(), im), ErrorCode::Unsupported, "a BMP image");
  const Bytes webp = bytes(std::string("RIFF\x10\0\0\0WEBPVP8 ", 16));
  require_error(read_image(webp.data(), webp.size(), im), ErrorCode::Unsupported, "a WebP image");
  CHECK(im.empty());
}

TEST_CASE("JPEG segments are checked before stb reads them", "[io][image][untrusted]") {
  Image im;
  // Class 5: the 10-byte JPEG whose DHT segment declares 65535 bytes and
  // Huffman counts of 255 (stbi_info wrote past its 257-entry array).
  const Bytes ten = {0xFF, 0xD8, 0xFF, 0xC4, 0xFF, 0xFF, 0x00, 0xFF, 0xFF, 0xFF};
  require_error(read_image(ten.data(), ten.size(), im), ErrorCode::Truncated, "truncated JPEG");
  // The same counts in a segment long enough to hold them: 300 codes.
  Bytes dht = {0xFF, 0xD8, 0xFF, 0xC4};
  const size_t length = 2 + 17 + 300;
  dht.push_back(std::uint8_t(length >> 8));
  dht.push_back(std::uint8_t(length & 255));
  dht.push_back(0x00);
  for (int b = 0; b < 16; ++b) dht.push_back(b < 2 ? 150 : 0);
  dht.resize(dht.size() + 300, 0x01);
  dht.push_back(0xFF);
  dht.push_back(0xD9);
  require_error(read_image(dht.data(), dht.size(), im), ErrorCode::InvalidInput,
                "a Huffman table declares 300 codes (at most 256)");

  const Bytes jpg = jpeg_of(quadrants(32, 16));
  REQUIRE(read_image(jpg.data(), jpg.size(), im).ok());
  const size_t sof = find_marker(jpg, 0xC0);
  REQUIRE(sof > 0);
  // Sampling factor 0 (stb divides by the largest), a 12-bit frame, and a
  // lossless frame type.
  Bytes bad = jpg;
  bad[sof + 11] = 0x01;
  require_error(read_image(bad.data(), bad.size(), im), ErrorCode::InvalidInput, "a sampling factor outside 1..4");
  bad = jpg;
  bad[sof + 4] = 12;
  require_error(read_image(bad.data(), bad.size(), im), ErrorCode::Unsupported, "12-bit JPEG");
  bad = jpg;
  bad[sof + 1] = 0xC3;
  require_error(read_image(bad.data(), bad.size(), im), ErrorCode::Unsupported, "lossless");
  // A scan decoding with Huffman tables no DHT defined (stb_image_write
  // defines 0 and 1): stb 2.27 decoded with uninitialized tables and read far
  // outside them (found by tests/fuzz/fuzz_image).
  const size_t sos = find_marker(jpg, 0xDA);
  REQUIRE(sos > 0);
  bad = jpg;
  bad[sos + 6] = 0x33;
  require_error(read_image(bad.data(), bad.size(), im), ErrorCode::InvalidInput, "never defined");
  // A baseline scan decodes its AC coefficients even when its header says
  // Se = 0: an undefined AC table is refused there too.
  bad = jpg;
  bad[sos + 6] = 0x03;
  bad[sos + 5 + 2 * size_t(jpg[sos + 4]) + 1] = 0;
  require_error(read_image(bad.data(), bad.size(), im), ErrorCode::InvalidInput, "never defined");
  // A segment length past the end of the data.
  bad = Bytes(jpg.begin(), jpg.begin() + sof + 6);
  require_error(read_image(bad.data(), bad.size(), im), ErrorCode::Truncated, "truncated JPEG");
  CHECK(im.empty());
}

TEST_CASE("decompression bombs: a size the bytes cannot hold is refused before decoding", "[io][image][untrusted]") {
  Image im;
  // Class 6: a 16x16 JPEG (a few hundred bytes) whose frame now declares
  // 8192x8192: stb decoded it into 64 Mpixel of grey and teeth exited 0.
  Bytes jpg = jpeg_of(quadrants(16, 16));
  REQUIRE(jpg.size() < 700);
  const size_t sof = find_marker(jpg, 0xC0);
  REQUIRE(sof > 0);
  for (size_t k : {sof + 5, sof + 7}) { jpg[k] = 0x20; jpg[k + 1] = 0x00; }
  require_error(read_image(jpg.data(), jpg.size(), im), ErrorCode::InvalidInput,
                "declares 8192x8192 pixels but holds only");
  CHECK(im.empty());
  // The same for a PNG: 8000x8000 RGB rows need at least 186 KB of deflate.
  Bytes png = write_png(quadrants(16, 16));
  REQUIRE(png.size() < 1000);
  for (size_t k : {size_t(16), size_t(20)}) { png[k] = 0; png[k + 1] = 0; png[k + 2] = 0x1F; png[k + 3] = 0x40; }
  require_error(read_image(png.data(), png.size(), im), ErrorCode::InvalidInput, "declares 8000x8000 pixels");
  // Over the pixel limit, refused from the header.
  require_error(read_image(png.data(), png.size(), im, 0, 1u << 20), ErrorCode::TooLarge, "over the limit");
  // A real, honest large image still decodes: 1024x1024 of flat colour.
  const Bytes flat = jpeg_of(Image::make(1024, 1024, 3, 128));
  INFO(flat.size() << " bytes");
  REQUIRE(read_image(flat.data(), flat.size(), im).ok());
  CHECK(im.width == 1024);
}

TEST_CASE("EXIF orientation is applied as a viewer shows the photo", "[io][image][untrusted]") {
  const Image src = quadrants(32, 16);  // red top-left, green top-right, blue bottom-left, white bottom-right
  const Bytes jpg = jpeg_of(src);
  auto colour_at = [](const Image& im, int x, int y) {
    const std::uint8_t* p = im.at(x, y);
    // 0 red, 1 green, 2 blue, 3 white
    if (p[0] > 200 && p[1] > 200 && p[2] > 200) return 3;
    if (p[0] > 200) return 0;
    if (p[1] > 200) return 1;
    return 2;
  };
  struct Case { int orientation, w, h, tl, tr, bl, br; };
  // The upright picture's corners for each EXIF orientation.
  for (const Case& c : {Case{1, 32, 16, 0, 1, 2, 3}, Case{3, 32, 16, 3, 2, 1, 0}, Case{6, 16, 32, 2, 0, 3, 1},
                        Case{8, 16, 32, 1, 3, 0, 2}, Case{2, 32, 16, 1, 0, 3, 2}}) {
    INFO("orientation " << c.orientation);
    const Bytes tagged = with_orientation(jpg, c.orientation);
    Image im;
    REQUIRE(read_image(tagged.data(), tagged.size(), im).ok());
    REQUIRE(im.width == c.w);
    REQUIRE(im.height == c.h);
    CHECK(colour_at(im, 2, 2) == c.tl);
    CHECK(colour_at(im, c.w - 3, 2) == c.tr);
    CHECK(colour_at(im, 2, c.h - 3) == c.bl);
    CHECK(colour_at(im, c.w - 3, c.h - 3) == c.br);
  }
}

TEST_CASE("inspect_image: the checks and the shown size without decoding", "[io][image][untrusted]") {
  const Bytes jpg = with_orientation(jpeg_of(quadrants(32, 16)), 6);
  ImageInfo info;
  REQUIRE(inspect_image(jpg.data(), jpg.size(), info).ok());
  CHECK(std::string(info.format) == "JPEG");
  CHECK(info.stored_width == 32);
  CHECK(info.stored_height == 16);
  CHECK(info.orientation == 6);
  CHECK(info.width == 16);
  CHECK(info.height == 32);
  const Bytes png = write_png(quadrants(8, 4));
  REQUIRE(inspect_image(png.data(), png.size(), info).ok());
  CHECK(std::string(info.format) == "PNG");
  CHECK(info.width == 8);
  CHECK(info.height == 4);
  CHECK(info.orientation == 1);
  require_error(inspect_image(jpg.data(), jpg.size() - 10, info), ErrorCode::Truncated, "truncated JPEG");
  Bytes pgm = bytes("P5\n4 4\n65535\n");
  pgm.resize(pgm.size() + 32, 0x7F);
  require_error(inspect_image(pgm.data(), pgm.size(), info), ErrorCode::Unsupported, "a PGM image");
}

TEST_CASE("a JPEG cut inside its image data and closed with an end marker is refused, not filled", "[io][image][untrusted]") {
  // stb_image (and browsers) decode such a file without complaint, filling
  // the missing blocks; read_image compares with its truncation probe.
  Image im = Image::make(64, 48, 3);
  for (int y = 0; y < 48; ++y)
    for (int x = 0; x < 64; ++x)
      for (int c = 0; c < 3; ++c) im.at(x, y)[c] = static_cast<std::uint8_t>((x * 5 + y * 3 + c * 70) % 256);
  const Bytes jpg = jpeg_of(im);
  Image back;
  REQUIRE(read_image(jpg.data(), jpg.size(), back).ok());
  const size_t sos = find_marker(jpg, 0xDA);
  REQUIRE(sos > 0);
  const size_t data = sos + 2 + (size_t(jpg[sos + 2]) << 8 | jpg[sos + 3]);
  Bytes cut(jpg.begin(), jpg.begin() + static_cast<std::ptrdiff_t>(data + (jpg.size() - 2 - data) / 2));
  if (cut.back() == 0xFF) cut.pop_back();
  cut.push_back(0xFF);
  cut.push_back(0xD9);
  require_error(read_image(cut.data(), cut.size(), back), ErrorCode::Truncated, "ends before its last blocks");
  Bytes probe;
  REQUIRE(jpeg_truncation_probe(jpg.data(), jpg.size(), probe).ok());
  CHECK(probe.size() == jpg.size() + 16);
  const Bytes png = write_png(im);
  REQUIRE(jpeg_truncation_probe(png.data(), png.size(), probe).ok());
  CHECK(probe.empty());
}

TEST_CASE("a progressive JPEG cut inside a scan is refused, and whole ones decode", "[io][image][untrusted][shared]") {
  LK_REQUIRE_SHARED("multiview_faces/keentools_kira/0001.jpg");
  Bytes jpg;
  REQUIRE(read_file(lk::test::shared_data_dir() + "/multiview_faces/keentools_kira/0001.jpg", jpg).ok());
  Image back;
  REQUIRE(read_image(jpg.data(), jpg.size(), back).ok());
  // Cut in the middle of the file (inside some scan's data), closed with EOI.
  Bytes cut(jpg.begin(), jpg.begin() + static_cast<std::ptrdiff_t>(jpg.size() / 2));
  while (cut.back() == 0xFF) cut.pop_back();
  cut.push_back(0xFF);
  cut.push_back(0xD9);
  require_error(read_image(cut.data(), cut.size(), back), ErrorCode::Truncated, "ends before its last blocks");
}

TEST_CASE("a PNG whose deflate stream is cut short, with its IEND kept, is refused", "[io][image][untrusted]") {
  Image im = Image::make(64, 48, 3);
  for (int y = 0; y < 48; ++y)
    for (int x = 0; x < 64; ++x)
      for (int c = 0; c < 3; ++c) im.at(x, y)[c] = static_cast<std::uint8_t>((x * 37 + y * 91 + c * 13) % 256);
  const Bytes png = write_png(im);
  // Find IDAT, halve its data, fix its length; the CRC is not checked.
  size_t at = 8;
  while (at + 8 <= png.size() && std::string(png.begin() + at + 4, png.begin() + at + 8) != "IDAT")
    at += 12 + (size_t(png[at]) << 24 | size_t(png[at + 1]) << 16 | size_t(png[at + 2]) << 8 | png[at + 3]);
  REQUIRE(at + 8 <= png.size());
  const size_t length = size_t(png[at]) << 24 | size_t(png[at + 1]) << 16 | size_t(png[at + 2]) << 8 | png[at + 3];
  const size_t keep = length / 2;
  Bytes cut(png.begin(), png.begin() + static_cast<std::ptrdiff_t>(at + 8 + keep));
  cut[at] = std::uint8_t(keep >> 24); cut[at + 1] = std::uint8_t(keep >> 16);
  cut[at + 2] = std::uint8_t(keep >> 8); cut[at + 3] = std::uint8_t(keep);
  cut.insert(cut.end(), png.begin() + static_cast<std::ptrdiff_t>(at + 8 + length), png.end());  // CRC, IEND
  Image back;
  const Status s = read_image(cut.data(), cut.size(), back);
  INFO(s.message);
  CHECK_FALSE(s.ok());
  CHECK(back.empty());
}
