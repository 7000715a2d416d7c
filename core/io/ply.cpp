// PLY reader and writer (Greg Turk's polygon file format): ascii,
// binary_little_endian and binary_big_endian.
//
// Reading checks the header's promises first: every element's smallest
// possible size against the bytes the file has after the header (so "element
// vertex 2147483648" in a 200-byte file fails before anything is allocated);
// then the body is read item by item, skipping elements and properties we do
// not use. The reader is a stream (PlyStreamReader, scan_stream.h) fed any
// chunks of the file; read_ply feeds it the whole buffer at once.
#include "io/io.h"
#include "io/scan_stream.h"
#include "io/text_scan.h"

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstring>

namespace lk {

using io_detail::quote;

namespace {

enum class PlyFormat { Ascii, BinaryLE, BinaryBE };

enum class PlyType { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };

bool parse_type(std::string_view name, PlyType& t) {
  struct Entry { const char* name; PlyType type; };
  static const Entry table[] = {
      {"char", PlyType::Int8},     {"int8", PlyType::Int8},      {"uchar", PlyType::UInt8},
      {"uint8", PlyType::UInt8},   {"short", PlyType::Int16},    {"int16", PlyType::Int16},
      {"ushort", PlyType::UInt16}, {"uint16", PlyType::UInt16},  {"int", PlyType::Int32},
      {"int32", PlyType::Int32},   {"uint", PlyType::UInt32},    {"uint32", PlyType::UInt32},
      {"float", PlyType::Float32}, {"float32", PlyType::Float32}, {"double", PlyType::Float64},
      {"float64", PlyType::Float64}};
  for (const Entry& e : table)
    if (name == e.name) {
      t = e.type;
      return true;
    }
  return false;
}

size_t type_size(PlyType t) {
  switch (t) {
    case PlyType::Int8: case PlyType::UInt8: return 1;
    case PlyType::Int16: case PlyType::UInt16: return 2;
    case PlyType::Int32: case PlyType::UInt32: case PlyType::Float32: return 4;
    case PlyType::Float64: return 8;
  }
  return 1;
}

bool is_integer_type(PlyType t) { return t != PlyType::Float32 && t != PlyType::Float64; }

// Integer colors are stored as fractions of their type's full scale.
double color_scale(PlyType t) {
  switch (t) {
    case PlyType::UInt16: return 1.0 / 65535.0;
    case PlyType::Float32: case PlyType::Float64: return 1.0;
    default: return 1.0 / 255.0;
  }
}

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::Float32;
  bool is_list = false;
  PlyType count_type = PlyType::UInt8;
};

struct PlyElement {
  std::string name;
  std::uint64_t count = 0;
  std::vector<PlyProperty> properties;
};

struct PlyHeader {
  PlyFormat format = PlyFormat::Ascii;
  std::vector<PlyElement> elements;
  std::uint64_t body_offset = 0;  // first byte after "end_header\n"
};

// Smallest number of body bytes an element can occupy: lists may be empty,
// but their counts are always there. Ascii values need a character and a
// separator each.
std::uint64_t min_item_bytes(const PlyElement& e, PlyFormat format) {
  std::uint64_t bytes = 0;
  for (const PlyProperty& p : e.properties) {
    if (format == PlyFormat::Ascii) bytes += 2;
    else bytes += type_size(p.is_list ? p.count_type : p.type);
  }
  return bytes;
}

std::string plural_name(const std::string& element) {
  if (element == "vertex") return "vertices";
  if (element == "face") return "faces";
  return "'" + element + "' elements";
}

// Reads one scalar of the body in either encoding, from the bytes at hand.
class PlyBody {
 public:
  PlyBody(const std::uint8_t* begin, const std::uint8_t* end, PlyFormat format, bool swap)
      : p_(begin), end_(end), format_(format), swap_(swap),
        tok_(reinterpret_cast<const char*>(begin), reinterpret_cast<const char*>(end)) {}

  // Returns false at the end of the bytes at hand; bad_token is set for
  // unparsable text.
  bool read(PlyType t, double& v) {
    if (format_ == PlyFormat::Ascii) {
      const std::string_view s = tok_.next();
      if (s.empty()) return false;
      if (!io_detail::parse_double(s.data(), s.data() + s.size(), v)) {
        bad_token = std::string(s);
        return false;
      }
      return true;
    }
    const size_t n = type_size(t);
    if (static_cast<size_t>(end_ - p_) < n) return false;
    v = decode(p_, t, swap_);
    p_ += n;
    return true;
  }

