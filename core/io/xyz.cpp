// XYZ point clouds: one point per line, "x y z" with optional normals and/or
// colors. Columns may be separated by spaces, tabs or commas; '#' and '//'
// start comment lines (CloudCompare writes a "//X Y Z ..." header). Leica
// style .pts is read too: a first line holding the point count, then
// "x y z intensity [r g b]" (4 or 7 columns; intensity is dropped).
//
// Six columns are ambiguous (normals or colors): they are normals when every
// row's extra triple has unit length, colors otherwise. With nine columns the
// unit-length triple is the normal and the other the color. Colors above 1
// anywhere in the file are taken as 0..255. The reader is a stream
// (XyzStreamReader, scan_stream.h) fed the file line by line; read_xyz feeds
// it the whole buffer at once.
#include "io/io.h"
#include "io/scan_stream.h"
#include "io/text_scan.h"

#include <algorithm>
#include <cmath>

namespace lk {

using io_detail::quote;

namespace {

bool is_separator(char c) { return c == ' ' || c == '\t' || c == ',' || c == ';' || c == '\r'; }

// |v| within 2 % of 1: the test that tells a normal from a color.
bool unit_length(const Vec3& v) {
  const double len = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  return !(std::abs(len - 1.0) > 0.02);
}

}  // namespace

// The reader's state between pushes. Each whole line is one point (or the
// .pts count, a comment, a blank); the extra columns are kept as triples and
// told apart (normal or color, color scale) at finish from what every row
// showed, so the file's values are held once, as the cloud's own arrays.
struct XyzStreamReader::State {
  explicit State(std::uint64_t total_size) : bytes(total_size, kMaxGeometryBytes) {}

  io_detail::StreamBytes bytes;
  io_detail::LineSplitter lines;
  int columns = 0, first_data_line = 0;
  int line = 0;
  double declared_count = -1;  // from a .pts count line
  std::vector<Vec3> positions;
  std::vector<Vec3> extra_a;  // columns 3-5 (4-6 with 7 columns: x y z intensity r g b)
  std::vector<Vec3> extra_b;  // columns 6-8 of 9
  bool a_unit = true;         // every row's extra_a has unit length
  bool a_above_1 = false, b_above_1 = false;

