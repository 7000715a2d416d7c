// Legacy VTK reader: ASCII "DATASET POLYDATA" files as old range scanners and
// VTKData ship them (fran_cut.vtk). POINTS, POLYGONS (fan-triangulated),
// TRIANGLE_STRIPS, and POINT_DATA NORMALS / TEXTURE_COORDINATES /
// COLOR_SCALARS are read; VERTICES, LINES, CELL_DATA, SCALARS, VECTORS,
// TENSORS, FIELD arrays and METADATA are skipped by their declared sizes.
// Both cell layouts are understood: "n size" + per-cell counts (up to 4.2)
// and OFFSETS/CONNECTIVITY (5.1).
//
// The reader is a stream (VtkStreamReader, scan_stream.h); read_vtk feeds it
// the whole buffer at once. A section's head (its keyword, counts and type
// names) is parsed once all of it is at hand, read again from its start when
// the bytes end inside it; its numbers are then read one by one as they come.
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

// A tokenizer over the bytes at hand that knows where they lie in the file:
// remaining() and line() are the whole file's. When more bytes are to come
// (not final), reading past the bytes at hand marks it starved: what was
// read since the last checkpoint is read again once more bytes are there.
// The bytes at hand end at a white space when not final, so every token it
// returns is whole.
class WindowTokenizer {
 public:
  WindowTokenizer(const char* begin, const char* end, bool final, std::uint64_t base, std::uint64_t total,
                  int first_line)
      : t_(begin, end), begin_(begin), end_(end), final_(final), base_(base), total_(total), first_line_(first_line) {}

  std::string_view next() {
    const std::string_view s = t_.next();
    if (s.empty()) starve();
    return s;
  }
  std::string_view peek() {
    const std::string_view s = t_.peek();
    if (s.empty()) starve();
    return s;
  }
  void skip_line() {
    const char* from = t_.position();
    t_.skip_line();
    const char* p = t_.position();
    if (p == end_ && (p == from || p[-1] != '\n')) starve();
  }
  std::string_view rest_of_line() {
    const std::string_view s = t_.rest_of_line();
    if (t_.position() == end_) starve();
    return s;
  }
  bool at_end() { return t_.at_end(); }
  std::uint64_t remaining() const { return total_ - (base_ + static_cast<std::uint64_t>(t_.position() - begin_)); }
  int line() const { return first_line_ + t_.line() - 1; }
  size_t offset() const { return static_cast<size_t>(t_.position() - begin_); }
  bool final() const { return final_; }
  bool starved() const { return starved_; }

 private:
  void starve() {
    if (!final_) starved_ = true;
  }

  io_detail::Tokenizer t_;
  const char* begin_;
  const char* end_;
  bool final_;
  std::uint64_t base_, total_;
  int first_line_;
  bool starved_ = false;
};

}  // namespace

struct VtkStreamReader::State {
  // Header: the magic, title and encoding lines. Keyword: a section's head.
  // Numbers: a section's values, one by one. ConnectivityHead: 5.1's
  // "CONNECTIVITY type" after the offsets. FieldArrayHead: a FIELD array's
  // "name components tuples type".
  enum class Phase { Header, Keyword, Numbers, ConnectivityHead, FieldArrayHead, Done };
  // What the numbers read become.
  enum class Then { Points, LegacyCells, Offsets, Connectivity, ColorScalars, Normals, TexCoords, Skipped, FieldArray };

  explicit State(std::uint64_t total_size) : bytes(total_size, kMaxGeometryBytes) {}

  io_detail::StreamBytes bytes;
  Bytes carry;
  std::uint64_t carry_base = 0;  // file offset of carry[0]
  int carry_line = 1;            // line number at carry[0]
  Phase phase = Phase::Header;

  // The numbers being read.
  const char* what = "";
  size_t count = 0, done = 0;
  bool keep = false;  // into values (else skipped)
  Then then = Then::Skipped;