  // Where the next value starts (ascii: after the last token read).
  const std::uint8_t* position() const {
    return format_ == PlyFormat::Ascii ? reinterpret_cast<const std::uint8_t*>(tok_.position()) : p_;
  }

  static double decode(const std::uint8_t* src, PlyType t, bool swap) {
    unsigned char b[8];
    const size_t n = type_size(t);
    std::memcpy(b, src, n);
    if (swap)
      for (size_t i = 0; i < n / 2; ++i) std::swap(b[i], b[n - 1 - i]);
    switch (t) {
      case PlyType::Int8: { std::int8_t x; std::memcpy(&x, b, 1); return x; }
      case PlyType::UInt8: return b[0];
      case PlyType::Int16: { std::int16_t x; std::memcpy(&x, b, 2); return x; }
      case PlyType::UInt16: { std::uint16_t x; std::memcpy(&x, b, 2); return x; }
      case PlyType::Int32: { std::int32_t x; std::memcpy(&x, b, 4); return x; }
      case PlyType::UInt32: { std::uint32_t x; std::memcpy(&x, b, 4); return x; }
      case PlyType::Float32: { float x; std::memcpy(&x, b, 4); return x; }
      case PlyType::Float64: { double x; std::memcpy(&x, b, 8); return x; }
    }
    return 0;
  }

  std::string bad_token;

 private:
  const std::uint8_t* p_;
  const std::uint8_t* end_;
  PlyFormat format_;
  bool swap_;
  io_detail::Tokenizer tok_;
};

bool host_is_little_endian() {
  const std::uint16_t probe = 1;
  unsigned char first;
  std::memcpy(&first, &probe, 1);
  return first == 1;
}

int find_property(const PlyElement& e, std::initializer_list<const char*> names) {
  for (const char* n : names)
    for (size_t i = 0; i < e.properties.size(); ++i)
      if (e.properties[i].name == n) return static_cast<int>(i);
  return -1;
}

}  // namespace

// The reader's state between pushes. process() parses what the bytes at
// hand allow and says how many it used; the rest (an unfinished header line,
// item or ascii number) is carried and offered again with the next bytes.
// With final set there are no next bytes: what is unfinished is an error.
struct PlyStreamReader::State {
  enum class Stage { Magic, Header, Body, Trailer };

  std::uint64_t total = 0, received = 0;
  Status error;  // sticky once set
  Stage stage = Stage::Magic;
  Bytes carry;
  std::uint64_t carry_base = 0;  // file offset of carry[0]

  // Header.
  PlyHeader header;
  int line_number = 0;
  bool have_format = false;

  // Body: what we use of the vertex and face elements, and where we are.
  bool swap = false;
  const PlyElement* vertex_element = nullptr;
  const PlyElement* face_element = nullptr;
  int num_vertices = 0;
  int ix = -1, iy = -1, iz = -1, inx = -1, iny = -1, inz = -1, ir = -1, ig = -1, ib = -1, iu = -1, iv = -1;
  bool has_normals = false, has_colors = false, has_uvs = false;
  int face_indices = -1, face_texcoords = -1;
  bool corner_uvs = false;
  std::vector<Vec2> corner_uv_values;  // 3 per triangle, from the faces' "texcoord" lists
  size_t element = 0;                  // index into header.elements
  std::uint64_t item = 0;              // within that element
  bool fixed = false;                  // binary, no lists: a fixed stride
  size_t stride = 0;
  std::vector<double> scalars, indices, texcoords, skipped;
  TriMesh mesh;

  Status process(const std::uint8_t* buf, size_t n, std::uint64_t base, bool final, size_t& used);
  Status header_line(std::string_view line, bool has_newline, std::uint64_t next_line_offset);
  Status begin_body();
  void begin_element();
  Status item_done();
  Status process_body(const std::uint8_t* buf, size_t n, std::uint64_t base, bool final, size_t& pos);
  std::string ends_after() const {
    const PlyElement& e = header.elements[element];
    return "truncated: header declares " + std::to_string(e.count) + " " + plural_name(e.name) +
           " but the data ends after " + std::to_string(item);
  }
};

