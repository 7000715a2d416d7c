// Wavefront OBJ (+ MTL) reader and writer.
//
// OBJ indexes positions, uvs and normals separately. Our TriMesh has one
// position per vertex, so uvs become per-vertex when every vertex uses a
// single uv throughout, and per-corner (uv_per_corner) otherwise, which keeps
// texture seams exact. Normals are averaged per vertex. The reader is a
// stream (ObjStreamReader, scan_stream.h) fed the file line by line; read_obj
// feeds it the whole buffer at once.
#include "io/io.h"
#include "io/scan_stream.h"
#include "io/text_scan.h"

#include <charconv>
#include <climits>
#include <cmath>

namespace lk {

using io_detail::quote;

namespace {

struct Corner {
  int v = -1, vt = -1, vn = -1;
};

enum class IndexResult { Ok, NotAnInteger, OutOfRange };

// Resolves a 1-based (or negative, relative) OBJ index against the count
// items defined so far. Every comparison is made on the parsed 64-bit value
// without negating it: -2^63 has no positive counterpart.
IndexResult resolve_index(std::string_view text, size_t count, int& out) {
  out = -1;
  const char* b = text.data();
  const char* e = b + text.size();
  if (b != e && *b == '+') ++b;
  std::int64_t i = 0;
  const auto r = std::from_chars(b, e, i);
  if (r.ptr != e || b == e) return IndexResult::NotAnInteger;
  if (r.ec == std::errc::result_out_of_range) return IndexResult::OutOfRange;
  if (r.ec != std::errc()) return IndexResult::NotAnInteger;
  // count <= INT_MAX (the vertex loop refuses more), so it fits an int64.
  const std::int64_t n = static_cast<std::int64_t>(count);
  if (i >= 1 && i <= n) {
    out = static_cast<int>(i - 1);
    return IndexResult::Ok;
  }
  if (i <= -1 && i >= -n) {
    out = static_cast<int>(n + i);
    return IndexResult::Ok;
  }
  return IndexResult::OutOfRange;
}

// A normal scaled to unit length without overflowing on huge components
// (1e300 squared is inf); zero stays zero.
Vec3 unit_or_zero(const Vec3& n) {
  const double scale = n.cwiseAbs().maxCoeff();
  if (!(scale > 0)) return Vec3::Zero();
  const Vec3 m = n / scale;
  return m / m.norm();
}

// OBJ statements are short lowercase words ("v", "usemtl", "c_interp"); a
// line starting with anything else means the input is not OBJ text.
bool is_statement_name(std::string_view key) {
  if (key.size() > 16) return false;
  for (char c : key)
    if (!((c >= 'a' && c <= 'z') || c == '_')) return false;
  return true;
}

// "map_Kd [-options ...] file": the file is the last token.
std::string map_file(std::string_view rest) {
  io_detail::Tokenizer tok(rest.data(), rest.data() + rest.size());
  std::string_view last;
  for (std::string_view t = tok.next(); !t.empty(); t = tok.next()) last = t;
  return std::string(last);
}

// Material name -> map_Kd, in file order.
std::vector<std::pair<std::string, std::string>> parse_mtl(const std::string& text) {
  std::vector<std::pair<std::string, std::string>> materials;
  io_detail::Tokenizer tok(text.data(), text.data() + text.size());
  while (!tok.at_end()) {
    const std::string_view key = tok.next_on_line();
    if (key == "newmtl") {
      materials.push_back({std::string(tok.rest_of_line()), ""});
    } else if (key == "map_Kd" && !materials.empty()) {
      materials.back().second = map_file(tok.rest_of_line());
    }
    tok.skip_line();
  }
  return materials;
}

}  // namespace

std::string obj_mtllib(const std::uint8_t* data, size_t size) {
  const char* text = reinterpret_cast<const char*>(data);
  io_detail::Tokenizer tok(text, text + size);
  while (!tok.at_end()) {
    if (tok.next_on_line() == "mtllib") return std::string(tok.rest_of_line());
    tok.skip_line();
  }
  return "";
}

// The reader's state between pushes: the vertices, uvs, normals and
// triangles read so far. Each whole line is one statement; uvs and normals
// per vertex are resolved at finish.
struct ObjStreamReader::State {
  State(std::uint64_t total_size, std::string mtl) : bytes(total_size, kMaxGeometryBytes), mtl_text(std::move(mtl)) {}