  // The section being read.
  bool polygons = false, strips = false;
  std::int64_t cells = 0, cell_numbers = 0, points_declared = 0, components = 0, dim = 0, field_arrays_left = 0;
  std::vector<std::int64_t> offsets, connectivity;

  bool in_data_section = false;  // after POINT_DATA or CELL_DATA
  bool point_data = false;       // attributes belong to points (else cells)
  std::int64_t attribute_count = 0;
  int num_points = 0;
  bool have_points = false;
  std::vector<double> values;
  TriMesh mesh;

  Status process(const std::uint8_t* buf, size_t n, std::uint64_t base, bool final, size_t& used);
  Status step(WindowTokenizer& tok);
  Status header(WindowTokenizer& tok);
  Status keyword(WindowTokenizer& tok);
  Status cells_head(WindowTokenizer& tok, const std::string& keyword);
  Status attribute_head(WindowTokenizer& tok, const std::string& keyword);
  Status connectivity_head(WindowTokenizer& tok);
  Status field_array_head(WindowTokenizer& tok);
  Status numbers(WindowTokenizer& tok);
  Status numbers_done(WindowTokenizer& tok);
  Status to_ints(WindowTokenizer& tok, std::vector<std::int64_t>& out);
  Status cells_done(WindowTokenizer& tok);
  Status build(TriMesh& out, GeometryKind& kind);

  static Status error(const WindowTokenizer& tok, ErrorCode code, const std::string& what) {
    return Status::error(code, "line " + std::to_string(tok.line()) + ": " + what);
  }
  // Reads a non-negative count; also checks that count * per_item values can
  // fit in the bytes left (each ascii value takes at least two bytes).
  static Status read_count(WindowTokenizer& tok, const char* what, std::uint64_t per_item, std::int64_t& count) {
    const std::string_view t = tok.next();
    if (!io_detail::parse_int64(t.data(), t.data() + t.size(), count) || count < 0)
      return error(tok, ErrorCode::InvalidInput, std::string("expected a count after ") + what + ", got " + quote(t));
    if (count > INT_MAX)
      return error(tok, ErrorCode::TooLarge, std::string(what) + " count " + std::to_string(count) + " is too large");
    const std::uint64_t min_bytes = static_cast<std::uint64_t>(count) * per_item * 2;
    if (min_bytes > tok.remaining() + 1)
      return error(tok, ErrorCode::Truncated, std::string("truncated: ") + what + " declares " + std::to_string(count) +
                                                  " items (at least " + std::to_string(min_bytes) + " bytes) but only " +
                                                  std::to_string(tok.remaining()) + " bytes are left");
    return Status::success();
  }
  // Starts reading n numbers (into values when keep, else skipped), then
  // `next`. Nothing is allocated before the bytes left are shown to hold n
  // values (two bytes each at least), whatever count a section declared.
  // Does nothing on a starved head: it is read again.
  Status begin_numbers(WindowTokenizer& tok, const char* name, size_t n, bool into_values, Then next) {
    if (tok.starved()) return Status::success();
    if (n > (tok.remaining() + 1) / 2) {
      if (into_values)
        return error(tok, ErrorCode::Truncated, std::string("truncated: ") + name + " declares " + std::to_string(n) +
                                                    " values (at least " +
                                                    std::to_string(2 * static_cast<std::uint64_t>(n)) +
                                                    " bytes) but only " + std::to_string(tok.remaining()) +
                                                    " bytes are left");
      return error(tok, ErrorCode::Truncated, std::string("truncated: ") + name + " declares " + std::to_string(n) +
                                                  " values but only " + std::to_string(tok.remaining()) +
                                                  " bytes are left");
    }
    what = name;
    count = n;
    done = 0;
    keep = into_values;
    then = next;
    if (keep) values.resize(n);
    phase = Phase::Numbers;
    return Status::success();
  }
};

