// PLY reader and writer (Greg Turk's polygon file format): ascii,
// binary_little_endian and binary_big_endian.
//
// Reading is in two passes over the header's promises: first every element's
// smallest possible size is checked against the bytes that follow the header
// (so "element vertex 2147483648" in a 200-byte file fails before anything is
// allocated), then the body is read property by property, skipping elements
// and properties we do not use.
#include "io/io.h"
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
  size_t body_offset = 0;  // first byte after "end_header\n"
};

Status parse_header(const std::uint8_t* data, size_t size, PlyHeader& header) {
  if (size == 0) return Status::error(ErrorCode::Empty, "empty input: no bytes");
  const char* text = reinterpret_cast<const char*>(data);
  if (size < 4 || std::memcmp(text, "ply", 3) != 0 || (text[3] != '\n' && text[3] != '\r'))
    return Status::error(ErrorCode::InvalidInput, "not a PLY file: it does not start with the line 'ply'");
  // The header is text up to "end_header"; read it line by line.
  size_t pos = 0;
  int line_number = 0;
  bool have_format = false;
  while (true) {
    if (pos >= size)
      return Status::error(ErrorCode::Truncated, "truncated: the header ends without 'end_header'");
    size_t eol = pos;
    while (eol < size && text[eol] != '\n') ++eol;
    ++line_number;
    io_detail::Tokenizer tok(text + pos, text + eol);
    const size_t next_line = eol < size ? eol + 1 : size;
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
      if (header.elements.empty())
        return Status::error(ErrorCode::InvalidInput, where + "property before any element");
      PlyProperty p;
      std::string_view type = tok.next();
      if (type == "list") {
        p.is_list = true;
        const std::string_view count_type = tok.next();
        if (!parse_type(count_type, p.count_type))
          return Status::error(ErrorCode::Unsupported, where + "unsupported list count type " + quote(count_type));
        if (!is_integer_type(p.count_type))
          return Status::error(ErrorCode::InvalidInput, where + "list count type must be an integer type, got " +
                                                            quote(count_type));
        type = tok.next();
      }
      if (!parse_type(type, p.type))
        return Status::error(ErrorCode::Unsupported, where + "unsupported property type " + quote(type));
      p.name = std::string(tok.next());
      if (p.name.empty()) return Status::error(ErrorCode::InvalidInput, where + "property without a name");
      header.elements.back().properties.push_back(std::move(p));
    } else if (keyword == "end_header") {
      header.body_offset = next_line;
      if (eol >= size && header.format != PlyFormat::Ascii)
        return Status::error(ErrorCode::Truncated, "truncated: no data after 'end_header'");
      break;
    } else {
      return Status::error(ErrorCode::InvalidInput, where + "unknown keyword " + quote(keyword));
    }
    pos = next_line;
  }
  if (!have_format) return Status::error(ErrorCode::InvalidInput, "the header has no 'format' line");
  return Status::success();
}

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

// Reads one scalar of the body in either encoding.
class PlyBody {
 public:
  PlyBody(const std::uint8_t* begin, const std::uint8_t* end, PlyFormat format)
      : p_(begin), end_(end), format_(format),
        swap_(format != PlyFormat::Ascii && (format == PlyFormat::BinaryLE) != host_is_little_endian()),
        tok_(reinterpret_cast<const char*>(begin), reinterpret_cast<const char*>(end)) {}

