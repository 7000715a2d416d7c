// Image decoding (stb_image) and PNG encoding (stb_image_write). This is the
// one translation unit of the project that compiles the stb implementations.
//
// stb_image is the decoder, but untrusted bytes never reach it unchecked
// (issue 36: Debian's 2.27 over-reads a 16-bit PGM, writes past an array in
// stbi_info on a JPEG with oversized Huffman counts, overflows PNM headers,
// and decodes tiny GIF/HDR/TGA/JPEG files into gigabytes of filler). So:
//  - stb is compiled with JPEG and PNG only; anything else is named by its
//    magic bytes and refused before stb sees it;
//  - our own bounded walk of the JPEG segments / PNG chunks checks every
//    length against the buffer, the tables stb trusts (DHT counts <= 256,
//    DQT and SOF layouts, SOS components), reads the declared size and
//    refuses it over the pixel limit or over what the bytes can hold
//    (see plausible_* below) before stb decodes anything;
//  - the decoded size must equal the declared one;
//  - a JPEG whose data ends before the end-of-image marker is refused (stb
//    would fill the missing rows with grey);
//  - EXIF orientation is applied, as browsers do when they show the photo.
#include "io/exif.h"
#include "io/io.h"

#include <algorithm>
#include <climits>
#include <cstdint>
#include <vector>
#include <cstring>
#include <string>

#include "io/stb_config.h"

#include <stb/stb_image.h>
#include <stb/stb_image_write.h>