Status VtkStreamReader::State::header(WindowTokenizer& tok) {
  // Line 1: magic, line 2: title, line 3: ASCII | BINARY.
  const std::string_view magic = tok.rest_of_line();
  if (tok.starved()) return Status::success();
  if (magic.substr(0, 22) != "# vtk DataFile Version")
    return Status::error(ErrorCode::InvalidInput, "not a legacy VTK file: the first line is not '# vtk DataFile Version ...'");
  tok.skip_line();
  tok.skip_line();  // title
  const std::string encoding = io_detail::lowercase(std::string(tok.next()));
  if (encoding == "binary") return error(tok, ErrorCode::Unsupported, "binary legacy VTK is not supported (only ASCII)");
  if (encoding != "ascii") return error(tok, ErrorCode::InvalidInput, "expected ASCII or BINARY, got " + quote(encoding));
  const std::string dataset = io_detail::lowercase(std::string(tok.next()));
  const std::string type = std::string(tok.next());
  if (dataset != "dataset") return error(tok, ErrorCode::InvalidInput, "expected DATASET, got " + quote(dataset));
  if (io_detail::lowercase(type) != "polydata")
    return error(tok, ErrorCode::Unsupported, "only DATASET POLYDATA is supported, got " + quote(type));
  phase = Phase::Keyword;
  return Status::success();
}

Status VtkStreamReader::State::keyword(WindowTokenizer& tok) {
  if (tok.at_end()) {
    if (tok.final()) phase = Phase::Done;
    return Status::success();  // else: wait for the next bytes
  }
  const std::string key = io_detail::lowercase(std::string(tok.next()));
  if (key == "points") {
    if (have_points) return error(tok, ErrorCode::InvalidInput, "a second POINTS section");
    if (Status s = read_count(tok, "POINTS", 3, points_declared); !s) return s;
    tok.next();  // data type: every numeric type reads as double
    return begin_numbers(tok, "POINTS", static_cast<size_t>(3 * points_declared), true, Then::Points);
  }
  if (key == "polygons" || key == "triangle_strips" || key == "vertices" || key == "lines") return cells_head(tok, key);
  if (key == "point_data" || key == "cell_data") {
    point_data = key == "point_data";
    in_data_section = true;
    // The count alone allocates nothing: each attribute that follows is
    // checked against the bytes left before it is read (begin_numbers).
    if (Status s = read_count(tok, point_data ? "POINT_DATA" : "CELL_DATA", 0, attribute_count); !s) return s;
    if (point_data && attribute_count != num_points)
      return error(tok, ErrorCode::InvalidInput, "wrong counts: POINT_DATA " + std::to_string(attribute_count) +
                                                     " but there are " + std::to_string(num_points) + " points");
    return Status::success();
  }
  if (key == "metadata") {
    // Free-form block that ends at an empty line.
    tok.skip_line();
    while (tok.remaining() > 0 && !tok.rest_of_line().empty()) tok.skip_line();
    return Status::success();
  }
  return attribute_head(tok, key);
}

Status VtkStreamReader::State::cells_head(WindowTokenizer& tok, const std::string& key) {
  polygons = key == "polygons";
  strips = key == "triangle_strips";
  const char* name = polygons ? "POLYGONS" : strips ? "TRIANGLE_STRIPS" : key == "vertices" ? "VERTICES" : "LINES";
  if (Status s = read_count(tok, name, 1, cells); !s) return s;
  if (Status s = read_count(tok, name, 1, cell_numbers); !s) return s;
  if (io_detail::lowercase(std::string(tok.peek())) == "offsets") {
    // VTK 5.1: "<cells+1> <connectivity size>", OFFSETS type <offsets>, CONNECTIVITY type <ids>.
    tok.next();
    tok.next();
    return begin_numbers(tok, name, static_cast<size_t>(cells), true, Then::Offsets);
  }
  // Up to 4.2: "<cells> <total numbers>", then per cell "<n> id_1 ... id_n".
  return begin_numbers(tok, name, static_cast<size_t>(cell_numbers), true, Then::LegacyCells);
}