  // Returns false at the end of the data; bad_token is set for unparsable text.
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
    v = decode(p_, t);
    p_ += n;
    return true;
  }

  // Binary elements without lists have a fixed stride: one bounds check per
  // item instead of per value (the common vertex case; 5x faster).
  bool read_fixed_item(const PlyElement& e, size_t stride, double* out) {
    if (static_cast<size_t>(end_ - p_) < stride) return false;
    for (const PlyProperty& p : e.properties) {
      *out++ = decode(p_, p.type);
      p_ += type_size(p.type);
    }
    return true;
  }

  // Bytes (binary) left, or whether non-space text is left (ascii).
  size_t leftover() {
    if (format_ == PlyFormat::Ascii) return tok_.at_end() ? 0 : tok_.remaining();
    return static_cast<size_t>(end_ - p_);
  }
  size_t remaining_bytes() const {
    return format_ == PlyFormat::Ascii ? tok_.remaining() : static_cast<size_t>(end_ - p_);
  }

  std::string bad_token;

 private:
  static bool host_is_little_endian() {
    const std::uint16_t probe = 1;
    unsigned char first;
    std::memcpy(&first, &probe, 1);
    return first == 1;
  }

  double decode(const std::uint8_t* src, PlyType t) const {
    unsigned char b[8];
    const size_t n = type_size(t);
    std::memcpy(b, src, n);
    if (swap_)
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

  const std::uint8_t* p_;
  const std::uint8_t* end_;
  PlyFormat format_;
  bool swap_;
  io_detail::Tokenizer tok_;
};

int find_property(const PlyElement& e, std::initializer_list<const char*> names) {
  for (const char* n : names)
    for (size_t i = 0; i < e.properties.size(); ++i)
      if (e.properties[i].name == n) return static_cast<int>(i);
  return -1;
}

}  // namespace