Status PlyStreamReader::State::header_line(std::string_view line, bool has_newline,
                                           std::uint64_t next_line_offset) {
  ++line_number;
  io_detail::Tokenizer tok(line.data(), line.data() + line.size());
  const std::string_view keyword = tok.next();
  const std::string where = "header line " + std::to_string(line_number) + ": ";
  if (line_number == 1 || keyword.empty() || keyword == "comment" || keyword == "obj_info") {
    // "ply" magic, blank lines and comments carry nothing we need.
  } else if (keyword == "format") {
    const std::string_view f = tok.next();
    if (f == "ascii") header.format = PlyFormat::Ascii;
    else if (f == "binary_little_endian") header.format = PlyFormat::BinaryLE;
    else if (f == "binary_big_endian") header.format = PlyFormat::BinaryBE;
    else return Status::error(ErrorCode::Unsupported, where + "unsupported format " + quote(f));
    have_format = true;
  } else if (keyword == "element") {
    PlyElement e;
    e.name = std::string(tok.next());
    const std::string_view count = tok.next();
    std::int64_t n = 0;
    if (e.name.empty() || !io_detail::parse_int64(count.data(), count.data() + count.size(), n) || n < 0)
      return Status::error(ErrorCode::InvalidInput,
                           where + "expected 'element <name> <count>', got count " + quote(count));
    e.count = static_cast<std::uint64_t>(n);
    header.elements.push_back(std::move(e));
  } else if (keyword == "property") {
    if (header.elements.empty()) return Status::error(ErrorCode::InvalidInput, where + "property before any element");
    PlyProperty p;
    std::string_view type = tok.next();
    if (type == "list") {
      p.is_list = true;
      const std::string_view count_type = tok.next();
      if (!parse_type(count_type, p.count_type))
        return Status::error(ErrorCode::Unsupported, where + "unsupported list count type " + quote(count_type));
      if (!is_integer_type(p.count_type))
        return Status::error(ErrorCode::InvalidInput,
                             where + "list count type must be an integer type, got " + quote(count_type));
      type = tok.next();
    }
    if (!parse_type(type, p.type))
      return Status::error(ErrorCode::Unsupported, where + "unsupported property type " + quote(type));
    p.name = std::string(tok.next());
    if (p.name.empty()) return Status::error(ErrorCode::InvalidInput, where + "property without a name");
    header.elements.back().properties.push_back(std::move(p));
  } else if (keyword == "end_header") {
    header.body_offset = next_line_offset;
    if (!has_newline && header.format != PlyFormat::Ascii)
      return Status::error(ErrorCode::Truncated, "truncated: no data after 'end_header'");
    if (!have_format) return Status::error(ErrorCode::InvalidInput, "the header has no 'format' line");
    stage = Stage::Body;
    return begin_body();
  } else {
    return Status::error(ErrorCode::InvalidInput, where + "unknown keyword " + quote(keyword));
  }
  return Status::success();
}

