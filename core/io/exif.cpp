// EXIF focal-length tags from a JPEG's APP1 segment (see exif.h).
#include "io/exif.h"

#include <algorithm>
#include <cmath>
#include <set>

namespace lk {
namespace {

// Bounds-checked reads from the TIFF block of the APP1 segment.
struct Tiff {
  const std::uint8_t* data = nullptr;
  size_t size = 0;
  bool big_endian = false;

  bool has(size_t offset, size_t count) const { return offset <= size && count <= size - offset; }
  std::uint32_t u16(size_t o) const {
    return big_endian ? (std::uint32_t(data[o]) << 8 | data[o + 1]) : (std::uint32_t(data[o + 1]) << 8 | data[o]);
  }
  std::uint32_t u32(size_t o) const {
    return big_endian ? (std::uint32_t(data[o]) << 24 | std::uint32_t(data[o + 1]) << 16 |
                         std::uint32_t(data[o + 2]) << 8 | data[o + 3])
                      : (std::uint32_t(data[o + 3]) << 24 | std::uint32_t(data[o + 2]) << 16 |
                         std::uint32_t(data[o + 1]) << 8 | data[o]);
  }
};

// TIFF field types we read: 2 ASCII, 3 SHORT, 4 LONG, 5 RATIONAL, 10 SRATIONAL.
size_t type_size(std::uint32_t type) {
  switch (type) {
    case 1: case 2: case 6: case 7: return 1;
    case 3: case 8: return 2;
    case 4: case 9: case 11: return 4;
    case 5: case 10: case 12: return 8;
    default: return 0;
  }
}

struct Entry {
  std::uint32_t tag = 0, type = 0, count = 0;
  size_t value = 0;  // offset of the value bytes in the TIFF block
};

Status entry_at(const Tiff& t, size_t at, Entry& e) {
  e.tag = t.u16(at);
  e.type = t.u16(at + 2);
  e.count = t.u32(at + 4);
  // Count first: on wasm size_t is 32 bits and count * 8 could wrap.
  if (type_size(e.type) != 0 && e.count > t.size)
    return Status::error(ErrorCode::Truncated, "EXIF tag " + std::to_string(e.tag) + " declares more values than the segment holds");
  const size_t bytes = type_size(e.type) * size_t(e.count);
  // Values of 4 bytes or fewer sit in the entry itself, others at an offset.
  e.value = bytes <= 4 ? at + 8 : t.u32(at + 8);
  if (type_size(e.type) != 0 && !t.has(e.value, bytes))
    return Status::error(ErrorCode::Truncated, "EXIF tag " + std::to_string(e.tag) + " points past the end of the segment");
  return Status::success();
}

// One numeric value (SHORT/LONG/RATIONAL); NaN for other types or 0 denominators.
double number(const Tiff& t, const Entry& e) {
  if (e.count < 1) return std::nan("");
  switch (e.type) {
    case 3: return t.u16(e.value);
    case 4: return t.u32(e.value);
    case 5: {
      const std::uint32_t d = t.u32(e.value + 4);
      return d ? double(t.u32(e.value)) / d : std::nan("");
    }
    case 10: {
      const auto n = std::int32_t(t.u32(e.value)), d = std::int32_t(t.u32(e.value + 4));
      return d ? double(n) / d : std::nan("");
    }
    default: return std::nan("");
  }
}

std::string text(const Tiff& t, const Entry& e) {
  if (e.type != 2) return {};
  std::string s(reinterpret_cast<const char*>(t.data + e.value), e.count);
  s = s.substr(0, s.find('\0'));
  while (!s.empty() && s.back() == ' ') s.pop_back();
  return s;
}

Status read_ifd(const Tiff& t, size_t offset, ExifInfo& out, std::set<size_t>& visited, int depth) {
  if (depth > 2) return Status::success();  // IFD0 -> Exif IFD is all we follow
  if (!visited.insert(offset).second)
    return Status::error(ErrorCode::InvalidInput, "the EXIF directories form a loop");
  if (!t.has(offset, 2)) return Status::error(ErrorCode::Truncated, "an EXIF directory starts past the end of the segment");
  const std::uint32_t n = t.u16(offset);
  if (!t.has(offset + 2, size_t(n) * 12))
    return Status::error(ErrorCode::Truncated, "an EXIF directory of " + std::to_string(n) +
                                                   " entries runs past the end of the segment");
  for (std::uint32_t i = 0; i < n; ++i) {
    Entry e;
    Status s = entry_at(t, offset + 2 + size_t(i) * 12, e);
    if (!s) return s;
    if (type_size(e.type) == 0) continue;  // unknown type: skip, as TIFF readers must
    const double v = number(t, e);
    const bool ok = std::isfinite(v) && v >= 0;
    switch (e.tag) {
      case 0x010F: out.make = text(t, e); break;
      case 0x0110: out.model = text(t, e); break;
      case 0x0112: if (ok && v < 1e6) out.orientation = int(v); break;  // (a LONG can exceed int)
      case 0x920A: if (ok) out.focal_length_mm = v; break;
      case 0xA405: if (ok && v < 1e5) out.focal_length_35mm = int(v); break;
      case 0xA20E: if (ok) out.focal_plane_x_resolution = v; break;
      case 0xA20F: if (ok) out.focal_plane_y_resolution = v; break;
      case 0xA210: if (ok && v < 1e6) out.focal_plane_resolution_unit = int(v); break;
      case 0xA002: if (ok && v < 1e6) out.pixel_x_dimension = int(v); break;
      case 0xA003: if (ok && v < 1e6) out.pixel_y_dimension = int(v); break;
      case 0x8769:  // the Exif sub-IFD
        if ((e.type == 4 || e.type == 3) && e.count == 1) {
          s = read_ifd(t, size_t(e.type == 4 ? t.u32(e.value) : t.u16(e.value)), out, visited, depth + 1);
          if (!s) return s;
        }
        break;
      default: break;
    }
  }
  return Status::success();
}

Status read_exif_segment(const std::uint8_t* seg, size_t size, ExifInfo& out) {
  // "Exif\0\0" then the TIFF header: byte order, 42, offset of IFD0.
  Tiff t;
  t.data = seg + 6;
  t.size = size - 6;
  if (t.size < 8) return Status::error(ErrorCode::Truncated, "the EXIF segment ends inside its TIFF header");
  if (t.data[0] == 'M' && t.data[1] == 'M') t.big_endian = true;
  else if (!(t.data[0] == 'I' && t.data[1] == 'I'))
    return Status::error(ErrorCode::InvalidInput, "the EXIF segment has no TIFF byte-order mark (II or MM)");
  if (t.u16(2) != 42) return Status::error(ErrorCode::InvalidInput, "the EXIF segment's TIFF header lacks the number 42");
  out.present = true;
  std::set<size_t> visited;
  return read_ifd(t, t.u32(4), out, visited, 1);
}

}  // namespace

Status read_jpeg_exif(const std::uint8_t* data, size_t size, ExifInfo& out) {
  out = ExifInfo{};
  if (!data || size < 4 || data[0] != 0xFF || data[1] != 0xD8)
    return Status::error(ErrorCode::InvalidInput, "not a JPEG (no start-of-image marker)");
  size_t at = 2;
  while (at + 4 <= size) {
    if (data[at] != 0xFF) return Status::error(ErrorCode::InvalidInput, "JPEG marker expected at byte " + std::to_string(at));
    const std::uint8_t marker = data[at + 1];
    if (marker == 0xFF) { ++at; continue; }  // fill byte
    if (marker == 0xDA || marker == 0xD9) return Status::success();  // image data / end: no EXIF before it
    if (marker == 0x01 || (marker >= 0xD0 && marker <= 0xD7)) { at += 2; continue; }  // no length
    const size_t length = size_t(data[at + 2]) << 8 | data[at + 3];
    if (length < 2) return Status::error(ErrorCode::InvalidInput, "JPEG segment with a length below 2");
    if (length > size - at - 2) return Status::error(ErrorCode::Truncated, "a JPEG segment runs past the end of the data");
    const std::uint8_t* seg = data + at + 4;
    const size_t seg_size = length - 2;
    if (marker == 0xE1 && seg_size >= 6 && std::equal(seg, seg + 6, "Exif\0\0")) return read_exif_segment(seg, seg_size, out);
    at += 2 + length;
  }
  return Status::error(ErrorCode::Truncated, "the JPEG ends before its image data");
}

double exif_focal_pixels(const ExifInfo& e, int width, int height, double sensor_width_mm, std::string* source) {
  if (source) source->clear();
  if (width <= 0 || height <= 0) return 0;
  const double long_side = std::max(width, height);
  if (sensor_width_mm > 0 && e.focal_length_mm > 0) {
    if (source) *source = "FocalLength and the given sensor width";
    return e.focal_length_mm / sensor_width_mm * long_side;
  }
  double unit_mm = 0;
  switch (e.focal_plane_resolution_unit) {
    case 0: case 2: unit_mm = 25.4; break;  // inch, the TIFF default
    case 3: unit_mm = 10; break;
    case 4: unit_mm = 1; break;
    case 5: unit_mm = 1e-3; break;
    default: break;
  }
  if (e.focal_length_mm > 0 && e.focal_plane_x_resolution > 0 && unit_mm > 0) {
    double f = e.focal_length_mm * e.focal_plane_x_resolution / unit_mm;
    const int tagged_long = std::max(e.pixel_x_dimension, e.pixel_y_dimension);
    if (tagged_long > 0) f *= long_side / tagged_long;
    if (source) *source = "FocalLength and FocalPlaneXResolution";
    return f;
  }
  if (e.focal_length_35mm > 0) {
    if (source) *source = "FocalLengthIn35mmFilm";
    return e.focal_length_35mm / 43.2666 * std::hypot(double(width), double(height));
  }
  return 0;
}

}  // namespace lk