namespace {

Status read_ply_body(const std::uint8_t* data, size_t size, TriMesh& mesh, GeometryKind& kind) {
  PlyHeader header;
  if (Status s = parse_header(data, size, header); !s) return s;

  // Fail fast on counts that the bytes cannot hold.
  const std::uint64_t body_bytes = size - header.body_offset;
  std::uint64_t needed = 0;
  for (const PlyElement& e : header.elements) {
    // Every item must take at least one byte, or no byte count can bound the
    // loop over its items: "element junk 9223372036854775807" with no
    // properties would spin for hours over nothing.
    if (e.properties.empty() && e.count > 0)
      return Status::error(ErrorCode::InvalidInput, "element '" + e.name + "' declares " + std::to_string(e.count) +
                                                        " items but has no properties");
    const std::uint64_t item = min_item_bytes(e, header.format);
    if (item > 0 && e.count > (body_bytes + 1) / item) {
      const std::string at_least =
          e.count <= UINT64_MAX / item ? " (at least " + std::to_string(e.count * item) + " bytes)" : "";
      return Status::error(ErrorCode::Truncated, "truncated: header declares " + std::to_string(e.count) + " " +
                                                     plural_name(e.name) + at_least + " but only " +
                                                     std::to_string(body_bytes) + " bytes follow the header");
    }
    needed += e.count * item;
  }
  if (needed > body_bytes + 1)
    return Status::error(ErrorCode::Truncated, "truncated: the header's elements need at least " +
                                                   std::to_string(needed) + " bytes but only " +
                                                   std::to_string(body_bytes) + " follow the header");

  const PlyElement* vertex_element = nullptr;
  const PlyElement* face_element = nullptr;
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
  const int num_vertices = static_cast<int>(vertex_element->count);

  // Which vertex properties we use.
  const PlyElement& ve = *vertex_element;
  const int ix = find_property(ve, {"x"}), iy = find_property(ve, {"y"}), iz = find_property(ve, {"z"});
  if (ix < 0 || iy < 0 || iz < 0)
    return Status::error(ErrorCode::InvalidInput, "the vertex element lacks x, y or z");
  const int inx = find_property(ve, {"nx"}), iny = find_property(ve, {"ny"}), inz = find_property(ve, {"nz"});
  const int ir = find_property(ve, {"red", "diffuse_red", "r"});
  const int ig = find_property(ve, {"green", "diffuse_green", "g"});
  const int ib = find_property(ve, {"blue", "diffuse_blue", "b"});
  const int iu = find_property(ve, {"s", "u", "texture_u", "texture_s"});
  const int iv = find_property(ve, {"t", "v", "texture_v", "texture_t"});
  for (int i : {ix, iy, iz, inx, iny, inz, ir, ig, ib, iu, iv})
    if (i >= 0 && ve.properties[i].is_list)
      return Status::error(ErrorCode::InvalidInput, "vertex property '" + ve.properties[i].name + "' is a list");
  const bool has_normals = inx >= 0 && iny >= 0 && inz >= 0;
  const bool has_colors = ir >= 0 && ig >= 0 && ib >= 0;
  const bool has_uvs = iu >= 0 && iv >= 0;

  int face_indices = -1, face_texcoords = -1;
  if (face_element) {
    face_indices = find_property(*face_element, {"vertex_indices", "vertex_index"});
    face_texcoords = find_property(*face_element, {"texcoord"});
    if (face_element->count > 0 && (face_indices < 0 || !face_element->properties[face_indices].is_list))
      return Status::error(ErrorCode::InvalidInput, "the face element has no 'vertex_indices' list");
    if (face_texcoords >= 0 && !face_element->properties[face_texcoords].is_list) face_texcoords = -1;
  }

  mesh.positions.reserve(num_vertices);
  if (has_normals) mesh.normals.reserve(num_vertices);
  if (has_colors) mesh.colors.reserve(num_vertices);
  if (has_uvs) mesh.uvs.reserve(num_vertices);
  bool corner_uvs = face_texcoords >= 0;
  std::vector<Vec2> corner_uv_values;  // 3 per triangle, from the faces' "texcoord" lists

  PlyBody body(data + header.body_offset, data + size, header.format);
  std::vector<double> scalars;
  std::vector<double> indices, texcoords;
  std::vector<double> skipped;
  for (const PlyElement& e : header.elements) {
    const bool is_vertex = &e == vertex_element;
    const bool is_face = &e == face_element;
    scalars.assign(e.properties.size(), 0.0);
    bool fixed = header.format != PlyFormat::Ascii;
    size_t stride = 0;
    for (const PlyProperty& p : e.properties) {
      fixed = fixed && !p.is_list;
      stride += type_size(p.type);
    }
    auto ends_after = [&e](std::uint64_t item) {
      return "truncated: header declares " + std::to_string(e.count) + " " + plural_name(e.name) +
             " but the data ends after " + std::to_string(item);
    };
    for (std::uint64_t item = 0; item < e.count; ++item) {
      if (fixed && !body.read_fixed_item(e, stride, scalars.data()))
        return Status::error(ErrorCode::Truncated, ends_after(item));
      for (size_t pi = 0; pi < e.properties.size() && !fixed; ++pi) {
        const PlyProperty& p = e.properties[pi];
        bool ok = true;
        if (!p.is_list) {
          ok = body.read(p.type, scalars[pi]);
        } else {
          double count_value = 0;
          ok = body.read(p.count_type, count_value);
          if (ok) {
            if (count_value < 0 || count_value != std::floor(count_value))
              return Status::error(ErrorCode::InvalidInput, e.name + " " + std::to_string(item) +
                                                                ": invalid list length " +
                                                                io_detail::format_double(count_value));
            // A list cannot hold more values than the bytes left (this also
            // stops a huge count from reserving memory).
            const double min_bytes = count_value * (header.format == PlyFormat::Ascii ? 2.0 : type_size(p.type));
            if (min_bytes > static_cast<double>(body.remaining_bytes()) + 1)
              return Status::error(ErrorCode::Truncated,
                                   ends_after(item) + " (" + e.name + " " + std::to_string(item) +
                                       " declares a list of " + io_detail::format_double(count_value) +
                                       " values but only " + std::to_string(body.remaining_bytes()) +
                                       " bytes remain)");
            const size_t n = static_cast<size_t>(count_value);
            std::vector<double>& list =
                (is_face && static_cast<int>(pi) == face_indices) ? indices
                : (is_face && static_cast<int>(pi) == face_texcoords) ? texcoords : skipped;
            list.resize(n);
            for (size_t k = 0; k < n && ok; ++k) ok = body.read(p.type, list[k]);
          }
        }
        if (!ok) {
          if (!body.bad_token.empty())
            return Status::error(ErrorCode::InvalidInput, e.name + " " + std::to_string(item) + ", property '" +
                                                              p.name + "': " + quote(body.bad_token) +
                                                              " is not a number");
          return Status::error(ErrorCode::Truncated, ends_after(item));
        }
      }
      if (is_vertex) {
        const Vec3 p(scalars[ix], scalars[iy], scalars[iz]);
        if (!p.allFinite())
          return Status::error(ErrorCode::InvalidInput,
                               "vertex " + std::to_string(item) + " has a NaN or infinite coordinate");
        mesh.positions.push_back(p);
        if (has_normals) {
          const Vec3 n(scalars[inx], scalars[iny], scalars[inz]);
          if (!n.allFinite())
            return Status::error(ErrorCode::InvalidInput,
                                 "vertex " + std::to_string(item) + " has a NaN or infinite normal");
          mesh.normals.push_back(n);
        }
        if (has_colors) {
          const Vec3 c(scalars[ir] * color_scale(ve.properties[ir].type),
                       scalars[ig] * color_scale(ve.properties[ig].type),
                       scalars[ib] * color_scale(ve.properties[ib].type));
          if (!c.allFinite())
            return Status::error(ErrorCode::InvalidInput,
                                 "vertex " + std::to_string(item) + " has a NaN or infinite color");
          mesh.colors.push_back(c);
        }
        if (has_uvs) {
          const Vec2 uv(scalars[iu], scalars[iv]);
          if (!uv.allFinite())
            return Status::error(ErrorCode::InvalidInput,
                                 "vertex " + std::to_string(item) + " has a NaN or infinite texture coordinate");
          mesh.uvs.push_back(uv);
        }
      } else if (is_face) {
        const size_t n = indices.size();
        if (n < 3)
          return Status::error(ErrorCode::InvalidInput, "face " + std::to_string(item) + " has " +
                                                            std::to_string(n) + " vertices (at least 3 needed)");
        for (double index : indices) {
          if (!(index >= 0 && index < num_vertices) || index != std::floor(index))
            return Status::error(ErrorCode::InvalidInput,
                                 "face " + std::to_string(item) + " refers to vertex " +
                                     io_detail::format_double(index) + " but there are only " +
                                     std::to_string(num_vertices) + " vertices");
        }
        if (corner_uvs && texcoords.size() != 2 * n) corner_uvs = false;  // per-corner uvs must cover every face
        // Fan triangulation; faces with n corners give n-2 triangles.
        for (size_t k = 1; k + 1 < n; ++k) {
          mesh.triangles.push_back(
              {static_cast<int>(indices[0]), static_cast<int>(indices[k]), static_cast<int>(indices[k + 1])});
          if (corner_uvs) {
            for (size_t c : {size_t(0), k, k + 1})
              corner_uv_values.push_back(Vec2(texcoords[2 * c], texcoords[2 * c + 1]));
          }
        }
      }
    }
  }
  if (const size_t extra = body.leftover(); extra > 0)
    return Status::error(ErrorCode::InvalidInput,
                         "wrong counts: " + std::to_string(extra) +
                             " bytes of data follow the last element the header declares");

  // Per-corner uvs (MeshLab's face "texcoord") win over per-vertex ones.
  if (corner_uvs && !mesh.triangles.empty() && corner_uv_values.size() == 3 * mesh.triangles.size()) {
    for (const Vec2& uv : corner_uv_values)
      if (!uv.allFinite())
        return Status::error(ErrorCode::InvalidInput, "a face has a NaN or infinite texture coordinate");
    mesh.uvs = std::move(corner_uv_values);
    mesh.uv_per_corner = true;
  }
  kind = mesh.triangles.empty() ? GeometryKind::PointCloud : GeometryKind::Mesh;
  return Status::success();
}

}  // namespace

Status read_ply(const std::uint8_t* data, size_t size, TriMesh& mesh, GeometryKind& kind) {
  mesh = TriMesh();
  kind = GeometryKind::PointCloud;
  if (Status s = io_detail::check_input_size(size, kMaxGeometryBytes); !s) return s;
  Status s = io_detail::guard_allocation([&] { return read_ply_body(data, size, mesh, kind); });
  if (!s) mesh = TriMesh();  // never hand back half a mesh
  return s;
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