// The header is whole: check its counts against the declared size (so
// "element vertex 2147483648" in a 200-byte file fails before anything is
// allocated) and find the properties we use.
Status PlyStreamReader::State::begin_body() {
  const std::uint64_t body_bytes = total - header.body_offset;
  std::uint64_t needed = 0;
  for (const PlyElement& e : header.elements) {
    // Every item must take at least one byte, or no byte count can bound the
    // loop over its items: "element junk 9223372036854775807" with no
    // properties would spin for hours over nothing.
    if (e.properties.empty() && e.count > 0)
      return Status::error(ErrorCode::InvalidInput, "element '" + e.name + "' declares " + std::to_string(e.count) +
                                                        " items but has no properties");
    const std::uint64_t item_bytes = min_item_bytes(e, header.format);
    if (item_bytes > 0 && e.count > (body_bytes + 1) / item_bytes) {
      const std::string at_least = e.count <= UINT64_MAX / item_bytes
                                       ? " (at least " + std::to_string(e.count * item_bytes) + " bytes)"
                                       : "";
      return Status::error(ErrorCode::Truncated, "truncated: header declares " + std::to_string(e.count) + " " +
                                                     plural_name(e.name) + at_least + " but only " +
                                                     std::to_string(body_bytes) + " bytes follow the header");
    }
    needed += e.count * item_bytes;
  }
  if (needed > body_bytes + 1)
    return Status::error(ErrorCode::Truncated, "truncated: the header's elements need at least " +
                                                   std::to_string(needed) + " bytes but only " +
                                                   std::to_string(body_bytes) + " follow the header");

  for (const PlyElement& e : header.elements) {
    if (e.name == "vertex" && !vertex_element) vertex_element = &e;
    if (e.name == "face" && !face_element) face_element = &e;
  }
  if (!vertex_element) return Status::error(ErrorCode::InvalidInput, "no 'vertex' element in the header");
  if (vertex_element->count == 0) return Status::error(ErrorCode::Empty, "empty: the file declares 0 vertices");
  if (vertex_element->count > static_cast<std::uint64_t>(INT_MAX))
    return Status::error(ErrorCode::TooLarge, "too large: " + std::to_string(vertex_element->count) + " vertices");
  if (face_element && face_element->count > static_cast<std::uint64_t>(INT_MAX / 2))
    return Status::error(ErrorCode::TooLarge, "too large: " + std::to_string(face_element->count) + " faces");
  num_vertices = static_cast<int>(vertex_element->count);

  const PlyElement& ve = *vertex_element;
  ix = find_property(ve, {"x"}), iy = find_property(ve, {"y"}), iz = find_property(ve, {"z"});
  if (ix < 0 || iy < 0 || iz < 0) return Status::error(ErrorCode::InvalidInput, "the vertex element lacks x, y or z");
  inx = find_property(ve, {"nx"}), iny = find_property(ve, {"ny"}), inz = find_property(ve, {"nz"});
  ir = find_property(ve, {"red", "diffuse_red", "r"});
  ig = find_property(ve, {"green", "diffuse_green", "g"});
  ib = find_property(ve, {"blue", "diffuse_blue", "b"});
  iu = find_property(ve, {"s", "u", "texture_u", "texture_s"});
  iv = find_property(ve, {"t", "v", "texture_v", "texture_t"});
  for (int i : {ix, iy, iz, inx, iny, inz, ir, ig, ib, iu, iv})
    if (i >= 0 && ve.properties[i].is_list)
      return Status::error(ErrorCode::InvalidInput, "vertex property '" + ve.properties[i].name + "' is a list");
  has_normals = inx >= 0 && iny >= 0 && inz >= 0;
  has_colors = ir >= 0 && ig >= 0 && ib >= 0;
  has_uvs = iu >= 0 && iv >= 0;

  if (face_element) {
    face_indices = find_property(*face_element, {"vertex_indices", "vertex_index"});
    face_texcoords = find_property(*face_element, {"texcoord"});
    if (face_element->count > 0 && (face_indices < 0 || !face_element->properties[face_indices].is_list))
      return Status::error(ErrorCode::InvalidInput, "the face element has no 'vertex_indices' list");
    if (face_texcoords >= 0 && !face_element->properties[face_texcoords].is_list) face_texcoords = -1;
  }

  // The counts are bounded by the declared size, checked above.
  mesh.positions.reserve(num_vertices);
  if (has_normals) mesh.normals.reserve(num_vertices);
  if (has_colors) mesh.colors.reserve(num_vertices);
  if (has_uvs) mesh.uvs.reserve(num_vertices);
  corner_uvs = face_texcoords >= 0;
  swap = header.format != PlyFormat::Ascii && (header.format == PlyFormat::BinaryLE) != host_is_little_endian();
  element = 0;
  item = 0;
  begin_element();
  return Status::success();
}

void PlyStreamReader::State::begin_element() {
  if (element >= header.elements.size()) return;
  const PlyElement& e = header.elements[element];
  scalars.assign(e.properties.size(), 0.0);
  fixed = header.format != PlyFormat::Ascii;
  stride = 0;
  for (const PlyProperty& p : e.properties) {
    fixed = fixed && !p.is_list;
    stride += type_size(p.type);
  }
}

