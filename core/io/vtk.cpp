// Legacy VTK reader: ASCII "DATASET POLYDATA" files as old range scanners and
// VTKData ship them (fran_cut.vtk). POINTS, POLYGONS (fan-triangulated),
// TRIANGLE_STRIPS, and POINT_DATA NORMALS / TEXTURE_COORDINATES /
// COLOR_SCALARS are read; VERTICES, LINES, CELL_DATA, SCALARS, VECTORS,
// TENSORS, FIELD arrays and METADATA are skipped by their declared sizes.
// Both cell layouts are understood: "n size" + per-cell counts (up to 4.2)
// and OFFSETS/CONNECTIVITY (5.1).
#include "io/io.h"
#include "io/text_scan.h"

#include <climits>
#include <cmath>
#include <cstring>

namespace lk {

using io_detail::quote;

namespace {

class VtkParser {
 public:
  VtkParser(const char* begin, const char* end) : tok_(begin, end) {}

  Status parse(TriMesh& mesh);

 private:
  Status error(ErrorCode code, const std::string& what) const {
    return Status::error(code, "line " + std::to_string(tok_.line()) + ": " + what);
  }
  // Reads a non-negative count; also checks that count * per_item values can
  // fit in the bytes left (each ascii value takes at least two bytes).
  Status read_count(const char* what, std::uint64_t per_item, std::int64_t& count) {
    const std::string_view t = tok_.next();
    if (!io_detail::parse_int64(t.data(), t.data() + t.size(), count) || count < 0)
      return error(ErrorCode::InvalidInput, std::string("expected a count after ") + what + ", got " + quote(t));
    if (count > INT_MAX) return error(ErrorCode::TooLarge, std::string(what) + " count " + std::to_string(count) + " is too large");
    const std::uint64_t min_bytes = static_cast<std::uint64_t>(count) * per_item * 2;
    if (min_bytes > tok_.remaining() + 1)
      return error(ErrorCode::Truncated, std::string("truncated: ") + what + " declares " + std::to_string(count) +
                                             " items (at least " + std::to_string(min_bytes) + " bytes) but only " +
                                             std::to_string(tok_.remaining()) + " bytes are left");
    return Status::success();
  }
  // Reads n numbers; a missing one is truncation, a bad one invalid input.
  // Nothing is allocated before the bytes left are shown to hold n values
  // (two bytes each at least), whatever count a section declared.
  Status read_numbers(const char* what, size_t n, std::vector<double>& out) {
    if (n > (tok_.remaining() + 1) / 2)
      return error(ErrorCode::Truncated, std::string("truncated: ") + what + " declares " + std::to_string(n) +
                                             " values (at least " + std::to_string(2 * static_cast<std::uint64_t>(n)) +
                                             " bytes) but only " + std::to_string(tok_.remaining()) +
                                             " bytes are left");
    out.resize(n);
    for (size_t i = 0; i < n; ++i) {
      const std::string_view t = tok_.next();
      if (t.empty())
        return error(ErrorCode::Truncated, std::string("truncated: ") + what + " declares " + std::to_string(n) +
                                               " values but the data ends after " + std::to_string(i));
      if (!io_detail::parse_double(t.data(), t.data() + t.size(), out[i]))
        return error(ErrorCode::InvalidInput, std::string(what) + ": " + quote(t) + " is not a number");
      if (!std::isfinite(out[i])) return error(ErrorCode::InvalidInput, std::string(what) + ": NaN or infinite value");
    }
    return Status::success();
  }
  Status skip_numbers(const char* what, size_t n) {
    if (n > (tok_.remaining() + 1) / 2)
      return error(ErrorCode::Truncated, std::string("truncated: ") + what + " declares " + std::to_string(n) +
                                             " values but only " + std::to_string(tok_.remaining()) +
                                             " bytes are left");
    for (size_t i = 0; i < n; ++i)
      if (tok_.next().empty())
        return error(ErrorCode::Truncated, std::string("truncated: ") + what + " declares " + std::to_string(n) +
                                               " values but the data ends after " + std::to_string(i));
    return Status::success();
  }
  Status read_cells(const std::string& keyword, TriMesh& mesh);
  Status read_attribute(const std::string& keyword, TriMesh& mesh);

