// XYZ point clouds: one point per line, "x y z" with optional normals and/or
// colors. Columns may be separated by spaces, tabs or commas; '#' and '//'
// start comment lines (CloudCompare writes a "//X Y Z ..." header). Leica
// style .pts is read too: a first line holding the point count, then
// "x y z intensity [r g b]" (4 or 7 columns; intensity is dropped).
//
// Six columns are ambiguous (normals or colors): they are normals when every
// row's extra triple has unit length, colors otherwise. With nine columns the
// unit-length triple is the normal and the other the color. Colors above 1
// anywhere in the file are taken as 0..255.
#include "io/io.h"
#include "io/text_scan.h"

#include <algorithm>
#include <cmath>

namespace lk {

using io_detail::quote;

namespace {

bool is_separator(char c) { return c == ' ' || c == '\t' || c == ',' || c == ';' || c == '\r'; }

bool all_unit_length(const std::vector<double>& values, int columns, int first) {
  const size_t rows = values.size() / columns;
  for (size_t r = 0; r < rows; ++r) {
    const double* v = &values[r * columns + first];
    const double len = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (std::abs(len - 1.0) > 0.02) return false;
  }
  return true;
}

}  // namespace

namespace {

Status read_xyz_body(const std::uint8_t* data, size_t size, PointCloud& cloud) {
  if (size == 0) return Status::error(ErrorCode::Empty, "empty input: no bytes");
  const char* p = reinterpret_cast<const char*>(data);
  const char* end = p + size;
  int columns = 0, first_data_line = 0;
  int line = 0;
  double declared_count = -1;  // from a .pts count line
  std::vector<double> values;
  double row[9];
  while (p < end) {
    const char* eol = p;
    while (eol < end && *eol != '\n') ++eol;
    ++line;
    const char* q = p;
    while (q < eol && is_separator(*q)) ++q;
    if (q < eol && *q != '#' && !(q + 1 < eol && q[0] == '/' && q[1] == '/')) {
      int n = 0;
      while (q < eol) {
        const char* b = q;
        while (q < eol && !is_separator(*q)) ++q;
        if (n == 9)
          return Status::error(ErrorCode::Unsupported, "line " + std::to_string(line) +
                                                           ": more than 9 values; XYZ supports 3 (x y z), 6 (+ normals "
                                                           "or colors) or 9 (+ both)");
        if (!io_detail::parse_double(b, q, row[n]))
          return Status::error(ErrorCode::InvalidInput, "line " + std::to_string(line) + ": " +
                                                            quote(std::string_view(b, q - b)) + " is not a number");
        if (!std::isfinite(row[n]))
          return Status::error(ErrorCode::InvalidInput, "line " + std::to_string(line) + ": NaN or infinite value");
        ++n;
        while (q < eol && is_separator(*q)) ++q;
      }
      if (columns == 0 && n == 1 && declared_count < 0 && row[0] >= 0 && row[0] == std::floor(row[0])) {
        declared_count = row[0];
        p = eol < end ? eol + 1 : end;
        continue;
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
      values.insert(values.end(), row, row + n);
    }
    p = eol < end ? eol + 1 : end;
  }
  if (columns == 0) return Status::error(ErrorCode::Empty, "empty: no points (only blank or comment lines)");
  const size_t rows = values.size() / columns;
  if (declared_count >= 0 && declared_count != static_cast<double>(rows))
    return Status::error(ErrorCode::InvalidInput, "wrong counts: the first line declares " +
                                                      io_detail::format_double(declared_count) + " points but " +
                                                      std::to_string(rows) + " follow");

  int normal_column = -1, color_column = -1;
  if (columns == 6) {
    if (all_unit_length(values, 6, 3)) normal_column = 3;
    else color_column = 3;
  } else if (columns == 7) {
    color_column = 4;  // x y z intensity r g b
  } else if (columns == 9) {
    const bool first_is_normal = all_unit_length(values, 9, 3);
    normal_column = first_is_normal ? 3 : 6;
    color_column = first_is_normal ? 6 : 3;
  }
  double color_scale = 1.0;
  if (color_column >= 0) {
    for (size_t i = 0; i < values.size(); i += columns)
      for (int k = 0; k < 3; ++k)
        if (values[i + color_column + k] > 1.0) color_scale = 1.0 / 255.0;
  }
  cloud.positions.resize(rows);
  if (normal_column >= 0) cloud.normals.resize(rows);
  if (color_column >= 0) cloud.colors.resize(rows);
  for (size_t r = 0; r < rows; ++r) {
    const double* v = &values[r * columns];
    cloud.positions[r] = Vec3(v[0], v[1], v[2]);
    if (normal_column >= 0) cloud.normals[r] = Vec3(v[normal_column], v[normal_column + 1], v[normal_column + 2]);
    if (color_column >= 0)
      cloud.colors[r] = color_scale * Vec3(v[color_column], v[color_column + 1], v[color_column + 2]);
  }
  return Status::success();
}

}  // namespace

Status read_xyz(const std::uint8_t* data, size_t size, PointCloud& cloud) {
  cloud = PointCloud();
  if (Status s = io_detail::check_input_size(size, kMaxGeometryBytes); !s) return s;
  Status s = io_detail::guard_allocation([&] { return read_xyz_body(data, size, cloud); });
  if (!s) cloud = PointCloud();  // never hand back half a cloud
  return s;
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