// One whole item of the current element is in scalars / indices / texcoords.
Status PlyStreamReader::State::item_done() {
  const PlyElement& e = header.elements[element];
  if (&e == vertex_element) {
    const PlyElement& ve = e;
    const Vec3 p(scalars[ix], scalars[iy], scalars[iz]);
    if (!p.allFinite())
      return Status::error(ErrorCode::InvalidInput, "vertex " + std::to_string(item) + " has a NaN or infinite coordinate");
    mesh.positions.push_back(p);
    if (has_normals) {
      const Vec3 nrm(scalars[inx], scalars[iny], scalars[inz]);
      if (!nrm.allFinite())
        return Status::error(ErrorCode::InvalidInput, "vertex " + std::to_string(item) + " has a NaN or infinite normal");
      mesh.normals.push_back(nrm);
    }
    if (has_colors) {
      const Vec3 c(scalars[ir] * color_scale(ve.properties[ir].type), scalars[ig] * color_scale(ve.properties[ig].type),
                   scalars[ib] * color_scale(ve.properties[ib].type));
      if (!c.allFinite())
        return Status::error(ErrorCode::InvalidInput, "vertex " + std::to_string(item) + " has a NaN or infinite color");
      mesh.colors.push_back(c);
    }
    if (has_uvs) {
      const Vec2 uv(scalars[iu], scalars[iv]);
      if (!uv.allFinite())
        return Status::error(ErrorCode::InvalidInput,
                             "vertex " + std::to_string(item) + " has a NaN or infinite texture coordinate");
      mesh.uvs.push_back(uv);
    }
  } else if (&e == face_element) {
    const size_t n = indices.size();
    if (n < 3)
      return Status::error(ErrorCode::InvalidInput, "face " + std::to_string(item) + " has " + std::to_string(n) +
                                                        " vertices (at least 3 needed)");
    for (double index : indices) {
      if (!(index >= 0 && index < num_vertices) || index != std::floor(index))
        return Status::error(ErrorCode::InvalidInput, "face " + std::to_string(item) + " refers to vertex " +
                                                          io_detail::format_double(index) + " but there are only " +
                                                          std::to_string(num_vertices) + " vertices");
    }
    if (corner_uvs && texcoords.size() != 2 * n) corner_uvs = false;  // per-corner uvs must cover every face
    // Fan triangulation; faces with n corners give n-2 triangles.
    for (size_t k = 1; k + 1 < n; ++k) {
      mesh.triangles.push_back(
          {static_cast<int>(indices[0]), static_cast<int>(indices[k]), static_cast<int>(indices[k + 1])});
      if (corner_uvs)
        for (size_t c : {size_t(0), k, k + 1}) corner_uv_values.push_back(Vec2(texcoords[2 * c], texcoords[2 * c + 1]));
    }
  }
  return Status::success();
}

// Parses the body's items from buf[pos, n); pos ends at the first byte not
// used (the start of an unfinished item when more bytes are to come).
Status PlyStreamReader::State::process_body(const std::uint8_t* buf, size_t n, std::uint64_t base, bool final,
                                            size_t& pos) {
  const bool ascii = header.format == PlyFormat::Ascii;
  // Ascii: a number is whole only once a separator follows it (or the file ends).
  size_t limit = n;
  if (ascii && !final) {
    while (limit > pos && !io_detail::is_space(static_cast<char>(buf[limit - 1]))) --limit;
  }
  while (element < header.elements.size()) {
    const PlyElement& e = header.elements[element];
    if (item >= e.count) {
      ++element;
      item = 0;
      begin_element();
      continue;
    }
    if (fixed) {
      // Binary elements without lists have a fixed stride: one bounds check
      // per item instead of per value (the common vertex case; 5x faster).
      while (item < e.count && n - pos >= stride) {
        const std::uint8_t* p = buf + pos;
        for (size_t pi = 0; pi < e.properties.size(); ++pi) {
          scalars[pi] = PlyBody::decode(p, e.properties[pi].type, swap);
          p += type_size(e.properties[pi].type);
        }
        if (Status s = item_done(); !s) return s;
        pos += stride;
        ++item;
      }
      if (item < e.count) {
        if (final) return Status::error(ErrorCode::Truncated, ends_after());
        return Status::success();  // the rest of this item comes with the next bytes
      }
      continue;
    }
    const bool is_face = &e == face_element;
    PlyBody body(buf + pos, buf + limit, header.format, swap);
    bool ok = true;
    size_t pi = 0;
    for (; pi < e.properties.size(); ++pi) {
      const PlyProperty& p = e.properties[pi];
      if (!p.is_list) {
        ok = body.read(p.type, scalars[pi]);
        if (!ok) break;
        continue;
      }
      double count_value = 0;
      ok = body.read(p.count_type, count_value);
      if (!ok) break;
      if (count_value < 0 || count_value != std::floor(count_value))
        return Status::error(ErrorCode::InvalidInput, e.name + " " + std::to_string(item) + ": invalid list length " +
                                                          io_detail::format_double(count_value));
      // A list cannot hold more values than the file has bytes left (this
      // also stops a huge count from reserving memory).
      const std::uint64_t remaining = total - (base + static_cast<std::uint64_t>(body.position() - buf));
      const double min_bytes = count_value * (ascii ? 2.0 : type_size(p.type));
      if (min_bytes > static_cast<double>(remaining) + 1)
        return Status::error(ErrorCode::Truncated, ends_after() + " (" + e.name + " " + std::to_string(item) +
                                                       " declares a list of " + io_detail::format_double(count_value) +
                                                       " values but only " + std::to_string(remaining) +
                                                       " bytes remain)");
      const size_t count = static_cast<size_t>(count_value);
      std::vector<double>& list = (is_face && static_cast<int>(pi) == face_indices)     ? indices
                                  : (is_face && static_cast<int>(pi) == face_texcoords) ? texcoords
                                                                                        : skipped;
      list.resize(count);
      for (size_t k = 0; k < count && ok; ++k) ok = body.read(p.type, list[k]);
      if (!ok) break;
    }
    if (!ok) {
      if (!body.bad_token.empty())
        return Status::error(ErrorCode::InvalidInput, e.name + " " + std::to_string(item) + ", property '" +
                                                          e.properties[pi].name + "': " + quote(body.bad_token) +
                                                          " is not a number");
      if (final) return Status::error(ErrorCode::Truncated, ends_after());
      return Status::success();  // an unfinished item: wait for more bytes
    }
    if (Status s = item_done(); !s) return s;
    pos = static_cast<size_t>(body.position() - buf);
    ++item;
  }
  return Status::success();
}