  io_detail::Tokenizer tok_;
  bool in_data_section_ = false;  // after POINT_DATA or CELL_DATA
  bool point_data_ = false;       // attributes belong to points (else cells)
  std::int64_t attribute_count_ = 0;
  int num_points_ = 0;
  std::vector<double> values_;
};

Status VtkParser::parse(TriMesh& mesh) {
  // Line 1: magic, line 2: title, line 3: ASCII | BINARY.
  const std::string_view magic = tok_.rest_of_line();
  if (magic.substr(0, 22) != "# vtk DataFile Version")
    return Status::error(ErrorCode::InvalidInput, "not a legacy VTK file: the first line is not '# vtk DataFile Version ...'");
  tok_.skip_line();
  tok_.skip_line();  // title
  const std::string encoding = io_detail::lowercase(std::string(tok_.next()));
  if (encoding == "binary") return error(ErrorCode::Unsupported, "binary legacy VTK is not supported (only ASCII)");
  if (encoding != "ascii") return error(ErrorCode::InvalidInput, "expected ASCII or BINARY, got " + quote(encoding));
  const std::string dataset = io_detail::lowercase(std::string(tok_.next()));
  const std::string type = std::string(tok_.next());
  if (dataset != "dataset") return error(ErrorCode::InvalidInput, "expected DATASET, got " + quote(dataset));
  if (io_detail::lowercase(type) != "polydata")
    return error(ErrorCode::Unsupported, "only DATASET POLYDATA is supported, got " + quote(type));

  bool have_points = false;
  while (!tok_.at_end()) {
    const std::string keyword = io_detail::lowercase(std::string(tok_.next()));
    if (keyword == "points") {
      if (have_points) return error(ErrorCode::InvalidInput, "a second POINTS section");
      std::int64_t n = 0;
      if (Status s = read_count("POINTS", 3, n); !s) return s;
      tok_.next();  // data type: every numeric type reads as double
      if (Status s = read_numbers("POINTS", static_cast<size_t>(3 * n), values_); !s) return s;
      mesh.positions.resize(n);
      for (std::int64_t i = 0; i < n; ++i) mesh.positions[i] = Vec3(values_[3 * i], values_[3 * i + 1], values_[3 * i + 2]);
      num_points_ = static_cast<int>(n);
      have_points = true;
    } else if (keyword == "polygons" || keyword == "triangle_strips" || keyword == "vertices" || keyword == "lines") {
      if (Status s = read_cells(keyword, mesh); !s) return s;
    } else if (keyword == "point_data" || keyword == "cell_data") {
      point_data_ = keyword == "point_data";
      in_data_section_ = true;
      // The count alone allocates nothing: each attribute that follows is
      // checked against the bytes left before it is read (read_numbers).
      if (Status s = read_count(point_data_ ? "POINT_DATA" : "CELL_DATA", 0, attribute_count_); !s) return s;
      if (point_data_ && attribute_count_ != num_points_)
        return error(ErrorCode::InvalidInput, "wrong counts: POINT_DATA " + std::to_string(attribute_count_) +
                                                  " but there are " + std::to_string(num_points_) + " points");
    } else if (keyword == "metadata") {
      // Free-form block that ends at an empty line.
      tok_.skip_line();
      while (tok_.remaining() > 0 && !tok_.rest_of_line().empty()) tok_.skip_line();
    } else {
      if (Status s = read_attribute(keyword, mesh); !s) return s;
    }
  }
  if (!have_points || num_points_ == 0) return Status::error(ErrorCode::Empty, "empty: the VTK file has no POINTS");
  return Status::success();
}

Status VtkParser::read_cells(const std::string& keyword, TriMesh& mesh) {
  const bool polygons = keyword == "polygons", strips = keyword == "triangle_strips";
  const char* what = polygons ? "POLYGONS" : strips ? "TRIANGLE_STRIPS" : keyword == "vertices" ? "VERTICES" : "LINES";
  std::int64_t cells = 0, size = 0;
  if (Status s = read_count(what, 1, cells); !s) return s;
  if (Status s = read_count(what, 1, size); !s) return s;
  // Cell lists as (offsets, connectivity).
  std::vector<std::int64_t> offsets, connectivity;
  auto read_ints = [this, what](size_t n, std::vector<std::int64_t>& out) -> Status {
    if (Status s = read_numbers(what, n, values_); !s) return s;
    out.resize(n);
    for (size_t i = 0; i < n; ++i) {
      if (values_[i] != std::floor(values_[i]) || std::abs(values_[i]) > 4e18)
        return error(ErrorCode::InvalidInput, std::string(what) + ": " + io_detail::format_double(values_[i]) +
                                                  " is not an integer");
      out[i] = static_cast<std::int64_t>(values_[i]);
    }
    return Status::success();
  };
  if (io_detail::lowercase(std::string(tok_.peek())) == "offsets") {
    // VTK 5.1: "<cells+1> <connectivity size>", OFFSETS type <offsets>, CONNECTIVITY type <ids>.
    tok_.next();
    tok_.next();
    if (Status s = read_ints(static_cast<size_t>(cells), offsets); !s) return s;
    if (io_detail::lowercase(std::string(tok_.next())) != "connectivity")
      return error(ErrorCode::InvalidInput, std::string(what) + ": expected CONNECTIVITY after the offsets");
    tok_.next();
    if (Status s = read_ints(static_cast<size_t>(size), connectivity); !s) return s;
    for (size_t i = 0; i < offsets.size(); ++i)
      if (offsets[i] < 0 || offsets[i] > size || (i > 0 && offsets[i] < offsets[i - 1]))
        return error(ErrorCode::InvalidInput, std::string(what) + ": offsets are not increasing within the connectivity");
  } else {
    // Up to 4.2: "<cells> <total numbers>", then per cell "<n> id_1 ... id_n".
    std::vector<std::int64_t> flat;
    if (Status s = read_ints(static_cast<size_t>(size), flat); !s) return s;
    offsets.push_back(0);
    size_t pos = 0;
    for (std::int64_t c = 0; c < cells; ++c) {
      if (pos >= flat.size() || flat[pos] < 0 || static_cast<std::uint64_t>(flat[pos]) > flat.size() - pos - 1)
        return error(ErrorCode::InvalidInput, "wrong counts: " + std::string(what) + " declares " +
                                                  std::to_string(cells) + " cells in " + std::to_string(size) +
                                                  " numbers, but cell " + std::to_string(c) + " does not fit");
      const std::int64_t n = flat[pos];
      connectivity.insert(connectivity.end(), flat.begin() + pos + 1, flat.begin() + pos + 1 + n);
      pos += static_cast<size_t>(n) + 1;
      offsets.push_back(static_cast<std::int64_t>(connectivity.size()));
    }
    if (pos != flat.size())
      return error(ErrorCode::InvalidInput, "wrong counts: " + std::string(what) + " declares " + std::to_string(size) +
                                                " numbers but its " + std::to_string(cells) + " cells use " +
                                                std::to_string(pos));
  }
  if (!polygons && !strips) return Status::success();
  for (std::int64_t id : connectivity)
    if (id < 0 || id >= num_points_)
      return error(ErrorCode::InvalidInput, std::string(what) + " refers to point " + std::to_string(id) +
                                                " but there are only " + std::to_string(num_points_) + " points");
  for (size_t c = 0; c + 1 < offsets.size(); ++c) {
    const std::int64_t* ids = connectivity.data() + offsets[c];
    const std::int64_t n = offsets[c + 1] - offsets[c];
    if (polygons) {
      if (n < 3)
        return error(ErrorCode::InvalidInput, "polygon " + std::to_string(c) + " has " + std::to_string(n) +
                                                  " points (at least 3 needed)");
      for (std::int64_t k = 1; k + 1 < n; ++k)
        mesh.triangles.push_back({static_cast<int>(ids[0]), static_cast<int>(ids[k]), static_cast<int>(ids[k + 1])});
    } else {
      // Strips alternate orientation; repeated ids (degenerate triangles)
      // are how strips are stitched and are dropped.
      for (std::int64_t k = 0; k + 2 < n; ++k) {
        Tri t = (k % 2 == 0) ? Tri{int(ids[k]), int(ids[k + 1]), int(ids[k + 2])}
                             : Tri{int(ids[k + 1]), int(ids[k]), int(ids[k + 2])};
        if (t[0] != t[1] && t[1] != t[2] && t[0] != t[2]) mesh.triangles.push_back(t);
      }
    }
  }
  return Status::success();
}

Status VtkParser::read_attribute(const std::string& keyword, TriMesh& mesh) {
  const size_t n = static_cast<size_t>(attribute_count_);
  auto need_data_section = [&]() -> Status {
    if (!in_data_section_)
      return error(ErrorCode::InvalidInput, quote(keyword) + " outside a POINT_DATA or CELL_DATA section");
    return Status::success();
  };
  if (keyword == "scalars") {
    if (Status s = need_data_section(); !s) return s;
    tok_.next();  // name
    tok_.next();  // type
    std::int64_t components = 1;
    std::string_view t = tok_.next();
    if (io_detail::lowercase(std::string(t)) != "lookup_table") {
      if (!io_detail::parse_int64(t.data(), t.data() + t.size(), components) || components < 1 || components > 4)
        return error(ErrorCode::InvalidInput, "SCALARS: bad component count " + quote(t));
      if (io_detail::lowercase(std::string(tok_.peek())) == "lookup_table") {
        tok_.next();
        tok_.next();  // table name
      }
    } else {
      tok_.next();  // table name
    }
    return skip_numbers("SCALARS", n * static_cast<size_t>(components));
  }
  if (keyword == "lookup_table") {
    tok_.next();  // name
    std::int64_t entries = 0;
    if (Status s = read_count("LOOKUP_TABLE", 4, entries); !s) return s;
    return skip_numbers("LOOKUP_TABLE", 4 * static_cast<size_t>(entries));
  }
  if (keyword == "color_scalars") {
    if (Status s = need_data_section(); !s) return s;
    tok_.next();  // name
    std::int64_t components = 0;
    if (Status s = read_count("COLOR_SCALARS", 0, components); !s) return s;
    if (components < 1 || components > 4) return error(ErrorCode::InvalidInput, "COLOR_SCALARS: bad component count");
    if (Status s = read_numbers("COLOR_SCALARS", n * components, values_); !s) return s;
    if (point_data_ && components >= 3) {
      mesh.colors.resize(n);
      for (size_t i = 0; i < n; ++i)
        mesh.colors[i] = Vec3(values_[i * components], values_[i * components + 1], values_[i * components + 2]);
    }
    return Status::success();
  }
  if (keyword == "vectors" || keyword == "normals" || keyword == "tensors") {
    if (Status s = need_data_section(); !s) return s;
    tok_.next();  // name
    tok_.next();  // type
    const size_t per = keyword == "tensors" ? 9 : 3;
    if (static_cast<std::uint64_t>(n) * per * 2 > tok_.remaining() + 1)
      return error(ErrorCode::Truncated, "truncated: " + io_detail::lowercase(keyword) + " for " + std::to_string(n) +
                                             " items do not fit in the bytes left");
    if (keyword == "normals" && point_data_) {
      if (Status s = read_numbers("NORMALS", 3 * n, values_); !s) return s;
      mesh.normals.resize(n);
      for (size_t i = 0; i < n; ++i) mesh.normals[i] = Vec3(values_[3 * i], values_[3 * i + 1], values_[3 * i + 2]);
      return Status::success();
    }
    return skip_numbers("VECTORS", per * n);
  }
  if (keyword == "texture_coordinates") {
    if (Status s = need_data_section(); !s) return s;
    tok_.next();  // name
    std::int64_t dim = 0;
    if (Status s = read_count("TEXTURE_COORDINATES", 0, dim); !s) return s;
    if (dim < 1 || dim > 3) return error(ErrorCode::InvalidInput, "TEXTURE_COORDINATES: dimension must be 1, 2 or 3");
    tok_.next();  // type
    if (Status s = read_numbers("TEXTURE_COORDINATES", n * dim, values_); !s) return s;
    if (point_data_) {
      mesh.uvs.resize(n);
      for (size_t i = 0; i < n; ++i) mesh.uvs[i] = Vec2(values_[i * dim], dim > 1 ? values_[i * dim + 1] : 0.0);
    }
    return Status::success();
  }
  if (keyword == "field") {
    tok_.next();  // name
    std::int64_t arrays = 0;
    if (Status s = read_count("FIELD", 4, arrays); !s) return s;
    for (std::int64_t a = 0; a < arrays; ++a) {
      tok_.next();  // array name
      std::int64_t components = 0, tuples = 0;
      if (Status s = read_count("FIELD array", 0, components); !s) return s;
      if (Status s = read_count("FIELD array", static_cast<std::uint64_t>(components), tuples); !s) return s;
      tok_.next();  // type
      if (Status s = skip_numbers("FIELD array", static_cast<size_t>(components * tuples)); !s) return s;
    }
    return Status::success();
  }
  return error(ErrorCode::InvalidInput, "unknown keyword " + quote(keyword));
}

}  // namespace

Status read_vtk(const std::uint8_t* data, size_t size, TriMesh& mesh, GeometryKind& kind) {
  mesh = TriMesh();
  kind = GeometryKind::PointCloud;
  if (size == 0) return Status::error(ErrorCode::Empty, "empty input: no bytes");
  const char* text = reinterpret_cast<const char*>(data);
  if (Status s = io_detail::check_input_size(size, kMaxGeometryBytes); !s) return s;
  VtkParser parser(text, text + size);
  if (Status s = io_detail::guard_allocation([&] { return parser.parse(mesh); }); !s) {
    mesh = TriMesh();
    return s;
  }
  const size_t nv = mesh.positions.size();
  // Attributes of another size than the points would be unusable.
  if (mesh.normals.size() != nv) mesh.normals.clear();
  if (mesh.colors.size() != nv) mesh.colors.clear();
  if (mesh.uvs.size() != nv) mesh.uvs.clear();
  kind = mesh.triangles.empty() ? GeometryKind::PointCloud : GeometryKind::Mesh;
  return Status::success();
}

}  // namespace lk