  Status row(std::string_view text);
  Status build(PointCloud& cloud);
  void clear() {
    lines.clear();
    positions = {};
    extra_a = {};
    extra_b = {};
  }
};

Status XyzStreamReader::State::row(std::string_view text) {
  ++line;
  const char* q = text.data();
  const char* eol = q + text.size();
  while (q < eol && is_separator(*q)) ++q;
  if (q == eol || *q == '#' || (q + 1 < eol && q[0] == '/' && q[1] == '/')) return Status::success();
  double v[9];
  int n = 0;
  while (q < eol) {
    const char* b = q;
    while (q < eol && !is_separator(*q)) ++q;
    if (n == 9)
      return Status::error(ErrorCode::Unsupported, "line " + std::to_string(line) +
                                                       ": more than 9 values; XYZ supports 3 (x y z), 6 (+ normals "
                                                       "or colors) or 9 (+ both)");
    if (!io_detail::parse_double(b, q, v[n]))
      return Status::error(ErrorCode::InvalidInput, "line " + std::to_string(line) + ": " +
                                                        quote(std::string_view(b, q - b)) + " is not a number");
    if (!std::isfinite(v[n]))
      return Status::error(ErrorCode::InvalidInput, "line " + std::to_string(line) + ": NaN or infinite value");
    ++n;
    while (q < eol && is_separator(*q)) ++q;
  }
  if (columns == 0 && n == 1 && declared_count < 0 && v[0] >= 0 && v[0] == std::floor(v[0])) {
    declared_count = v[0];
    return Status::success();
  }
  if (columns == 0) {
    if (n != 3 && n != 4 && n != 6 && n != 7 && n != 9)
      return Status::error(ErrorCode::Unsupported, "line " + std::to_string(line) + " has " + std::to_string(n) +
                                                       " values; XYZ supports 3 (x y z), 4 (+ intensity), 6 (+ "
                                                       "normals or colors), 7 (+ intensity and colors) or 9 (+ "
                                                       "normals and colors)");
    columns = n;
    first_data_line = line;
  } else if (n != columns) {
    return Status::error(ErrorCode::InvalidInput, "wrong counts: line " + std::to_string(line) + " has " +
                                                      std::to_string(n) + " values but line " +
                                                      std::to_string(first_data_line) + " has " +
                                                      std::to_string(columns));
  }
  positions.push_back(Vec3(v[0], v[1], v[2]));
  if (columns >= 6) {
    const int a = columns == 7 ? 4 : 3;
    const Vec3 ea(v[a], v[a + 1], v[a + 2]);
    a_unit = a_unit && unit_length(ea);
    a_above_1 = a_above_1 || ea[0] > 1.0 || ea[1] > 1.0 || ea[2] > 1.0;
    extra_a.push_back(ea);
  }
  if (columns == 9) {
    const Vec3 eb(v[6], v[7], v[8]);
    b_above_1 = b_above_1 || eb[0] > 1.0 || eb[1] > 1.0 || eb[2] > 1.0;
    extra_b.push_back(eb);
  }
  return Status::success();
}

// Every line has been read: which triple is the normal and which the color
// (and whether colors are 0..255) is decided from all the rows.
Status XyzStreamReader::State::build(PointCloud& cloud) {
  if (columns == 0) return Status::error(ErrorCode::Empty, "empty: no points (only blank or comment lines)");
  const size_t rows = positions.size();
  if (declared_count >= 0 && declared_count != static_cast<double>(rows))
    return Status::error(ErrorCode::InvalidInput, "wrong counts: the first line declares " +
                                                      io_detail::format_double(declared_count) + " points but " +
                                                      std::to_string(rows) + " follow");
  std::vector<Vec3>* normals = nullptr;
  std::vector<Vec3>* colors = nullptr;
  bool colors_above_1 = false;
  if (columns == 6) {
    if (a_unit) normals = &extra_a;
    else colors = &extra_a, colors_above_1 = a_above_1;
  } else if (columns == 7) {
    colors = &extra_a, colors_above_1 = a_above_1;
  } else if (columns == 9) {
    normals = a_unit ? &extra_a : &extra_b;
    colors = a_unit ? &extra_b : &extra_a;
    colors_above_1 = a_unit ? b_above_1 : a_above_1;
  }
  if (colors && colors_above_1) {
    const double color_scale = 1.0 / 255.0;
    for (Vec3& c : *colors) c = color_scale * c;
  }
  cloud.positions = std::move(positions);
  if (normals) cloud.normals = std::move(*normals);
  if (colors) cloud.colors = std::move(*colors);
  return Status::success();
}

XyzStreamReader::XyzStreamReader(std::uint64_t total_size) : s_(std::make_unique<State>(total_size)) {}

XyzStreamReader::~XyzStreamReader() = default;

std::uint64_t XyzStreamReader::bytes_received() const { return s_->bytes.received; }
std::uint64_t XyzStreamReader::points_read() const { return s_->positions.size(); }
std::uint64_t XyzStreamReader::declared_points() const {
  return s_->declared_count > 0 && s_->declared_count < 1e18 ? static_cast<std::uint64_t>(s_->declared_count) : 0;
}

Status XyzStreamReader::push(const std::uint8_t* data, size_t size) {
  State& st = *s_;
  if (Status s = st.bytes.accept(size); !s) return s;
  Status s = io_detail::guard_allocation(
      [&] { return st.lines.push(data, size, [&st](std::string_view text) { return st.row(text); }); });
  if (!s) {
    st.bytes.error = s;
    st.clear();
  }
  return s;
}

Status XyzStreamReader::finish(PointCloud& cloud) {
  State& st = *s_;
  cloud = PointCloud();
  if (Status s = st.bytes.complete(); !s) return s;
  Status s = io_detail::guard_allocation([&] {
    if (st.bytes.total == 0) return Status::error(ErrorCode::Empty, "empty input: no bytes");
    if (Status e = st.lines.finish([&st](std::string_view text) { return st.row(text); }); !e) return e;
    return st.build(cloud);
  });
  st.clear();
  if (!s) cloud = PointCloud();  // never hand back half a cloud
  st.bytes.error = s.ok() ? Status::error(ErrorCode::Internal, "the reader has already finished") : s;
  return s;
}

Status read_xyz(const std::uint8_t* data, size_t size, PointCloud& cloud) {
  cloud = PointCloud();
  if (Status s = io_detail::check_input_size(size, kMaxGeometryBytes); !s) return s;
  XyzStreamReader reader(size);
  if (Status s = reader.push(data, size); !s) return s;
  return reader.finish(cloud);
}

std::string write_xyz(const PointCloud& cloud) {
  const size_t n = cloud.positions.size();
  const bool has_normals = cloud.normals.size() == n;
  const bool has_colors = cloud.colors.size() == n;
  std::string out;
  for (size_t i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) {
      if (k) out += ' ';
      io_detail::append_double(out, cloud.positions[i][k]);
    }
    if (has_normals)
      for (int k = 0; k < 3; ++k) {
        out += ' ';
        io_detail::append_double(out, cloud.normals[i][k]);
      }
    // Colors as 0..255 integers: never mistaken for a unit normal.
    if (has_colors)
      for (int k = 0; k < 3; ++k) {
        const double c = std::round(std::min(1.0, std::max(0.0, cloud.colors[i][k])) * 255.0);
        out += ' ' + std::to_string(static_cast<int>(c));
      }
    out += '\n';
  }
  return out;
}

}  // namespace lk