Status PlyStreamReader::State::process(const std::uint8_t* buf, size_t n, std::uint64_t base, bool final,
                                       size_t& used) {
  size_t pos = 0;
  used = 0;
  if (stage == Stage::Magic) {
    if (n < 4 && !final) return Status::success();
    if (n == 0) return Status::error(ErrorCode::Empty, "empty input: no bytes");
    if (n < 4 || std::memcmp(buf, "ply", 3) != 0 || (buf[3] != '\n' && buf[3] != '\r'))
      return Status::error(ErrorCode::InvalidInput, "not a PLY file: it does not start with the line 'ply'");
    stage = Stage::Header;
  }
  while (stage == Stage::Header) {
    if (pos >= n) {
      if (final) return Status::error(ErrorCode::Truncated, "truncated: the header ends without 'end_header'");
      break;
    }
    const void* nl = std::memchr(buf + pos, '\n', n - pos);
    if (!nl && !final) break;  // the rest of this line comes with the next bytes
    const size_t eol = nl ? static_cast<size_t>(static_cast<const std::uint8_t*>(nl) - buf) : n;
    const size_t next_line = nl ? eol + 1 : n;
    const std::string_view line(reinterpret_cast<const char*>(buf + pos), eol - pos);
    if (Status s = header_line(line, nl != nullptr, base + next_line); !s) return s;
    pos = next_line;
  }
  if (stage == Stage::Body) {
    if (Status s = process_body(buf, n, base, final, pos); !s) return s;
    if (element >= header.elements.size()) stage = Stage::Trailer;
  }
  if (stage == Stage::Trailer && pos < n) {
    // Nothing may follow the last element but (in ascii) white space.
    size_t q = pos;
    if (header.format == PlyFormat::Ascii)
      while (q < n && io_detail::is_space(static_cast<char>(buf[q]))) ++q;
    if (q < n)
      return Status::error(ErrorCode::InvalidInput,
                           "wrong counts: " + std::to_string(total - (base + q)) +
                               " bytes of data follow the last element the header declares");
    pos = n;
  }
  used = pos;
  return Status::success();
}

PlyStreamReader::PlyStreamReader(std::uint64_t total_size) : s_(std::make_unique<State>()) {
  s_->total = total_size;
  if (total_size > kMaxGeometryBytes)
    s_->error = Status::error(ErrorCode::TooLarge, "too large: " + std::to_string(total_size) +
                                                       " bytes, the limit is " + std::to_string(kMaxGeometryBytes));
}

PlyStreamReader::~PlyStreamReader() = default;

std::uint64_t PlyStreamReader::bytes_received() const { return s_->received; }

std::uint64_t PlyStreamReader::declared_vertices() const {
  return s_->error.ok() && s_->vertex_element ? s_->vertex_element->count : 0;
}