Status VtkStreamReader::State::connectivity_head(WindowTokenizer& tok) {
  const std::string key = io_detail::lowercase(std::string(tok.next()));
  if (tok.starved()) return Status::success();
  if (key != "connectivity")
    return error(tok, ErrorCode::InvalidInput, std::string(what) + ": expected CONNECTIVITY after the offsets");
  tok.next();
  return begin_numbers(tok, what, static_cast<size_t>(cell_numbers), true, Then::Connectivity);
}

Status VtkStreamReader::State::attribute_head(WindowTokenizer& tok, const std::string& key) {
  const size_t n = static_cast<size_t>(attribute_count);
  auto need_data_section = [&]() -> Status {
    if (!in_data_section)
      return error(tok, ErrorCode::InvalidInput, quote(key) + " outside a POINT_DATA or CELL_DATA section");
    return Status::success();
  };
  if (key == "scalars") {
    if (Status s = need_data_section(); !s) return s;
    tok.next();  // name
    tok.next();  // type
    std::int64_t scalar_components = 1;
    std::string_view t = tok.next();
    if (io_detail::lowercase(std::string(t)) != "lookup_table") {
      if (!io_detail::parse_int64(t.data(), t.data() + t.size(), scalar_components) || scalar_components < 1 ||
          scalar_components > 4)
        return error(tok, ErrorCode::InvalidInput, "SCALARS: bad component count " + quote(t));
      if (io_detail::lowercase(std::string(tok.peek())) == "lookup_table") {
        tok.next();
        tok.next();  // table name
      }
    } else {
      tok.next();  // table name
    }
    return begin_numbers(tok, "SCALARS", n * static_cast<size_t>(scalar_components), false, Then::Skipped);
  }
  if (key == "lookup_table") {
    tok.next();  // name
    std::int64_t entries = 0;
    if (Status s = read_count(tok, "LOOKUP_TABLE", 4, entries); !s) return s;
    return begin_numbers(tok, "LOOKUP_TABLE", 4 * static_cast<size_t>(entries), false, Then::Skipped);
  }
  if (key == "color_scalars") {
    if (Status s = need_data_section(); !s) return s;
    tok.next();  // name
    if (Status s = read_count(tok, "COLOR_SCALARS", 0, components); !s) return s;
    if (components < 1 || components > 4)
      return error(tok, ErrorCode::InvalidInput, "COLOR_SCALARS: bad component count");
    return begin_numbers(tok, "COLOR_SCALARS", n * components, true, Then::ColorScalars);
  }
  if (key == "vectors" || key == "normals" || key == "tensors") {
    if (Status s = need_data_section(); !s) return s;
    tok.next();  // name
    tok.next();  // type
    const size_t per = key == "tensors" ? 9 : 3;
    if (static_cast<std::uint64_t>(n) * per * 2 > tok.remaining() + 1)
      return error(tok, ErrorCode::Truncated, "truncated: " + io_detail::lowercase(key) + " for " + std::to_string(n) +
                                                  " items do not fit in the bytes left");
    if (key == "normals" && point_data) return begin_numbers(tok, "NORMALS", 3 * n, true, Then::Normals);
    return begin_numbers(tok, "VECTORS", per * n, false, Then::Skipped);
  }
  if (key == "texture_coordinates") {
    if (Status s = need_data_section(); !s) return s;
    tok.next();  // name
    if (Status s = read_count(tok, "TEXTURE_COORDINATES", 0, dim); !s) return s;
    if (dim < 1 || dim > 3)
      return error(tok, ErrorCode::InvalidInput, "TEXTURE_COORDINATES: dimension must be 1, 2 or 3");
    tok.next();  // type
    return begin_numbers(tok, "TEXTURE_COORDINATES", n * dim, true, Then::TexCoords);
  }
  if (key == "field") {
    tok.next();  // name
    if (Status s = read_count(tok, "FIELD", 4, field_arrays_left); !s) return s;
    if (!tok.starved() && field_arrays_left > 0) phase = Phase::FieldArrayHead;
    return Status::success();
  }
  return error(tok, ErrorCode::InvalidInput, "unknown keyword " + quote(key));
}