namespace lk {

namespace {

constexpr const char* kReads = "; Likeness reads JPEG and PNG";

Status invalid(const std::string& what) { return Status::error(ErrorCode::InvalidInput, what); }
Status truncated(const std::string& what) { return Status::error(ErrorCode::Truncated, what); }

bool starts_with(const std::uint8_t* d, size_t n, const char* magic, size_t m) {
  return n >= m && std::memcmp(d, magic, m) == 0;
}

// The name of an image format we do not read, from its magic bytes; empty
// when the bytes are no image format we know.
std::string other_format_name(const std::uint8_t* d, size_t n) {
  if (starts_with(d, n, "GIF87a", 6) || starts_with(d, n, "GIF89a", 6)) return "a GIF image";
  if (starts_with(d, n, "BM", 2) && n >= 18) {  // and a known DIB header size
    const std::uint32_t dib = d[14] | std::uint32_t(d[15]) << 8 | std::uint32_t(d[16]) << 16 | std::uint32_t(d[17]) << 24;
    if (dib == 12 || dib == 40 || dib == 52 || dib == 56 || dib == 64 || dib == 108 || dib == 124) return "a BMP image";
  }
  if (n >= 3 && d[0] == 'P' && d[1] >= '1' && d[1] <= '7' && (d[2] == ' ' || d[2] == '\n' || d[2] == '\r' || d[2] == '\t')) {
    static const char* names[] = {"a PBM", "a PGM", "a PPM", "a PBM", "a PGM", "a PPM", "a PAM"};
    return std::string(names[d[1] - '1']) + " image";
  }
  if (starts_with(d, n, "8BPS", 4)) return "a Photoshop (PSD) image";
  if (starts_with(d, n, "#?RADIANCE", 10) || starts_with(d, n, "#?RGBE", 6)) return "a Radiance HDR image";
  if (starts_with(d, n, "\x53\x80\xF6\x34", 4)) return "a Softimage PIC image";
  if (starts_with(d, n, "II*\0", 4) || starts_with(d, n, "MM\0*", 4)) return "a TIFF image";
  if (n >= 12 && starts_with(d, n, "RIFF", 4) && std::memcmp(d + 8, "WEBP", 4) == 0) return "a WebP image";
  if (n >= 12 && std::memcmp(d + 4, "ftyp", 4) == 0) {
    const std::string brand(reinterpret_cast<const char*>(d + 8), 4);
    if (brand == "avif" || brand == "avis") return "an AVIF image";
    if (brand == "heic" || brand == "heix" || brand == "mif1" || brand == "msf1" || brand == "hevc") return "a HEIC image";
  }
  if (starts_with(d, n, "qoif", 4)) return "a QOI image";
  if (starts_with(d, n, "\xFF\x0A", 2) || starts_with(d, n, "\0\0\0\x0CJXL \r\n\x87\n", 12)) return "a JPEG XL image";
  if (starts_with(d, n, "\0\0\0\x0CjP  \r\n\x87\n", 12)) return "a JPEG 2000 image";
  if (starts_with(d, n, "\x76\x2F\x31\x01", 4)) return "an OpenEXR image";
  // TGA has no magic; its 18-byte header with a known image type and
  // pixel depth is the best guess (only for the message).
  if (n >= 18 && (d[2] == 1 || d[2] == 2 || d[2] == 3 || d[2] == 9 || d[2] == 10 || d[2] == 11) && d[1] <= 1 &&
      (d[16] == 8 || d[16] == 15 || d[16] == 16 || d[16] == 24 || d[16] == 32))
    return "probably a TGA image";
  return "";
}

std::uint32_t be16(const std::uint8_t* p) { return std::uint32_t(p[0]) << 8 | p[1]; }
std::uint32_t be32(const std::uint8_t* p) {
  return std::uint32_t(p[0]) << 24 | std::uint32_t(p[1]) << 16 | std::uint32_t(p[2]) << 8 | p[3];
}

// What the structural checks learn about a file.
struct Declared {
  int width = 0, height = 0;
  bool jpeg = false;
  std::vector<size_t> scan_ends;  // JPEG: where each scan's entropy-coded data ends
};

std::string at_byte(size_t i) { return " at byte " + std::to_string(i); }

std::string marker_name(std::uint8_t m) {
  static const char* hex = "0123456789ABCDEF";
  return std::string("FF") + hex[m >> 4] + hex[m & 15];
}

// Walks a JPEG from SOI to EOI. Every segment length must lie inside the
// buffer; the segments stb_image trusts are checked as stb reads them (so
// that, once this passes, stb only ever reads inside its own arrays):
//  DHT: class <= 1, table <= 3, the 16 code counts sum to at most 256 (stb's
//       arrays hold 256 symbols; more is the reported stbi_info overflow)
//       and the symbols fit in the segment;
//  DQT: precision 0/1, table <= 3, exact length;
//  SOF0/1/2: one frame, 8-bit, width and height > 0, 1, 3 or 4 components
//       with sampling factors 1..4 that divide the largest, tables <= 3;
//       other SOF types (lossless, arithmetic, hierarchical) are refused;
//  SOS: after SOF, 1..4 components named in the frame, exact length; its
//       entropy-coded data runs to the next marker other than RSTn / FF00;
//  DRI length 4; APPn and COM skipped; other markers refused (stb would).
// Bytes after EOI (camera trailers) are allowed.
Status check_jpeg(const std::uint8_t* d, size_t n, Declared& out, std::uint64_t& scan_bytes,
                  std::uint64_t& max_blocks) {
  const std::string corrupt = "corrupt JPEG: ";
  const std::string cut = "truncated JPEG: the data ends before the end-of-image marker";
  size_t i = 2;  // after SOI
  bool have_frame = false, have_scan = false, progressive = false;
  bool table_defined[2][4] = {{false, false, false, false}, {false, false, false, false}};  // [DC, AC][id]
  int components = 0;
  int comp_id[4] = {0, 0, 0, 0}, comp_h[4] = {0, 0, 0, 0}, comp_v[4] = {0, 0, 0, 0};
  scan_bytes = 0;
  for (;;) {
    if (i >= n) return truncated(cut);
    if (d[i] != 0xFF) return invalid(corrupt + "a marker was expected" + at_byte(i));
    while (i < n && d[i] == 0xFF) ++i;  // fill bytes before a marker
    if (i >= n) return truncated(cut);
    const std::uint8_t m = d[i++];
    if (m == 0xD9) break;  // EOI
    if (m == 0x00 || m == 0xD8 || m == 0x01 || (m >= 0xD0 && m <= 0xD7))
      return invalid(corrupt + "marker " + marker_name(m) + " out of place" + at_byte(i - 2));
    if (n - i < 2) return truncated(cut);
    const size_t length = be16(d + i);
    if (length < 2) return invalid(corrupt + "a segment length below 2" + at_byte(i));
    if (length > n - i) return truncated(cut);
    const std::uint8_t* s = d + i + 2;
    const size_t len = length - 2;
    if (m == 0xC0 || m == 0xC1 || m == 0xC2) {
      if (have_frame) return invalid(corrupt + "a second frame header");
      progressive = m == 0xC2;
      if (len < 6) return invalid(corrupt + "a short frame header");
      if (s[0] != 8) return Status::error(ErrorCode::Unsupported, "a " + std::to_string(s[0]) + "-bit JPEG; only 8-bit JPEGs are read");
      out.height = static_cast<int>(be16(s + 1));
      out.width = static_cast<int>(be16(s + 3));
      components = s[5];
      if (out.width == 0 || out.height == 0) return invalid(corrupt + "the frame declares no pixels (width or height 0)");
      if (components != 1 && components != 3 && components != 4)
        return invalid(corrupt + std::to_string(components) + " colour components (1, 3 or 4 are read)");
      if (len != 6 + 3 * size_t(components)) return invalid(corrupt + "the frame header's length does not match its components");
      int h_max = 1, v_max = 1;
      for (int c = 0; c < components; ++c) {
        comp_id[c] = s[6 + 3 * c];
        comp_h[c] = s[7 + 3 * c] >> 4;
        comp_v[c] = s[7 + 3 * c] & 15;
        if (comp_h[c] < 1 || comp_h[c] > 4 || comp_v[c] < 1 || comp_v[c] > 4)
          return invalid(corrupt + "a sampling factor outside 1..4");
        if (s[8 + 3 * c] > 3) return invalid(corrupt + "a quantization table number over 3");
        h_max = std::max(h_max, comp_h[c]);
        v_max = std::max(v_max, comp_v[c]);
      }
      max_blocks = 0;
      for (int c = 0; c < components; ++c) {
        if (h_max % comp_h[c] != 0 || v_max % comp_v[c] != 0)
          return invalid(corrupt + "sampling factors that do not divide the largest");
        const std::uint64_t cw = (std::uint64_t(out.width) * comp_h[c] + h_max - 1) / h_max;
        const std::uint64_t ch = (std::uint64_t(out.height) * comp_v[c] + v_max - 1) / v_max;
        max_blocks = std::max(max_blocks, ((cw + 7) / 8) * ((ch + 7) / 8));
      }
      have_frame = true;
    } else if ((m >= 0xC3 && m <= 0xCF) && m != 0xC4 && m != 0xC8 && m != 0xCC) {
      return Status::error(ErrorCode::Unsupported,
                           "a lossless, arithmetic-coded or hierarchical JPEG; only baseline and progressive JPEGs are read");
    } else if (m == 0xC4) {  // DHT
      size_t k = 0;
      while (k < len) {
        if (len - k < 17) return invalid(corrupt + "a Huffman table header runs past its segment");
        if ((s[k] >> 4) > 1 || (s[k] & 15) > 3) return invalid(corrupt + "a Huffman table with a bad class or number");
        table_defined[s[k] >> 4][s[k] & 15] = true;
        size_t symbols = 0;
        for (int b = 1; b <= 16; ++b) symbols += s[k + b];
        if (symbols > 256)
          return invalid(corrupt + "a Huffman table declares " + std::to_string(symbols) + " codes (at most 256)");
        k += 17;
        if (symbols > len - k) return invalid(corrupt + "a Huffman table's symbols run past its segment");
        k += symbols;
      }
    } else if (m == 0xDB) {  // DQT
      size_t k = 0;
      while (k < len) {
        const int precision = s[k] >> 4, table = s[k] & 15;
        if (precision > 1 || table > 3) return invalid(corrupt + "a quantization table with a bad precision or number");
        const size_t need = 1 + (precision ? 128 : 64);
        if (need > len - k) return invalid(corrupt + "a quantization table runs past its segment");
        k += need;
      }
    } else if (m == 0xDD) {  // DRI
      if (len != 2) return invalid(corrupt + "a restart interval segment of the wrong length");
    } else if (m == 0xDA) {  // SOS
      if (!have_frame) return invalid(corrupt + "image data before the frame header");
      if (len < 1) return invalid(corrupt + "an empty scan header");
      const int ns = s[0];
      if (ns < 1 || ns > 4 || ns > components || len != 4 + 2 * size_t(ns))
        return invalid(corrupt + "a scan header with a bad component count or length");
      for (int c = 0; c < ns; ++c) {
        bool known = false;
        for (int f = 0; f < components; ++f) known = known || comp_id[f] == s[1 + 2 * c];
        if (!known) return invalid(corrupt + "a scan names a component the frame does not have");
        if ((s[2 + 2 * c] >> 4) > 3 || (s[2 + 2 * c] & 15) > 3) return invalid(corrupt + "a scan names a bad Huffman table");
      }
      // The tables a scan decodes with must have been defined before it:
      // stb 2.27 does not clear its tables, and decodes with whatever memory
      // an undefined one holds (fuzzed: reads far outside the table).
      const int ss = s[1 + 2 * ns], se = s[2 + 2 * ns], ah = s[3 + 2 * ns] >> 4;
      // A baseline scan decodes with both tables whatever Ss/Se say; a
      // progressive one with the DC table (first DC scans) or the AC table.
      const bool uses_dc = !progressive || (ss == 0 && ah == 0), uses_ac = !progressive || se > 0;
      for (int c = 0; c < ns; ++c)
        if ((uses_dc && !table_defined[0][s[2 + 2 * c] >> 4]) || (uses_ac && !table_defined[1][s[2 + 2 * c] & 15]))
          return invalid(corrupt + "a scan decodes with a Huffman table that was never defined");
      // Entropy-coded data: up to a marker other than FF00 (stuffing) and RSTn.
      size_t k = i + length;
      const size_t begin = k;
      while (k + 1 < n && !(d[k] == 0xFF && d[k + 1] != 0x00 && !(d[k + 1] >= 0xD0 && d[k + 1] <= 0xD7))) ++k;
      if (k + 1 >= n) return truncated(cut);
      scan_bytes += k - begin;
      out.scan_ends.push_back(k);
      have_scan = true;
      i = k;
      continue;
    } else if ((m >= 0xE0 && m <= 0xEF) || m == 0xFE) {
      // APPn, COM: skipped.
    } else {
      return Status::error(ErrorCode::Unsupported, "a JPEG with marker " + marker_name(m) + ", which is not read");
    }
    i += length;
  }
  if (!have_frame) return invalid(corrupt + "no frame header (no image size)");
  if (!have_scan) return invalid(corrupt + "no image data");
  out.jpeg = true;
  return Status::success();
}

// Walks a PNG's chunks: IHDR first (13 bytes, size > 0, a valid bit depth
// and colour type pair, no unknown method), every chunk inside the buffer,
// PLTE before IDAT for palette images, IDAT present, IEND reached; unknown
// critical chunks are refused. idat_bytes and raw_bytes (the filtered rows
// the zlib stream must inflate to) are returned for the plausibility rule.
Status check_png(const std::uint8_t* d, size_t n, Declared& out, std::uint64_t& idat_bytes, std::uint64_t& raw_bytes) {
  const std::string corrupt = "corrupt PNG: ";
  const std::string cut = "truncated PNG: the data ends before the IEND chunk";
  size_t i = 8;
  bool have_header = false, have_palette = false;
  int colour = 0;
  idat_bytes = 0;
  for (;;) {
    if (n - i < 12) return truncated(cut);
    const std::uint32_t length = be32(d + i);
    if (length > 0x7FFFFFFFu) return invalid(corrupt + "a chunk length over 2^31" + at_byte(i));
    if (length > n - i - 12) return truncated(cut);
    const std::uint8_t* type = d + i + 4;
    const std::uint8_t* s = d + i + 8;
    for (int k = 0; k < 4; ++k)
      if (!((type[k] >= 'A' && type[k] <= 'Z') || (type[k] >= 'a' && type[k] <= 'z')))
        return invalid(corrupt + "a chunk type that is not four letters" + at_byte(i + 4));
    const std::string name(reinterpret_cast<const char*>(type), 4);
    if (!have_header && name != "IHDR") return invalid(corrupt + "the first chunk is not IHDR");
    if (name == "IHDR") {
      if (have_header) return invalid(corrupt + "a second IHDR chunk");
      if (length != 13) return invalid(corrupt + "an IHDR chunk of " + std::to_string(length) + " bytes (13 expected)");
      const std::uint32_t w = be32(s), h = be32(s + 4);
      const int depth = s[8];
      colour = s[9];
      if (w == 0 || h == 0) return invalid(corrupt + "the header declares no pixels (width or height 0)");
      if (w > 0x7FFFFFFFu || h > 0x7FFFFFFFu) return invalid(corrupt + "a width or height over 2^31");
      const bool depth_ok = (colour == 0 && (depth == 1 || depth == 2 || depth == 4 || depth == 8 || depth == 16)) ||
                            (colour == 3 && (depth == 1 || depth == 2 || depth == 4 || depth == 8)) ||
                            ((colour == 2 || colour == 4 || colour == 6) && (depth == 8 || depth == 16));
      if (!depth_ok) return invalid(corrupt + "colour type " + std::to_string(colour) + " with bit depth " + std::to_string(depth));
      if (s[10] != 0 || s[11] != 0 || s[12] > 1) return invalid(corrupt + "an unknown compression, filter or interlace method");
      out.width = static_cast<int>(std::min<std::uint32_t>(w, INT_MAX));
      out.height = static_cast<int>(std::min<std::uint32_t>(h, INT_MAX));
      const int samples = colour == 2 ? 3 : colour == 4 ? 2 : colour == 6 ? 4 : 1;
      const std::uint64_t row = (std::uint64_t(w) * samples * depth + 7) / 8;
      raw_bytes = std::uint64_t(h) * (1 + row);  // each row has a filter byte (interlacing adds a little)
      have_header = true;
    } else if (name == "PLTE") {
      have_palette = true;
    } else if (name == "IDAT") {
      if (colour == 3 && !have_palette) return invalid(corrupt + "a palette image without a palette before its data");
      idat_bytes += length;
    } else if (name == "IEND") {
      break;
    } else if (type[0] >= 'A' && type[0] <= 'Z') {
      return Status::error(ErrorCode::Unsupported, "a PNG with the unknown critical chunk " + name);
    }
    i += 12 + size_t(length);
  }
  if (idat_bytes == 0) return invalid(corrupt + "no image data (IDAT)");
  return Status::success();
}

// EXIF orientation (1..8) applied: the pixels as a viewer shows the photo.
Image oriented(const Image& in, int orientation) {
  if (orientation < 2 || orientation > 8) return in;
  const int w = in.width, h = in.height;
  const bool swap = orientation >= 5;
  Image out = Image::make(swap ? h : w, swap ? w : h, in.channels);
  for (int y = 0; y < out.height; ++y)
    for (int x = 0; x < out.width; ++x) {
      int sx = x, sy = y;
      switch (orientation) {
        case 2: sx = w - 1 - x; break;                    // mirrored
        case 3: sx = w - 1 - x; sy = h - 1 - y; break;    // rotated 180
        case 4: sy = h - 1 - y; break;                    // mirrored vertically
        case 5: sx = y; sy = x; break;                    // transposed
        case 6: sx = y; sy = h - 1 - x; break;            // to be turned 90 clockwise
        case 7: sx = w - 1 - y; sy = h - 1 - x; break;    // transversed
        case 8: sx = w - 1 - y; sy = x; break;            // to be turned 90 counter-clockwise
        default: break;
      }
      std::memcpy(out.at(x, y), in.at(sx, sy), static_cast<size_t>(in.channels));
    }
  return out;
}

void append_to_bytes(void* context, void* data, int size) {
  Bytes* out = static_cast<Bytes*>(context);
  const std::uint8_t* p = static_cast<const std::uint8_t*>(data);
  out->insert(out->end(), p, p + size);
}

// JPEG: the bytes with sixteen 0xFE bytes after each scan's entropy-coded
// data (mostly one-bits; not 0xFF, which would need stuffing and make the
// decoder's search for the next marker stop early). A whole scan never uses
// bits past its data (its last byte is padded), so the copy decodes to the
// same pixels; a scan whose data ends early has its missing blocks read from
// these bits instead of the decoder's zero filler (or fails on a code no
// table has), so the pixels differ. stb_image 2.27 and browsers fill
// silently; this tells.
Bytes ones_after_scans(const std::uint8_t* d, size_t n, const std::vector<size_t>& ends) {
  Bytes out;
  out.reserve(n + 16 * ends.size());
  size_t at = 0;
  for (size_t end : ends) {
    out.insert(out.end(), d + at, d + end);
    out.insert(out.end(), 16, 0xFE);
    at = end;
  }
  out.insert(out.end(), d + at, d + n);
  return out;
}

std::uint64_t fnv1a(const stbi_uc* p, size_t n) {
  std::uint64_t h = 1469598103934665603ull;
  for (size_t i = 0; i < n; ++i) h = (h ^ p[i]) * 1099511628211ull;
  return h;
}

Status inspect(const std::uint8_t* data, size_t size, ImageInfo& info, size_t max_pixels, Declared& declared);

}  // namespace

Status inspect_image(const std::uint8_t* data, size_t size, ImageInfo& info, size_t max_pixels) {
  Declared declared;
  return inspect(data, size, info, max_pixels, declared);
}

Status jpeg_truncation_probe(const std::uint8_t* data, size_t size, Bytes& probe) {
  probe.clear();
  ImageInfo info;
  Declared declared;
  if (Status s = inspect(data, size, info, SIZE_MAX, declared); !s) return s;
  if (declared.jpeg) probe = ones_after_scans(data, size, declared.scan_ends);
  return Status::success();
}

namespace {

Status inspect(const std::uint8_t* data, size_t size, ImageInfo& info, size_t max_pixels, Declared& declared) {
  info = ImageInfo();
  if (size == 0 || data == nullptr) return Status::error(ErrorCode::Empty, "empty input: no bytes");
  if (size > kMaxImageBytes) return Status::error(ErrorCode::TooLarge, "image data over 2 GiB");
  const bool jpeg = size >= 3 && data[0] == 0xFF && data[1] == 0xD8 && data[2] == 0xFF;
  const bool png = starts_with(data, size, "\x89PNG\r\n\x1a\n", 8);
  if (!jpeg && !png) {
    const std::string other = other_format_name(data, size);
    if (!other.empty()) return Status::error(ErrorCode::Unsupported, "this is " + other + kReads);
    return invalid(std::string("not an image") + kReads + " (a JPEG starts with FF D8 FF, a PNG with 89 'PNG')");
  }
  declared = Declared();
  std::uint64_t coded_bytes = 0, needed_bytes = 0;
  std::string rule;
  if (jpeg) {
    std::uint64_t blocks = 0;
    if (Status s = check_jpeg(data, size, declared, coded_bytes, blocks); !s) return s;
    // Every 8x8 block of every component is coded with at least one bit
    // (its DC difference's Huffman code, in any scan order).
    needed_bytes = (blocks + 7) / 8;
    rule = "at least one bit per 8x8 block";
  } else {
    std::uint64_t raw = 0;
    if (Status s = check_png(data, size, declared, coded_bytes, raw); !s) return s;
    // Deflate expands at most 1032:1 (a 258-byte match coded in 2 bits).
    needed_bytes = raw / 1032;
    rule = "deflate inflates at most 1032:1";
  }
  const std::string dims = std::to_string(declared.width) + "x" + std::to_string(declared.height);
  if (static_cast<std::uint64_t>(declared.width) * static_cast<std::uint64_t>(declared.height) > max_pixels)
    return Status::error(ErrorCode::TooLarge,
                         "image is " + dims + ", over the limit of " + std::to_string(max_pixels) + " pixels");
  if (coded_bytes < needed_bytes)
    return Status::error(ErrorCode::InvalidInput,
                         "the " + std::string(jpeg ? "JPEG" : "PNG") + " declares " + dims + " pixels but holds only " +
                             std::to_string(coded_bytes) + " bytes of image data, fewer than the " +
                             std::to_string(needed_bytes) + " that size needs (" + rule +
                             "): a decompression bomb or a damaged file");
  info.format = jpeg ? "JPEG" : "PNG";
  info.stored_width = declared.width;
  info.stored_height = declared.height;
  if (jpeg) {
    ExifInfo exif;
    // A damaged EXIF block does not spoil the picture: it is read as upright.
    if (read_jpeg_exif(data, size, exif).ok() && exif.orientation >= 2 && exif.orientation <= 8)
      info.orientation = exif.orientation;
  }
  const bool turned = info.orientation >= 5;
  info.width = turned ? declared.height : declared.width;
  info.height = turned ? declared.width : declared.height;
  return Status::success();
}

}  // namespace

Status read_image(const std::uint8_t* data, size_t size, Image& image, int want_channels, size_t max_pixels) {
  image = Image();
  if (want_channels < 0 || want_channels > 4)
    return invalid("want_channels must be 0..4, got " + std::to_string(want_channels));
  ImageInfo info;
  Declared declared;
  if (Status s = inspect(data, size, info, max_pixels, declared); !s) return s;
  // The bytes are checked: stb may now look at them.
  const int n = static_cast<int>(size);
  int w = 0, h = 0, c = 0;
  if (!stbi_info_from_memory(data, n, &w, &h, &c))
    return invalid(std::string("cannot decode image: ") + stbi_failure_reason());
  // Gray+alpha has no Image layout of its own: expand to RGBA.
  const int channels = want_channels != 0 ? want_channels : (c == 2 ? 4 : c);
  int dw = 0, dh = 0, dc = 0;
  stbi_uc* pixels = stbi_load_from_memory(data, n, &dw, &dh, &dc, channels);
  if (!pixels) return invalid(std::string("cannot decode image: ") + stbi_failure_reason());
  if (dw != info.stored_width || dh != info.stored_height) {
    stbi_image_free(pixels);
    return Status::error(ErrorCode::Internal, "the decoder gave " + std::to_string(dw) + "x" + std::to_string(dh) +
                                                  " pixels for an image that declares " +
                                                  std::to_string(info.stored_width) + "x" +
                                                  std::to_string(info.stored_height));
  }
  if (declared.jpeg) {
    // Filler inside a whole-looking file: see ones_after_scans.
    const size_t count = static_cast<size_t>(dw) * dh * channels;
    const std::uint64_t hash = fnv1a(pixels, count);
    const Bytes probe = ones_after_scans(data, size, declared.scan_ends);
    int pw = 0, ph = 0, pc = 0;
    stbi_uc* other = probe.size() <= static_cast<size_t>(INT_MAX)
                         ? stbi_load_from_memory(probe.data(), static_cast<int>(probe.size()), &pw, &ph, &pc, channels)
                         : nullptr;
    const bool same = other && pw == dw && ph == dh && fnv1a(other, count) == hash;
    if (other) stbi_image_free(other);
    if (!same) {
      stbi_image_free(pixels);
      return Status::error(ErrorCode::Truncated,
                           "truncated JPEG: its image data ends before its last blocks (the decoder would fill them "
                           "with grey)");
    }
  }
  Image decoded;
  decoded.width = dw;
  decoded.height = dh;
  decoded.channels = channels;
  decoded.pixels.assign(pixels, pixels + static_cast<size_t>(dw) * dh * channels);
  stbi_image_free(pixels);
  image = info.orientation >= 2 ? oriented(decoded, info.orientation) : std::move(decoded);
  return Status::success();
}

Bytes write_png(const Image& image) {
  Bytes out;
  if (image.width <= 0 || image.height <= 0 || image.channels < 1 || image.channels > 4 ||
      image.pixels.size() != static_cast<size_t>(image.width) * image.height * image.channels)
    return out;
  stbi_write_png_to_func(append_to_bytes, &out, image.width, image.height, image.channels, image.pixels.data(),
                         image.width * image.channels);
  return out;
}

}  // namespace lk