Status PlyStreamReader::push(const std::uint8_t* data, size_t size) {
  State& st = *s_;
  if (!st.error.ok()) return st.error;
  if (size > st.total - st.received) {
    st.error = Status::error(ErrorCode::InvalidInput, "more bytes than the " + std::to_string(st.total) +
                                                          " the file was declared to have");
    return st.error;
  }
  const std::uint64_t data_base = st.received;
  st.received += size;
  Status s = io_detail::guard_allocation([&] {
    return io_detail::push_carried(st.carry, st.carry_base, data_base, data, size,
                                   [&st](const std::uint8_t* d, size_t n, std::uint64_t at, bool final, size_t& used) {
                                     return st.process(d, n, at, final, used);
                                   });
  });
  if (!s) {
    st.error = s;
    st.mesh = TriMesh();
    st.carry = Bytes();
  }
  return s;
}

Status PlyStreamReader::finish(TriMesh& mesh, GeometryKind& kind) {
  State& st = *s_;
  mesh = TriMesh();
  kind = GeometryKind::PointCloud;
  if (st.error.ok() && st.received != st.total)
    st.error = Status::error(ErrorCode::Truncated, "truncated: the data ends after " + std::to_string(st.received) +
                                                       " of the file's " + std::to_string(st.total) + " bytes");
  if (!st.error.ok()) return st.error;
  Status s = io_detail::guard_allocation([&] {
    size_t used = 0;
    if (Status e = st.process(st.carry.data(), st.carry.size(), st.carry_base, true, used); !e) return e;
    // Per-corner uvs (MeshLab's face "texcoord") win over per-vertex ones.
    if (st.corner_uvs && !st.mesh.triangles.empty() && st.corner_uv_values.size() == 3 * st.mesh.triangles.size()) {
      for (const Vec2& uv : st.corner_uv_values)
        if (!uv.allFinite())
          return Status::error(ErrorCode::InvalidInput, "a face has a NaN or infinite texture coordinate");
      st.mesh.uvs = std::move(st.corner_uv_values);
      st.mesh.uv_per_corner = true;
    }
    return Status::success();
  });
  st.carry = Bytes();
  if (!s) {
    st.error = s;
    st.mesh = TriMesh();
    return s;
  }
  kind = st.mesh.triangles.empty() ? GeometryKind::PointCloud : GeometryKind::Mesh;
  mesh = std::move(st.mesh);
  st.mesh = TriMesh();
  st.error = Status::error(ErrorCode::Internal, "the reader has already finished");
  return Status::success();
}

Status read_ply(const std::uint8_t* data, size_t size, TriMesh& mesh, GeometryKind& kind) {
  mesh = TriMesh();
  kind = GeometryKind::PointCloud;
  if (Status s = io_detail::check_input_size(size, kMaxGeometryBytes); !s) return s;
  PlyStreamReader reader(size);
  if (Status s = reader.push(data, size); !s) return s;
  return reader.finish(mesh, kind);
}

namespace {

// Appends a value in little-endian byte order (the format we write).
template <typename T>
void put_le(Bytes& out, T v) {
  unsigned char b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));
  const std::uint16_t probe = 1;
  unsigned char first;
  std::memcpy(&first, &probe, 1);
  if (first != 1)
    for (size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(b[i], b[sizeof(T) - 1 - i]);
  out.insert(out.end(), b, b + sizeof(T));
}

std::uint8_t color_byte(double c) {
  const double v = std::round(std::min(1.0, std::max(0.0, c)) * 255.0);
  return static_cast<std::uint8_t>(v);
}