Status VtkStreamReader::State::field_array_head(WindowTokenizer& tok) {
  tok.next();  // array name
  std::int64_t array_components = 0, tuples = 0;
  if (Status s = read_count(tok, "FIELD array", 0, array_components); !s) return s;
  if (Status s = read_count(tok, "FIELD array", static_cast<std::uint64_t>(array_components), tuples); !s) return s;
  tok.next();  // type
  return begin_numbers(tok, "FIELD array", static_cast<size_t>(array_components * tuples), false, Then::FieldArray);
}

// Reads the numbers at hand; a missing one is truncation, a bad one invalid
// input. Stops (starved) before a number the bytes at hand do not hold.
Status VtkStreamReader::State::numbers(WindowTokenizer& tok) {
  while (done < count) {
    const WindowTokenizer before = tok;
    const std::string_view t = tok.next();
    if (tok.starved()) {
      tok = before;
      return Status::success();
    }
    if (t.empty())
      return error(tok, ErrorCode::Truncated, std::string("truncated: ") + what + " declares " + std::to_string(count) +
                                                  " values but the data ends after " + std::to_string(done));
    if (keep) {
      double& v = values[done];
      if (!io_detail::parse_double(t.data(), t.data() + t.size(), v))
        return error(tok, ErrorCode::InvalidInput, std::string(what) + ": " + quote(t) + " is not a number");
      if (!std::isfinite(v)) return error(tok, ErrorCode::InvalidInput, std::string(what) + ": NaN or infinite value");
    }
    ++done;
  }
  phase = Phase::Keyword;
  return numbers_done(tok);
}

Status VtkStreamReader::State::to_ints(WindowTokenizer& tok, std::vector<std::int64_t>& out) {
  out.resize(count);
  for (size_t i = 0; i < count; ++i) {
    if (values[i] != std::floor(values[i]) || std::abs(values[i]) > 4e18)
      return error(tok, ErrorCode::InvalidInput, std::string(what) + ": " + io_detail::format_double(values[i]) +
                                                     " is not an integer");
    out[i] = static_cast<std::int64_t>(values[i]);
  }
  return Status::success();
}

