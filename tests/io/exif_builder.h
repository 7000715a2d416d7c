// Crafted EXIF blocks for the tests and the fuzzers' seeds: a TIFF block
// (header, IFD0, the Exif IFD, out-of-line values; either byte order) and a
// minimal JPEG carrying it in an APP1 segment, and the tags of a real camera.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

namespace lk::exif_test {

using Bytes = std::vector<std::uint8_t>;

struct Field {
  std::uint16_t tag, type;
  std::uint32_t count;
  Bytes value;  // already in the block's byte order
};

// Lays out a TIFF block: header, IFD0, the Exif IFD, then out-of-line values.
struct TiffBuilder {
  bool big = false;
  std::vector<Field> ifd0, exif;

  Bytes u16(std::uint32_t v) const {
    return big ? Bytes{std::uint8_t(v >> 8), std::uint8_t(v)} : Bytes{std::uint8_t(v), std::uint8_t(v >> 8)};
  }
  Bytes u32(std::uint32_t v) const {
    return big ? Bytes{std::uint8_t(v >> 24), std::uint8_t(v >> 16), std::uint8_t(v >> 8), std::uint8_t(v)}
               : Bytes{std::uint8_t(v), std::uint8_t(v >> 8), std::uint8_t(v >> 16), std::uint8_t(v >> 24)};
  }
  Field shrt(std::uint16_t tag, std::uint32_t v) const { return {tag, 3, 1, u16(v)}; }
  Field lng(std::uint16_t tag, std::uint32_t v) const { return {tag, 4, 1, u32(v)}; }
  Field rational(std::uint16_t tag, std::uint32_t n, std::uint32_t d) const {
    Bytes b = u32(n), e = u32(d);
    b.insert(b.end(), e.begin(), e.end());
    return {tag, 5, 1, b};
  }
  Field ascii(std::uint16_t tag, const std::string& s) const {
    Bytes b(s.begin(), s.end());
    b.push_back(0);
    return {tag, 2, std::uint32_t(b.size()), b};
  }

  Bytes build() const {
    Bytes out = big ? Bytes{'M', 'M'} : Bytes{'I', 'I'};
    auto put = [&](const Bytes& b) { out.insert(out.end(), b.begin(), b.end()); };
    put(u16(42));
    put(u32(8));
    const std::uint32_t ifd0_at = 8, ifd0_size = 2 + 12 * std::uint32_t(ifd0.size() + 1) + 4;
    const std::uint32_t exif_at = ifd0_at + ifd0_size, exif_size = 2 + 12 * std::uint32_t(exif.size()) + 4;
    std::uint32_t data_at = exif_at + exif_size;
    Bytes data;
    auto directory = [&](std::vector<Field> fields) {
      put(u16(std::uint32_t(fields.size())));
      for (const Field& f : fields) {
        put(u16(f.tag));
        put(u16(f.type));
        put(u32(f.count));
        if (f.value.size() <= 4) {
          Bytes v = f.value;
          v.resize(4, 0);
          put(v);
        } else {
          put(u32(data_at + std::uint32_t(data.size())));
          data.insert(data.end(), f.value.begin(), f.value.end());
        }
      }
      put(u32(0));  // no next IFD
    };
    std::vector<Field> first = ifd0;
    first.push_back(lng(0x8769, exif_at));
    directory(first);
    directory(exif);
    put(data);
    return out;
  }
};

inline Bytes jpeg_with(const Bytes& tiff, bool with_exif = true) {
  Bytes j = {0xFF, 0xD8};
  const Bytes jfif = {0xFF, 0xE0, 0x00, 0x10, 'J', 'F', 'I', 'F', 0, 1, 1, 0, 0, 1, 0, 1, 0, 0};
  j.insert(j.end(), jfif.begin(), jfif.end());
  if (with_exif) {
    const size_t len = 2 + 6 + tiff.size();
    j.push_back(0xFF);
    j.push_back(0xE1);
    j.push_back(std::uint8_t(len >> 8));
    j.push_back(std::uint8_t(len));
    const char* hdr = "Exif\0\0";
    j.insert(j.end(), hdr, hdr + 6);
    j.insert(j.end(), tiff.begin(), tiff.end());
  }
  const Bytes rest = {0xFF, 0xDB, 0x00, 0x04, 0x00, 0x00, 0xFF, 0xDA, 0x00, 0x02, 0x12, 0x34, 0xFF, 0xD9};
  j.insert(j.end(), rest.begin(), rest.end());
  return j;
}

// A Canon-like APS-C body: 50 mm, 6000x4000 sensor pixels over 23.6 mm,
// focal-plane resolution in pixels per inch; 35-mm equivalent 80 mm.
inline TiffBuilder camera_tags(bool big) {
  TiffBuilder t;
  t.big = big;
  t.ifd0 = {t.ascii(0x010F, "Canon"), t.ascii(0x0110, "Canon EOS 80D"), t.shrt(0x0112, 1)};
  t.exif = {t.rational(0x920A, 50, 1), t.shrt(0xA405, 80), t.rational(0xA20E, 6000 * 254, 236),
            t.rational(0xA20F, 4000 * 254, 236), t.shrt(0xA210, 2), t.lng(0xA002, 6000), t.lng(0xA003, 4000)};
  return t;
}

}  // namespace lk::exif_test