Bytes write_ply_impl(const std::vector<Vec3>& positions, const std::vector<Vec3>& normals,
                     const std::vector<Vec3>& colors, const std::vector<Vec2>& vertex_uvs,
                     const std::vector<Tri>& triangles, const std::vector<Vec2>& corner_uvs, bool ascii) {
  const size_t nv = positions.size();
  const bool has_normals = normals.size() == nv && nv > 0;
  const bool has_colors = colors.size() == nv && nv > 0;
  const bool has_uvs = vertex_uvs.size() == nv && nv > 0;
  const bool has_corner_uvs = !triangles.empty() && corner_uvs.size() == 3 * triangles.size();
  // Ascii keeps full double precision (exact round trips, for debugging);
  // binary uses float, which every PLY tool reads and halves the size.
  const char* real = ascii ? "double" : "float";
  std::string h = "ply\n";
  h += ascii ? "format ascii 1.0\n" : "format binary_little_endian 1.0\n";
  h += "comment written by likeness\n";
  h += "element vertex " + std::to_string(nv) + "\n";
  for (const char* c : {"x", "y", "z"}) h += std::string("property ") + real + " " + c + "\n";
  if (has_normals)
    for (const char* c : {"nx", "ny", "nz"}) h += std::string("property ") + real + " " + c + "\n";
  if (has_colors)
    for (const char* c : {"red", "green", "blue"}) h += std::string("property uchar ") + c + "\n";
  if (has_uvs)
    for (const char* c : {"s", "t"}) h += std::string("property ") + real + " " + c + "\n";
  if (!triangles.empty()) {
    h += "element face " + std::to_string(triangles.size()) + "\n";
    h += "property list uchar int vertex_indices\n";
    if (has_corner_uvs) h += std::string("property list uchar ") + real + " texcoord\n";
  }
  h += "end_header\n";

  Bytes out(h.begin(), h.end());
  if (ascii) {
    std::string body;
    auto put3 = [&body](const Vec3& v) {
      for (int k = 0; k < 3; ++k) {
        body += ' ';
        io_detail::append_double(body, v[k]);
      }
    };
    for (size_t i = 0; i < nv; ++i) {
      io_detail::append_double(body, positions[i].x());
      body += ' ';
      io_detail::append_double(body, positions[i].y());
      body += ' ';
      io_detail::append_double(body, positions[i].z());
      if (has_normals) put3(normals[i]);
      if (has_colors)
        for (int k = 0; k < 3; ++k) body += " " + std::to_string(color_byte(colors[i][k]));
      if (has_uvs) {
        body += ' ';
        io_detail::append_double(body, vertex_uvs[i].x());
        body += ' ';
        io_detail::append_double(body, vertex_uvs[i].y());
      }
      body += '\n';
    }
    for (size_t f = 0; f < triangles.size(); ++f) {
      const Tri& t = triangles[f];
      body += "3 " + std::to_string(t[0]) + " " + std::to_string(t[1]) + " " + std::to_string(t[2]);
      if (has_corner_uvs) {
        body += " 6";
        for (int k = 0; k < 3; ++k) {
          body += ' ';
          io_detail::append_double(body, corner_uvs[3 * f + k].x());
          body += ' ';
          io_detail::append_double(body, corner_uvs[3 * f + k].y());
        }
      }
      body += '\n';
    }
    out.insert(out.end(), body.begin(), body.end());
    return out;
  }
  out.reserve(out.size() + nv * 4 * (3 + (has_normals ? 3 : 0) + (has_uvs ? 2 : 0)) + nv * 3 +
              triangles.size() * (13 + (has_corner_uvs ? 25 : 0)));
  for (size_t i = 0; i < nv; ++i) {
    for (int k = 0; k < 3; ++k) put_le(out, static_cast<float>(positions[i][k]));
    if (has_normals)
      for (int k = 0; k < 3; ++k) put_le(out, static_cast<float>(normals[i][k]));
    if (has_colors)
      for (int k = 0; k < 3; ++k) out.push_back(color_byte(colors[i][k]));
    if (has_uvs)
      for (int k = 0; k < 2; ++k) put_le(out, static_cast<float>(vertex_uvs[i][k]));
  }
  for (size_t f = 0; f < triangles.size(); ++f) {
    out.push_back(3);
    for (int k = 0; k < 3; ++k) put_le(out, static_cast<std::int32_t>(triangles[f][k]));
    if (has_corner_uvs) {
      out.push_back(6);
      for (int k = 0; k < 3; ++k)
        for (int c = 0; c < 2; ++c) put_le(out, static_cast<float>(corner_uvs[3 * f + k][c]));
    }
  }
  return out;
}

}  // namespace

Bytes write_ply(const TriMesh& mesh, bool ascii) {
  static const std::vector<Vec2> none;
  return write_ply_impl(mesh.positions, mesh.normals, mesh.colors, mesh.uv_per_corner ? none : mesh.uvs,
                        mesh.triangles, mesh.uv_per_corner ? mesh.uvs : none, ascii);
}

Bytes write_ply(const PointCloud& cloud, bool ascii) {
  static const std::vector<Vec2> none;
  static const std::vector<Tri> no_triangles;
  return write_ply_impl(cloud.positions, cloud.normals, cloud.colors, none, no_triangles, none, ascii);
}

}  // namespace lk