// The numbers are all read: what they become.
Status VtkStreamReader::State::numbers_done(WindowTokenizer& tok) {
  switch (then) {
    case Then::Points: {
      const std::int64_t n = points_declared;
      mesh.positions.resize(n);
      for (std::int64_t i = 0; i < n; ++i) mesh.positions[i] = Vec3(values[3 * i], values[3 * i + 1], values[3 * i + 2]);
      num_points = static_cast<int>(n);
      have_points = true;
      return Status::success();
    }
    case Then::Offsets:
      if (Status s = to_ints(tok, offsets); !s) return s;
      phase = Phase::ConnectivityHead;
      return Status::success();
    case Then::Connectivity:
      if (Status s = to_ints(tok, connectivity); !s) return s;
      for (size_t i = 0; i < offsets.size(); ++i)
        if (offsets[i] < 0 || offsets[i] > cell_numbers || (i > 0 && offsets[i] < offsets[i - 1]))
          return error(tok, ErrorCode::InvalidInput,
                       std::string(what) + ": offsets are not increasing within the connectivity");
      return cells_done(tok);
    case Then::LegacyCells: {
      std::vector<std::int64_t> flat;
      if (Status s = to_ints(tok, flat); !s) return s;
      offsets.clear();
      connectivity.clear();
      offsets.push_back(0);
      size_t pos = 0;
      for (std::int64_t c = 0; c < cells; ++c) {
        if (pos >= flat.size() || flat[pos] < 0 || static_cast<std::uint64_t>(flat[pos]) > flat.size() - pos - 1)
          return error(tok, ErrorCode::InvalidInput, "wrong counts: " + std::string(what) + " declares " +
                                                         std::to_string(cells) + " cells in " +
                                                         std::to_string(cell_numbers) + " numbers, but cell " +
                                                         std::to_string(c) + " does not fit");
        const std::int64_t n = flat[pos];
        connectivity.insert(connectivity.end(), flat.begin() + pos + 1, flat.begin() + pos + 1 + n);
        pos += static_cast<size_t>(n) + 1;
        offsets.push_back(static_cast<std::int64_t>(connectivity.size()));
      }
      if (pos != flat.size())
        return error(tok, ErrorCode::InvalidInput, "wrong counts: " + std::string(what) + " declares " +
                                                       std::to_string(cell_numbers) + " numbers but its " +
                                                       std::to_string(cells) + " cells use " + std::to_string(pos));
      return cells_done(tok);
    }
    case Then::ColorScalars: {
      const size_t n = static_cast<size_t>(attribute_count);
      if (point_data && components >= 3) {
        mesh.colors.resize(n);
        for (size_t i = 0; i < n; ++i)
          mesh.colors[i] = Vec3(values[i * components], values[i * components + 1], values[i * components + 2]);
      }
      return Status::success();
    }
    case Then::Normals: {
      const size_t n = static_cast<size_t>(attribute_count);
      mesh.normals.resize(n);
      for (size_t i = 0; i < n; ++i) mesh.normals[i] = Vec3(values[3 * i], values[3 * i + 1], values[3 * i + 2]);
      return Status::success();
    }
    case Then::TexCoords:
      if (point_data) {
        const size_t n = static_cast<size_t>(attribute_count);
        mesh.uvs.resize(n);
        for (size_t i = 0; i < n; ++i) mesh.uvs[i] = Vec2(values[i * dim], dim > 1 ? values[i * dim + 1] : 0.0);
      }
      return Status::success();
    case Then::FieldArray:
      if (--field_arrays_left > 0) phase = Phase::FieldArrayHead;
      return Status::success();
    case Then::Skipped:
      return Status::success();
  }
  return Status::success();
}