  io_detail::StreamBytes bytes;
  io_detail::LineSplitter lines;
  std::string mtl_text;
  int line_number = 0;

  TriMesh mesh;
  std::vector<Vec3> vertex_colors;
  bool all_have_colors = true;
  std::vector<Vec2> texcoords;
  std::vector<Vec3> normals;
  std::vector<Corner> face;
  std::string used_material;
  int faces_with_uv = 0, faces_without_uv = 0;
  // Each face's corners are used as it is read (triangles, uvs, normals),
  // not held until the end: a corner took 12 bytes, three a triangle, on
  // top of the triangle's own 12 at the end (issue 39).
  std::vector<int> corner_uv;     // the texture coordinate of each triangle corner (faces with uv)
  std::vector<int> uv_of_vertex;  // the first corner's texture coordinate per vertex, or -1
  bool uv_per_vertex = true;      // so far every vertex's corners have one uv
  std::vector<Vec3> normal_sum;   // per vertex: the unit normals of its corners, summed
  bool any_normal = false;

  Status statement(std::string_view line);
  void add_corner(const Corner& c);
  Status build(TriMesh& out, GeometryKind& kind);
  void clear() {
    lines.clear();
    mesh = TriMesh();
    vertex_colors = {};
    texcoords = {};
    normals = {};
    corner_uv = {};
    uv_of_vertex = {};
    normal_sum = {};
  }
};

// One triangle corner, in file order: its uv and normal are taken now.
void ObjStreamReader::State::add_corner(const Corner& c) {
  if (c.vt >= 0) {
    corner_uv.push_back(c.vt);
    if (uv_of_vertex.size() <= static_cast<size_t>(c.v)) uv_of_vertex.resize(mesh.positions.size(), -1);
    if (uv_of_vertex[c.v] < 0) uv_of_vertex[c.v] = c.vt;
    else if (texcoords[uv_of_vertex[c.v]] != texcoords[c.vt]) uv_per_vertex = false;
  }
  if (c.vn >= 0) {
    any_normal = true;
    if (normal_sum.size() <= static_cast<size_t>(c.v)) normal_sum.resize(mesh.positions.size(), Vec3::Zero());
    normal_sum[c.v] += normals[c.vn];
  }
}

Status ObjStreamReader::State::statement(std::string_view line) {
  ++line_number;
  io_detail::Tokenizer tok(line.data(), line.data() + line.size());
  auto error_at = [this](ErrorCode code, const std::string& what) {
    return Status::error(code, "line " + std::to_string(line_number) + ": " + what);
  };
  auto read_reals = [&tok](double* out, int min_count, int max_count, int& got, std::string_view& bad) {
    got = 0;
    for (std::string_view t = tok.next_on_line(); !t.empty(); t = tok.next_on_line()) {
      if (got == max_count) return true;  // extra fields (e.g. vt's w) are ignored
      if (!io_detail::parse_double(t.data(), t.data() + t.size(), out[got])) {
        bad = t;
        return false;
      }
      ++got;
    }
    return got >= min_count;
  };

  if (tok.at_end()) return Status::success();  // a blank line
  const std::string_view key = tok.next_on_line();
  if (key.empty() || key[0] == '#') {
    // a comment
  } else if (key == "v") {
    double x[6];
    int got = 0;
    std::string_view bad;
    if (!read_reals(x, 3, 6, got, bad))
      return error_at(ErrorCode::InvalidInput,
                      bad.empty() ? "a vertex needs 3 coordinates" : "vertex coordinate " + quote(bad) + " is not a number");
    const Vec3 p(x[0], x[1], x[2]);
    if (!p.allFinite())
      return error_at(ErrorCode::InvalidInput, "vertex " + std::to_string(mesh.positions.size() + 1) +
                                                   " has a NaN or infinite coordinate");
    if (mesh.positions.size() >= static_cast<size_t>(INT_MAX))
      return error_at(ErrorCode::TooLarge, "too many vertices");
    mesh.positions.push_back(p);
    if (got == 6 && all_have_colors) {
      const Vec3 color(x[3], x[4], x[5]);
      if (!color.allFinite())
        return error_at(ErrorCode::InvalidInput, "vertex " + std::to_string(mesh.positions.size()) +
                                                     " has a NaN or infinite color");
      vertex_colors.push_back(color);
    } else {
      all_have_colors = false;
    }
  } else if (key == "vt") {
    double x[3];
    int got = 0;
    std::string_view bad;
    if (!read_reals(x, 1, 3, got, bad))
      return error_at(ErrorCode::InvalidInput, "texture coordinate " + quote(bad) + " is not a number");
    const Vec2 uv(x[0], got > 1 ? x[1] : 0.0);
    if (!uv.allFinite()) return error_at(ErrorCode::InvalidInput, "NaN or infinite texture coordinate");
    texcoords.push_back(uv);
  } else if (key == "vn") {
    double x[3];
    int got = 0;
    std::string_view bad;
    if (!read_reals(x, 3, 3, got, bad))
      return error_at(ErrorCode::InvalidInput,
                      bad.empty() ? "a normal needs 3 components" : "normal component " + quote(bad) + " is not a number");
    const Vec3 n(x[0], x[1], x[2]);
    if (!n.allFinite()) return error_at(ErrorCode::InvalidInput, "NaN or infinite normal");
    // Unit length now, so that the per-vertex sums below stay finite.
    normals.push_back(unit_or_zero(n));
  } else if (key == "f") {
    face.clear();
    for (std::string_view t = tok.next_on_line(); !t.empty(); t = tok.next_on_line()) {
      // v, v/vt, v//vn or v/vt/vn
      Corner c;
      const size_t s1 = t.find('/');
      const std::string_view vs = t.substr(0, s1);
      std::string_view ts, ns;
      if (s1 != std::string_view::npos) {
        const size_t s2 = t.find('/', s1 + 1);
        ts = t.substr(s1 + 1, s2 == std::string_view::npos ? std::string_view::npos : s2 - s1 - 1);
        if (s2 != std::string_view::npos) ns = t.substr(s2 + 1);
      }
      const size_t nv = mesh.positions.size();
      IndexResult r = resolve_index(vs, nv, c.v);
      if (r == IndexResult::NotAnInteger)
        return error_at(ErrorCode::InvalidInput, "face corner " + quote(t) + " is not a vertex index");
      if (r == IndexResult::OutOfRange)
        return error_at(ErrorCode::InvalidInput, "face refers to vertex " + std::string(vs.substr(0, 24)) +
                                                     (vs.size() > 24 ? "..." : "") + " but only " +
                                                     std::to_string(nv) + " vertices are defined before it");
      if (!ts.empty()) {
        r = resolve_index(ts, texcoords.size(), c.vt);
        if (r != IndexResult::Ok)
          return error_at(ErrorCode::InvalidInput, "face refers to texture coordinate " + quote(ts) + " but only " +
                                                       std::to_string(texcoords.size()) + " are defined");
      }
      if (!ns.empty()) {
        r = resolve_index(ns, normals.size(), c.vn);
        if (r != IndexResult::Ok)
          return error_at(ErrorCode::InvalidInput, "face refers to normal " + quote(ns) + " but only " +
                                                       std::to_string(normals.size()) + " are defined");
      }
      face.push_back(c);
    }
    if (face.size() < 3)
      return error_at(ErrorCode::InvalidInput,
                      "a face has " + std::to_string(face.size()) + " corners (at least 3 needed)");
    int with_uv = 0;
    for (const Corner& c : face) with_uv += c.vt >= 0;
    if (with_uv != 0 && with_uv != static_cast<int>(face.size()))
      return error_at(ErrorCode::InvalidInput, "a face has texture coordinates on some corners but not others");
    (with_uv ? faces_with_uv : faces_without_uv)++;
    if (faces_with_uv && faces_without_uv)
      return error_at(ErrorCode::InvalidInput, "some faces have texture coordinates and others do not");
    for (size_t k = 1; k + 1 < face.size(); ++k) {
      mesh.triangles.push_back({face[0].v, face[k].v, face[k + 1].v});
      add_corner(face[0]);
      add_corner(face[k]);
      add_corner(face[k + 1]);
    }
  } else if (key == "usemtl") {
    if (used_material.empty()) used_material = std::string(tok.rest_of_line());
  } else if (is_statement_name(key)) {
    // mtllib (read by obj_mtllib), groups, smoothing groups, lines and
    // free-form geometry: nothing we use.
  } else {
    return error_at(ErrorCode::InvalidInput, "not an OBJ statement: " + quote(key));
  }
  return Status::success();
}

// Every line has been read: the uvs and normals the corners gave.
Status ObjStreamReader::State::build(TriMesh& out, GeometryKind& kind) {
  const int nv = mesh.num_vertices();
  if (nv == 0) return Status::error(ErrorCode::Empty, "empty: the OBJ has no vertices");
  if (all_have_colors && static_cast<int>(vertex_colors.size()) == nv) mesh.colors = std::move(vertex_colors);
  const size_t nt = mesh.triangles.size();

  if (faces_with_uv > 0) {
    // Per-vertex when each vertex always uses one uv and every vertex has one.
    uv_of_vertex.resize(nv, -1);
    bool per_vertex = uv_per_vertex;
    for (int v = 0; v < nv && per_vertex; ++v) per_vertex = uv_of_vertex[v] >= 0;
    if (per_vertex) {
      mesh.uvs.resize(nv);
      for (int v = 0; v < nv; ++v) mesh.uvs[v] = texcoords[uv_of_vertex[v]];
    } else {
      mesh.uvs.resize(corner_uv.size());
      for (size_t i = 0; i < corner_uv.size(); ++i) mesh.uvs[i] = texcoords[corner_uv[i]];
      mesh.uv_per_corner = true;
    }
  }

  if (any_normal) {
    normal_sum.resize(nv, Vec3::Zero());
    bool complete = true;
    for (Vec3& n : normal_sum) {
      n = unit_or_zero(n);
      if (n == Vec3::Zero()) complete = false;
    }
    if (complete) mesh.normals = std::move(normal_sum);
  } else if (nt == 0 && static_cast<int>(normals.size()) == nv) {
    mesh.normals = std::move(normals);  // a point cloud stored as v + vn lines (now unit length)
  }

  if (!mtl_text.empty()) {
    const auto materials = parse_mtl(mtl_text);
    for (const auto& [name, file] : materials)
      if (!file.empty() && (used_material.empty() || name == used_material)) {
        mesh.texture_name = file;
        break;
      }
  }
  kind = nt > 0 ? GeometryKind::Mesh : GeometryKind::PointCloud;
  out = std::move(mesh);
  return Status::success();
}

ObjStreamReader::ObjStreamReader(std::uint64_t total_size, std::string mtl_text)
    : s_(std::make_unique<State>(total_size, std::move(mtl_text))) {}

ObjStreamReader::~ObjStreamReader() = default;

std::uint64_t ObjStreamReader::bytes_received() const { return s_->bytes.received; }
std::uint64_t ObjStreamReader::vertices_read() const { return s_->mesh.positions.size(); }

Status ObjStreamReader::push(const std::uint8_t* data, size_t size) {
  State& st = *s_;
  if (Status s = st.bytes.accept(size); !s) return s;
  Status s = io_detail::guard_allocation(
      [&] { return st.lines.push(data, size, [&st](std::string_view line) { return st.statement(line); }); });
  if (!s) {
    st.bytes.error = s;
    st.clear();
  }
  return s;
}

Status ObjStreamReader::finish(TriMesh& mesh, GeometryKind& kind) {
  State& st = *s_;
  mesh = TriMesh();
  kind = GeometryKind::PointCloud;
  if (Status s = st.bytes.complete(); !s) return s;
  Status s = io_detail::guard_allocation([&] {
    if (st.bytes.total == 0) return Status::error(ErrorCode::Empty, "empty input: no bytes");
    if (Status e = st.lines.finish([&st](std::string_view line) { return st.statement(line); }); !e) return e;
    return st.build(mesh, kind);
  });
  st.clear();
  if (!s) {
    mesh = TriMesh();  // never hand back half a mesh
    kind = GeometryKind::PointCloud;
  }
  st.bytes.error = s.ok() ? Status::error(ErrorCode::Internal, "the reader has already finished") : s;
  return s;
}

Status read_obj(const std::uint8_t* data, size_t size, TriMesh& mesh, GeometryKind& kind,
                const std::string& mtl_text) {
  mesh = TriMesh();
  kind = GeometryKind::PointCloud;
  if (Status s = io_detail::check_input_size(size, kMaxGeometryBytes); !s) return s;
  ObjStreamReader reader(size, mtl_text);
  if (Status s = reader.push(data, size); !s) return s;
  return reader.finish(mesh, kind);
}

std::string write_obj(const TriMesh& mesh, const std::string& mtl_file) {
  const size_t nv = mesh.positions.size();
  const bool has_colors = mesh.colors.size() == nv && nv > 0;
  const bool has_normals = mesh.normals.size() == nv && nv > 0;
  const bool per_corner = mesh.uv_per_corner && mesh.uvs.size() == 3 * mesh.triangles.size() && !mesh.uvs.empty();
  const bool per_vertex_uv = !mesh.uv_per_corner && mesh.uvs.size() == nv && nv > 0;
  std::string out = "# written by likeness\n";
  out.reserve(64 * nv + 32 * mesh.triangles.size());  // a level-3 head: ~18 MB, written once
  if (!mtl_file.empty()) out += "mtllib " + mtl_file + "\n";
  for (size_t i = 0; i < nv; ++i) {
    out += "v";
    for (int k = 0; k < 3; ++k) {
      out += ' ';
      io_detail::append_double(out, mesh.positions[i][k]);
    }
    if (has_colors)
      for (int k = 0; k < 3; ++k) {
        out += ' ';
        io_detail::append_double(out, mesh.colors[i][k]);
      }
    out += '\n';
  }
  if (per_vertex_uv || per_corner) {
    for (const Vec2& uv : mesh.uvs) {
      out += "vt ";
      io_detail::append_double(out, uv.x());
      out += ' ';
      io_detail::append_double(out, uv.y());
      out += '\n';
    }
  }
  if (has_normals)
    for (const Vec3& n : mesh.normals) {
      out += "vn";
      for (int k = 0; k < 3; ++k) {
        out += ' ';
        io_detail::append_double(out, n[k]);
      }
      out += '\n';
    }
  if (!mtl_file.empty()) out += "usemtl material_0\n";
  for (size_t f = 0; f < mesh.triangles.size(); ++f) {
    out += "f";
    for (int k = 0; k < 3; ++k) {
      const long long v = mesh.triangles[f][k] + 1LL;
      out += ' ';
      io_detail::append_int(out, v);
      if (per_corner) {
        out += '/';
        io_detail::append_int(out, static_cast<long long>(3 * f + k + 1));
      } else if (per_vertex_uv) {
        out += '/';
        io_detail::append_int(out, v);
      }
      if (has_normals) {
        out += per_corner || per_vertex_uv ? "/" : "//";
        io_detail::append_int(out, v);
      }
    }
    out += '\n';
  }
  return out;
}

std::string write_mtl(const std::string& texture_file) {
  return "# written by likeness\n"
         "newmtl material_0\n"
         "Ka 1 1 1\n"
         "Kd 1 1 1\n"
         "Ks 0 0 0\n"
         "illum 1\n"
         "map_Kd " + texture_file + "\n";
}

}  // namespace lk