// A cell section's offsets and connectivity are whole: its triangles.
Status VtkStreamReader::State::cells_done(WindowTokenizer& tok) {
  if (!polygons && !strips) return Status::success();
  for (std::int64_t id : connectivity)
    if (id < 0 || id >= num_points)
      return error(tok, ErrorCode::InvalidInput, std::string(what) + " refers to point " + std::to_string(id) +
                                                     " but there are only " + std::to_string(num_points) + " points");
  for (size_t c = 0; c + 1 < offsets.size(); ++c) {
    const std::int64_t* ids = connectivity.data() + offsets[c];
    const std::int64_t n = offsets[c + 1] - offsets[c];
    if (polygons) {
      if (n < 3)
        return error(tok, ErrorCode::InvalidInput, "polygon " + std::to_string(c) + " has " + std::to_string(n) +
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

// One step: a head read whole (or, starved, left to be read again) or the
// numbers at hand.
Status VtkStreamReader::State::step(WindowTokenizer& tok) {
  if (phase == Phase::Numbers) return numbers(tok);
  WindowTokenizer head = tok;
  Status s;
  switch (phase) {
    case Phase::Header: s = header(head); break;
    case Phase::Keyword: s = keyword(head); break;
    case Phase::ConnectivityHead: s = connectivity_head(head); break;
    case Phase::FieldArrayHead: s = field_array_head(head); break;
    default: break;
  }
  if (head.starved()) return Status::success();  // tok stays at the head's start
  tok = head;
  return s;
}

Status VtkStreamReader::State::process(const std::uint8_t* buf, size_t n, std::uint64_t base, bool final,
                                       size_t& used) {
  // Not final: the bytes at hand end after their last white space, so a
  // number cut by the chunk's end is not taken for a whole one.
  size_t limit = n;
  if (!final)
    while (limit > 0 && !io_detail::is_space(static_cast<char>(buf[limit - 1]))) --limit;
  const char* text = reinterpret_cast<const char*>(buf);
  WindowTokenizer tok(text, text + limit, final, base, bytes.total, carry_line);
  for (;;) {
    const Phase before = phase;
    const size_t at = tok.offset();
    if (Status s = step(tok); !s) return s;
    if (phase == Phase::Done) break;
    // No progress: the rest comes with the next bytes.
    if (phase == before && tok.offset() == at && (phase != Phase::Numbers || done < count)) break;
  }
  used = tok.offset();
  carry_line = tok.line();
  return Status::success();
}

Status VtkStreamReader::State::build(TriMesh& out, GeometryKind& kind) {
  if (!have_points || num_points == 0) return Status::error(ErrorCode::Empty, "empty: the VTK file has no POINTS");
  const size_t nv = mesh.positions.size();
  // Attributes of another size than the points would be unusable.
  if (mesh.normals.size() != nv) mesh.normals.clear();
  if (mesh.colors.size() != nv) mesh.colors.clear();
  if (mesh.uvs.size() != nv) mesh.uvs.clear();
  kind = mesh.triangles.empty() ? GeometryKind::PointCloud : GeometryKind::Mesh;
  out = std::move(mesh);
  return Status::success();
}

VtkStreamReader::VtkStreamReader(std::uint64_t total_size) : s_(std::make_unique<State>(total_size)) {}

VtkStreamReader::~VtkStreamReader() = default;

std::uint64_t VtkStreamReader::bytes_received() const { return s_->bytes.received; }

std::uint64_t VtkStreamReader::declared_vertices() const {
  return s_->bytes.error.ok() ? static_cast<std::uint64_t>(s_->points_declared) : 0;
}

Status VtkStreamReader::push(const std::uint8_t* data, size_t size) {
  State& st = *s_;
  const std::uint64_t data_base = st.bytes.received;
  if (Status s = st.bytes.accept(size); !s) return s;
  Status s = io_detail::guard_allocation([&] {
    return io_detail::push_carried(st.carry, st.carry_base, data_base, data, size,
                                   [&st](const std::uint8_t* d, size_t n, std::uint64_t at, bool final, size_t& used) {
                                     return st.process(d, n, at, final, used);
                                   });
  });
  if (!s) {
    st.bytes.error = s;
    st.mesh = TriMesh();
    st.carry = Bytes();
    st.values = {};
  }
  return s;
}

Status VtkStreamReader::finish(TriMesh& mesh, GeometryKind& kind) {
  State& st = *s_;
  mesh = TriMesh();
  kind = GeometryKind::PointCloud;
  if (Status s = st.bytes.complete(); !s) return s;
  Status s = io_detail::guard_allocation([&] {
    if (st.bytes.total == 0) return Status::error(ErrorCode::Empty, "empty input: no bytes");
    size_t used = 0;
    if (Status e = st.process(st.carry.data(), st.carry.size(), st.carry_base, true, used); !e) return e;
    if (st.phase != State::Phase::Done)
      return Status::error(ErrorCode::Internal, "the VTK reader stopped before the end of the data");
    return st.build(mesh, kind);
  });
  st.carry = Bytes();
  st.values = {};
  st.offsets = {};
  st.connectivity = {};
  st.mesh = TriMesh();
  if (!s) {
    mesh = TriMesh();
    kind = GeometryKind::PointCloud;
  }
  st.bytes.error = s.ok() ? Status::error(ErrorCode::Internal, "the reader has already finished") : s;
  return s;
}

Status read_vtk(const std::uint8_t* data, size_t size, TriMesh& mesh, GeometryKind& kind) {
  mesh = TriMesh();
  kind = GeometryKind::PointCloud;
  if (size == 0) return Status::error(ErrorCode::Empty, "empty input: no bytes");
  if (Status s = io_detail::check_input_size(size, kMaxGeometryBytes); !s) return s;
  VtkStreamReader reader(size);
  if (Status s = reader.push(data, size); !s) return s;
  return reader.finish(mesh, kind);
}

}  // namespace lk
