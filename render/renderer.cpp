// The shared GLES3 / WebGL2 renderer (see renderer.h).
#include "render/renderer.h"

#include "mesh/geometry.h"
#include "render/gl.h"
#include "render/shader_sources.h"

#include <glm/gtc/matrix_inverse.hpp>
#include <glm/gtc/type_ptr.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <iterator>
#include <map>
#include <set>
#include <string>

namespace lk {
namespace {

// Attribute locations, fixed by layout qualifiers in shaders/*.vert.
enum Attribute : GLuint { kPosition = 0, kNormal = 1, kUv = 2, kColor = 3, kBarycentric = 4, kOcclusion = 5, kMorph = 6, kMorphMask = 7 };

// Morph data texture: rows of this many texels (even: an entry's two texels
// share a row) or GL_MAX_TEXTURE_SIZE when smaller.
constexpr int kMorphTextureWidth = 4096;
// Shapes with a weight the shader is told by name (mesh.vert's u_morph_active).
constexpr int kMaxActiveMorphs = 32;

glm::vec3 srgb_to_linear(const glm::vec3& c) {
  glm::vec3 out;
  for (int i = 0; i < 3; ++i) {
    const float x = std::clamp(c[i], 0.0f, 1.0f);
    out[i] = x <= 0.04045f ? x / 12.92f : std::pow((x + 0.055f) / 1.055f, 2.4f);
  }
  return out;
}

const char* gl_error_name(GLenum e) {
  switch (e) {
    case GL_INVALID_ENUM: return "GL_INVALID_ENUM";
    case GL_INVALID_VALUE: return "GL_INVALID_VALUE";
    case GL_INVALID_OPERATION: return "GL_INVALID_OPERATION";
    case GL_OUT_OF_MEMORY: return "GL_OUT_OF_MEMORY";
    case GL_INVALID_FRAMEBUFFER_OPERATION: return "GL_INVALID_FRAMEBUFFER_OPERATION";
    default: return "unknown GL error";
  }
}

// Collects every pending GL error into one Status.
Status check_gl(const char* where) {
  std::string errors;
  for (int i = 0; i < 16; ++i) {
    const GLenum e = glGetError();
    if (e == GL_NO_ERROR) break;
    if (!errors.empty()) errors += ", ";
    errors += gl_error_name(e);
  }
  if (errors.empty()) return Status::success();
  return Status::error(ErrorCode::Internal, std::string(where) + ": " + errors);
}

// A program whose shaders are compiled and linked but not yet checked. All
// programs are sent before any is checked: in WebGL each check is a
// synchronous call to the GPU process (about 30 ms each on SwiftShader, 12 of
// them at start-up when every shader was checked at once), and GL compiles
// the next ones meanwhile.
struct PendingProgram {
  GLuint program = 0, vs = 0, fs = 0;
  const char* name = "";
};

GLuint send_shader(GLenum type, const std::string& source) {
  const GLuint shader = glCreateShader(type);
  const char* src = source.c_str();
  const GLint len = static_cast<GLint>(source.size());
  glShaderSource(shader, 1, &src, &len);
  glCompileShader(shader);
  return shader;
}

PendingProgram send_program(const std::string& vs_src, const std::string& fs_src, const char* name) {
  PendingProgram p;
  p.name = name;
  p.vs = send_shader(GL_VERTEX_SHADER, vs_src);
  p.fs = send_shader(GL_FRAGMENT_SHADER, fs_src);
  p.program = glCreateProgram();
  glAttachShader(p.program, p.vs);
  glAttachShader(p.program, p.fs);
  glLinkProgram(p.program);
  return p;
}

std::string info_log(GLuint object, bool program) {
  GLint len = 0;
  if (program) glGetProgramiv(object, GL_INFO_LOG_LENGTH, &len);
  else glGetShaderiv(object, GL_INFO_LOG_LENGTH, &len);
  std::string log(static_cast<size_t>(std::max(len, 1)), '\0');
  if (program) glGetProgramInfoLog(object, len, nullptr, log.data());
  else glGetShaderInfoLog(object, len, nullptr, log.data());
  return log;
}

// The link checked (a shader that did not compile fails it; then that
// shader's log is the message). out: the program, or 0 with the error. The
// shaders are freed either way.
Status check_program(PendingProgram& p, GLuint& out) {
  out = 0;
  GLint ok = GL_FALSE;
  glGetProgramiv(p.program, GL_LINK_STATUS, &ok);
  Status s = Status::success();
  if (ok != GL_TRUE) {
    for (const GLuint shader : {p.vs, p.fs}) {
      GLint compiled = GL_FALSE;
      glGetShaderiv(shader, GL_COMPILE_STATUS, &compiled);
      if (compiled != GL_TRUE) {
        s = Status::error(ErrorCode::Internal, std::string("shader ") + p.name + " does not compile: " + info_log(shader, false));
        break;
      }
    }
    if (s) s = Status::error(ErrorCode::Internal, std::string("program ") + p.name + " does not link: " + info_log(p.program, true));
    glDeleteProgram(p.program);
  } else {
    out = p.program;
  }
  glDeleteShader(p.vs);  // flagged while attached; freed with the program
  glDeleteShader(p.fs);
  p = {};
  return s;
}

bool finite(const Vec3& v) { return std::isfinite(v.x()) && std::isfinite(v.y()) && std::isfinite(v.z()); }

// Uniform locations looked up once per program; -1 (absent) is ignored by GL.
struct Uniforms {
  GLuint program = 0;
  std::map<std::string, GLint> cache;
  GLint operator[](const char* name) {
    auto it = cache.find(name);
    if (it != cache.end()) return it->second;
    const GLint loc = glGetUniformLocation(program, name);
    cache[name] = loc;
    return loc;
  }
};

void upload_vec3s(GLuint buffer, const std::vector<float>& data, GLenum usage) {
  glBindBuffer(GL_ARRAY_BUFFER, buffer);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(data.size() * sizeof(float)), data.data(),
               usage);
}

void bind_attribute(GLuint buffer, GLuint location, int components) {
  glBindBuffer(GL_ARRAY_BUFFER, buffer);
  glEnableVertexAttribArray(location);
  glVertexAttribPointer(location, components, GL_FLOAT, GL_FALSE, 0, nullptr);
}

}  // namespace

struct Renderer::Impl {
  struct Drawable {
    bool is_points = false;
    MeshLayout layout = MeshLayout::Indexed;
    GLuint vao = 0;
    // Meshes: position + normal interleaved (6 floats per GPU vertex).
    // Point clouds: position_buffer and normal_buffer.
    GLuint geometry_buffer = 0, position_buffer = 0, normal_buffer = 0, uv_buffer = 0, color_buffer = 0,
           barycentric_buffer = 0, occlusion_buffer = 0, index_buffer = 0;
    GLuint edge_vao = 0, edge_buffer = 0;  // indexed wireframe (built on first use)
    GLsizei vertex_count = 0;  // GPU vertices (unrolled: 3 per triangle; indexed: #V + seam copies)
    GLsizei index_count = 0;   // indexed: 3 * #F
    GLsizei edge_index_count = 0;
    int num_vertices = 0;      // source vertices (#V or #P)
    std::vector<Tri> triangles;  // kept for normals and edges
    // The GPU vertex each extra vertex copies: unrolled, the source vertex
    // of every corner (3 * #F); indexed, the source vertex of each seam copy
    // appended after the first #V (GPU vertex i < #V is source vertex i).
    std::vector<std::uint32_t> gpu_source;
    // CPU copies for incremental animation updates (#V by 3 floats each),
    // unnormalized area-weighted face normals (#F by 3), the triangles
    // around each vertex (CSR: vertex_faces[vertex_face_start[v] ..
    // vertex_face_start[v + 1]]), and the interleaved GPU data (#GPU by 6).
    std::vector<float> positions, normals, face_normals, gpu_geometry;
    std::vector<std::uint32_t> vertex_face_start, vertex_faces;
    std::vector<std::uint32_t> face_stamp, vertex_stamp;  // "touched in update number n"
    std::uint32_t update_number = 0;
    // Back-face culling is safe (see DrawStyle::cull_hidden_back_faces) when
    // the topology allows it (closable) and the eye is inside every hole's
    // half-space; holes are the boundary loops (source vertex indices, in
    // the boundary half-edges' direction), their planes taken at draw time
    // so they follow animation.
    bool closable = false;
    std::vector<std::vector<std::uint32_t>> holes;
    bool has_colors = false, has_uvs = false, has_normals = false, has_occlusion = false;
    // Morph targets (set_morph_targets): the entries' data texture, the
    // per-GPU-vertex (first entry, count) buffer, the weights (padded to
    // whole vec4s) and whether any is non-zero.
    GLuint morph_texture = 0, morph_buffer = 0, morph_mask_buffer = 0;
    int morph_count = 0, morph_texture_width = 0;
    std::vector<float> morph_weights;
    // The shapes with a non-zero weight (at most kMaxActiveMorphs are listed
    // to the shader; more: every entry is weighted, mode 2).
    std::vector<int> morph_active_shapes;
    std::vector<float> morph_active_weights;
    int morph_mode = 0;
    TextureHandle texture = kNoHandle;
    DrawStyle style;
    BBox bbox;
  };

  bool ready = false;
  RendererOptions options;
  GLuint mesh_program = 0, points_program = 0, background_program = 0, lines_program = 0;
  Uniforms mesh_u, points_u, background_u, lines_u;
  float max_line_width = 1.0f;
  GLuint background_vao = 0;
  std::map<DrawableHandle, Drawable> drawables;
  std::map<TextureHandle, GLuint> textures;
  std::set<TextureHandle> transparent_textures;  // some alpha below 255 (alpha-tested)
  int next_handle = 0;
  int next_texture = 0;
  float max_point_size = 64.0f;
  int max_texture_size = 2048;
  int max_vertex_texture_units = 0, max_vertex_uniform_vectors = 0;

  ~Impl() { release_all(); }

  void release(Drawable& d) {
    GLuint buffers[] = {d.geometry_buffer, d.position_buffer, d.normal_buffer, d.uv_buffer, d.color_buffer,
                        d.barycentric_buffer, d.occlusion_buffer, d.index_buffer, d.edge_buffer};
    for (GLuint b : buffers)
      if (b) glDeleteBuffers(1, &b);
    if (d.vao) glDeleteVertexArrays(1, &d.vao);
    if (d.edge_vao) glDeleteVertexArrays(1, &d.edge_vao);
    release_morph(d);
  }

  static void release_morph(Drawable& d) {
    if (d.morph_texture) glDeleteTextures(1, &d.morph_texture);
    if (d.morph_buffer) glDeleteBuffers(1, &d.morph_buffer);
    if (d.morph_mask_buffer) glDeleteBuffers(1, &d.morph_mask_buffer);
    d.morph_texture = d.morph_buffer = d.morph_mask_buffer = 0;
    d.morph_count = d.morph_texture_width = 0;
    d.morph_weights.clear();
    d.morph_active_shapes.clear();
    d.morph_active_weights.clear();
    d.morph_mode = 0;
  }

  void release_all() {
    if (!ready) return;
    for (auto& [h, d] : drawables) release(d);
    drawables.clear();
    for (auto& [h, t] : textures) glDeleteTextures(1, &t);
    textures.clear();
    transparent_textures.clear();
    if (background_vao) glDeleteVertexArrays(1, &background_vao);
    if (mesh_program) glDeleteProgram(mesh_program);
    if (points_program) glDeleteProgram(points_program);
    if (background_program) glDeleteProgram(background_program);
    if (lines_program) glDeleteProgram(lines_program);
    background_vao = mesh_program = points_program = background_program = lines_program = 0;
    ready = false;
  }

  Drawable* find(DrawableHandle h) {
    auto it = drawables.find(h);
    return it == drawables.end() ? nullptr : &it->second;
  }

  // Whether back faces can only be seen through holes, and the holes:
  // every directed edge once (consistent orientation, at most two triangles
  // per edge), boundary half-edges forming simple loops.
  static void find_holes(Drawable& d) {
    d.closable = false;
    d.holes.clear();
    std::vector<std::uint64_t> directed;
    directed.reserve(d.triangles.size() * 3);
    auto key = [](std::uint32_t a, std::uint32_t b) { return std::uint64_t(a) << 32 | b; };
    for (const Tri& t : d.triangles)
      for (int c = 0; c < 3; ++c)
        directed.push_back(key(static_cast<std::uint32_t>(t[c]), static_cast<std::uint32_t>(t[(c + 1) % 3])));
    std::sort(directed.begin(), directed.end());
    if (std::adjacent_find(directed.begin(), directed.end()) != directed.end()) return;
    std::map<std::uint32_t, std::uint32_t> next;  // boundary half-edge a -> b
    for (std::uint64_t e : directed) {
      const std::uint32_t a = static_cast<std::uint32_t>(e >> 32), b = static_cast<std::uint32_t>(e & 0xffffffffu);
      if (std::binary_search(directed.begin(), directed.end(), key(b, a))) continue;
      if (!next.emplace(a, b).second) return;  // two boundary edges leave a: not a simple loop
    }
    std::map<std::uint32_t, bool> done;
    for (const auto& [start, unused] : next) {
      (void)unused;
      if (done.count(start)) continue;
      std::vector<std::uint32_t> loop;
      std::uint32_t v = start;
      do {
        done[v] = true;
        loop.push_back(v);
        auto it = next.find(v);
        if (it == next.end() || loop.size() > next.size()) return;
        v = it->second;
      } while (v != start);
      d.holes.push_back(std::move(loop));
    }
    d.closable = true;
  }

  // Whether the eye can see a back face of d (through a hole, or because of
  // its topology, or through an alpha-tested texture).
  bool back_faces_visible(const Drawable& d, const CameraMatrices& cam) const {
    if (!d.style.cull_hidden_back_faces || !d.closable) return true;
    if (d.style.use_texture && d.has_uvs && transparent_textures.count(d.texture)) return true;
    if (cam.projection[3][3] != 0.0f) return true;  // orthographic: not handled, draw all
    const glm::vec4 eye = glm::inverse(cam.view * d.style.model) * glm::vec4(0.0f, 0.0f, 0.0f, 1.0f);
    if (!(std::abs(eye.w) > 0.0f)) return true;
    const glm::vec3 e = glm::vec3(eye) / eye.w;
    // A ray from the eye can only reach the inside through a hole after
    // crossing its plane outward-to-inward; an eye beyond the plane on the
    // mesh's side (by more than the loop's own unevenness) never does.
    for (const std::vector<std::uint32_t>& loop : d.holes) {
      auto at = [&](size_t i) {
        const float* p = &d.positions[3 * size_t(loop[i % loop.size()])];
        return glm::vec3(p[0], p[1], p[2]);
      };
      // Newell's normal of the loop as the boundary half-edges run; a cap
      // closing the hole would run the other way, so out of the mesh is minus it.
      glm::vec3 centre(0.0f), newell(0.0f);
      for (size_t i = 0; i < loop.size(); ++i) {
        const glm::vec3 p = at(i), q = at(i + 1);
        centre += p;
        newell += glm::vec3((p.y - q.y) * (p.z + q.z), (p.z - q.z) * (p.x + q.x), (p.x - q.x) * (p.y + q.y));
      }
      centre /= float(loop.size());
      const float len = glm::length(newell);
      if (!(len > 0.0f)) return true;
      const glm::vec3 outward = -newell / len;
      float thickness = 0;
      for (size_t i = 0; i < loop.size(); ++i) thickness = std::max(thickness, std::abs(glm::dot(at(i) - centre, outward)));
      if (glm::dot(e - centre, outward) > -thickness) return true;
    }
    return false;
  }

  // The source vertex GPU vertex g shows.
  static std::uint32_t source_of(const Drawable& d, size_t g) {
    if (d.layout == MeshLayout::Unrolled) return d.gpu_source[g];
    return g < static_cast<size_t>(d.num_vertices) ? static_cast<std::uint32_t>(g)
                                                   : d.gpu_source[g - static_cast<size_t>(d.num_vertices)];
  }

  // Per-vertex float data (#V by k) laid out per GPU vertex.
  static std::vector<float> per_gpu_vertex(const Drawable& d, const std::vector<float>& per_vertex, int k) {
    std::vector<float> out(static_cast<size_t>(d.vertex_count) * k);
    for (size_t g = 0; g < static_cast<size_t>(d.vertex_count); ++g) {
      const size_t v = source_of(d, g);
      for (int c = 0; c < k; ++c) out[g * k + c] = per_vertex[v * k + c];
    }
    return out;
  }

  // Unnormalized face normal (twice the area) of triangle f, from d.positions.
  static void compute_face_normal(Drawable& d, size_t f) {
    const Tri& t = d.triangles[f];
    const float* a = &d.positions[3 * static_cast<size_t>(t[0])];
    const float* b = &d.positions[3 * static_cast<size_t>(t[1])];
    const float* c = &d.positions[3 * static_cast<size_t>(t[2])];
    const float e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    const float e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    float* n = &d.face_normals[3 * f];
    n[0] = e1[1] * e2[2] - e1[2] * e2[1];
    n[1] = e1[2] * e2[0] - e1[0] * e2[2];
    n[2] = e1[0] * e2[1] - e1[1] * e2[0];
  }

  // Vertex normal of v: the normalized sum of its triangles' face normals,
  // always summed in the same (CSR) order so an incremental update gives
  // bit-identical normals to a full recompute.
  static void compute_vertex_normal(Drawable& d, size_t v) {
    double sum[3] = {0, 0, 0};
    for (std::uint32_t i = d.vertex_face_start[v]; i < d.vertex_face_start[v + 1]; ++i) {
      const float* n = &d.face_normals[3 * static_cast<size_t>(d.vertex_faces[i])];
      for (int k = 0; k < 3; ++k) sum[k] += n[k];
    }
    const double len = std::sqrt(sum[0] * sum[0] + sum[1] * sum[1] + sum[2] * sum[2]);
    for (int k = 0; k < 3; ++k) d.normals[3 * v + k] = len > 0 ? static_cast<float>(sum[k] / len) : 0.0f;
  }

  static void build_vertex_faces(Drawable& d) {
    const size_t nv = static_cast<size_t>(d.num_vertices);
    d.vertex_face_start.assign(nv + 1, 0);
    for (const Tri& t : d.triangles)
      for (int c = 0; c < 3; ++c) ++d.vertex_face_start[static_cast<size_t>(t[c]) + 1];
    for (size_t v = 0; v < nv; ++v) d.vertex_face_start[v + 1] += d.vertex_face_start[v];
    d.vertex_faces.resize(d.vertex_face_start[nv]);
    std::vector<std::uint32_t> fill(d.vertex_face_start.begin(), d.vertex_face_start.end() - 1);
    for (size_t f = 0; f < d.triangles.size(); ++f)
      for (int c = 0; c < 3; ++c) d.vertex_faces[fill[static_cast<size_t>(d.triangles[f][c])]++] = static_cast<std::uint32_t>(f);
  }

  static void compute_all_normals(Drawable& d) {
    d.face_normals.resize(d.triangles.size() * 3);
    for (size_t f = 0; f < d.triangles.size(); ++f) compute_face_normal(d, f);
    d.normals.resize(d.positions.size());
    for (size_t v = 0; v < static_cast<size_t>(d.num_vertices); ++v) compute_vertex_normal(d, v);
  }

  // Writes GPU vertices [first, last) of the interleaved array from
  // d.positions / d.normals and sends them; `allocate` (re)creates the
  // buffer with the whole array instead.
  static void send_geometry(Drawable& d, size_t first, size_t last, bool allocate) {
    float* out = d.gpu_geometry.data();
    for (size_t g = first; g < last; ++g) {
      const size_t v = source_of(d, g);
      for (int k = 0; k < 3; ++k) {
        out[6 * g + k] = d.positions[3 * v + k];
        out[6 * g + 3 + k] = d.normals[3 * v + k];
      }
    }
    glBindBuffer(GL_ARRAY_BUFFER, d.geometry_buffer);
    if (allocate)
      glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(d.gpu_geometry.size() * sizeof(float)),
                   d.gpu_geometry.data(), GL_DYNAMIC_DRAW);
    else if (last > first)
      glBufferSubData(GL_ARRAY_BUFFER, static_cast<GLintptr>(first * 6 * sizeof(float)),
                      static_cast<GLsizeiptr>((last - first) * 6 * sizeof(float)), out + 6 * first);
  }

  // The indexed wireframe: every edge once, as GL_LINES indices.
  void build_edges(Drawable& d) {
    std::vector<std::uint64_t> keys;
    keys.reserve(d.triangles.size() * 3);
    for (const Tri& t : d.triangles)
      for (int c = 0; c < 3; ++c) {
        const std::uint64_t a = static_cast<std::uint32_t>(t[c]), b = static_cast<std::uint32_t>(t[(c + 1) % 3]);
        keys.push_back(a < b ? (a << 32 | b) : (b << 32 | a));
      }
    std::sort(keys.begin(), keys.end());
    keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
    std::vector<std::uint32_t> lines;
    lines.reserve(keys.size() * 2);
    for (std::uint64_t k : keys) {
      lines.push_back(static_cast<std::uint32_t>(k >> 32));
      lines.push_back(static_cast<std::uint32_t>(k & 0xffffffffu));
    }
    glGenVertexArrays(1, &d.edge_vao);
    glBindVertexArray(d.edge_vao);
    glBindBuffer(GL_ARRAY_BUFFER, d.geometry_buffer);
    glEnableVertexAttribArray(kPosition);
    glVertexAttribPointer(kPosition, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float), nullptr);
    glGenBuffers(1, &d.edge_buffer);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, d.edge_buffer);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(lines.size() * sizeof(std::uint32_t)),
                 lines.data(), GL_STATIC_DRAW);
    glBindVertexArray(0);
    d.edge_index_count = static_cast<GLsizei>(lines.size());
  }

  void draw_edges(Drawable& d, const CameraMatrices& cam) {
    if (!d.edge_vao) build_edges(d);
    const DrawStyle& s = d.style;
    glUseProgram(lines_program);
    glUniformMatrix4fv(lines_u["u_model"], 1, GL_FALSE, glm::value_ptr(s.model));
    glUniformMatrix4fv(lines_u["u_view"], 1, GL_FALSE, glm::value_ptr(cam.view));
    glUniformMatrix4fv(lines_u["u_projection"], 1, GL_FALSE, glm::value_ptr(cam.projection));
    const glm::vec3 c = glm::clamp(s.wire_color, 0.0f, 1.0f);
    glUniform3fv(lines_u["u_wire_color"], 1, glm::value_ptr(c));
    glLineWidth(std::clamp(s.wire_width_px, 1.0f, max_line_width));
    glBindVertexArray(d.edge_vao);
    glDrawElements(GL_LINES, d.edge_index_count, GL_UNSIGNED_INT, nullptr);
    glLineWidth(1.0f);
  }

  void draw_mesh(const Drawable& d, const CameraMatrices& cam) {
    const bool indexed = d.layout == MeshLayout::Indexed;
    const DrawStyle& s = d.style;
    Uniforms& u = mesh_u;
    glUseProgram(mesh_program);
    glUniformMatrix4fv(u["u_model"], 1, GL_FALSE, glm::value_ptr(s.model));
    glUniformMatrix4fv(u["u_view"], 1, GL_FALSE, glm::value_ptr(cam.view));
    glUniformMatrix4fv(u["u_projection"], 1, GL_FALSE, glm::value_ptr(cam.projection));
    const glm::mat3 normal_matrix = glm::inverseTranspose(glm::mat3(cam.view * s.model));
    glUniformMatrix3fv(u["u_normal_matrix"], 1, GL_FALSE, glm::value_ptr(normal_matrix));

    int albedo_source = 0;
    auto tex = textures.find(d.texture);
    if (s.use_texture && d.has_uvs && tex != textures.end()) {
      albedo_source = 2;
      glActiveTexture(GL_TEXTURE0);
      glBindTexture(GL_TEXTURE_2D, tex->second);
      glUniform1i(u["u_texture"], 0);
    } else if (s.use_vertex_colors && d.has_colors) {
      albedo_source = 1;
    }
    glUniform1i(u["u_albedo_source"], albedo_source);
    glUniform1i(u["u_has_occlusion"], d.has_occlusion ? 1 : 0);
    glUniform3fv(u["u_base_color"], 1, glm::value_ptr(srgb_to_linear(s.base_color)));
    glUniform1f(u["u_specular"], s.specular);
    glUniform1f(u["u_shininess"], std::max(s.shininess, 1.0f));
    glUniform1i(u["u_surface"], s.surface ? 1 : 0);
    glUniform1i(u["u_flat"], s.flat_shading ? 1 : 0);
    glUniform1i(u["u_wireframe"], s.wireframe && !indexed ? 1 : 0);
    glUniform3fv(u["u_wire_color"], 1, glm::value_ptr(srgb_to_linear(s.wire_color)));
    glUniform1f(u["u_wire_width"], std::max(s.wire_width_px, 0.5f));

    const LightRig& l = options.lights;
    glUniform3fv(u["u_key_dir"], 1, glm::value_ptr(l.key_dir));
    glUniform3fv(u["u_key_color"], 1, glm::value_ptr(l.key_color));
    glUniform3fv(u["u_fill_dir"], 1, glm::value_ptr(l.fill_dir));
    glUniform3fv(u["u_fill_color"], 1, glm::value_ptr(l.fill_color));
    glUniform3fv(u["u_rim_dir"], 1, glm::value_ptr(l.rim_dir));
    glUniform3fv(u["u_rim_color"], 1, glm::value_ptr(l.rim_color));
    glUniform3fv(u["u_ambient_sky"], 1, glm::value_ptr(l.ambient_sky));
    glUniform3fv(u["u_ambient_ground"], 1, glm::value_ptr(l.ambient_ground));
    glUniform1f(u["u_exposure"], l.exposure);

    glUniform1i(u["u_morph_mode"], d.morph_mode);
    if (d.morph_mode != 0) {
      glActiveTexture(GL_TEXTURE1);
      glBindTexture(GL_TEXTURE_2D, d.morph_texture);
      glUniform1i(u["u_morph_offsets"], 1);
      glUniform1i(u["u_morph_width"], d.morph_texture_width);
      if (d.morph_mode == 1) {
        glUniform1i(u["u_morph_active_count"], static_cast<GLint>(d.morph_active_shapes.size()));
        glUniform4iv(u["u_morph_active"], kMaxActiveMorphs / 4, d.morph_active_shapes.data());
        glUniform4fv(u["u_morph_active_weights"], kMaxActiveMorphs / 4, d.morph_active_weights.data());
      } else {
        glUniform4fv(u["u_morph_weights"], static_cast<GLsizei>(d.morph_weights.size() / 4), d.morph_weights.data());
      }
      glActiveTexture(GL_TEXTURE0);
    }

    // Edges alone are blended over what is already drawn (antialiased lines).
    if (!s.surface) {
      glEnable(GL_BLEND);
      glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
      glDepthMask(GL_FALSE);
    }
    // Indexed edges are lines drawn afterwards: push the surface back so they
    // win the depth test where they lie on it.
    const bool offset = indexed && s.wireframe && s.surface;
    if (offset) {
      glEnable(GL_POLYGON_OFFSET_FILL);
      glPolygonOffset(1.0f, 1.0f);
    }
    const bool cull = s.surface && !back_faces_visible(d, cam);
    if (cull) glEnable(GL_CULL_FACE);  // front faces are CCW (GL's default)
    glBindVertexArray(d.vao);
    if (indexed) glDrawElements(GL_TRIANGLES, d.index_count, GL_UNSIGNED_INT, nullptr);
    else glDrawArrays(GL_TRIANGLES, 0, d.vertex_count);
    if (offset) glDisable(GL_POLYGON_OFFSET_FILL);
    if (cull) glDisable(GL_CULL_FACE);
    if (!s.surface) {
      glDisable(GL_BLEND);
      glDepthMask(GL_TRUE);
    }
  }

  void draw_points(const Drawable& d, const CameraMatrices& cam) {
    const DrawStyle& s = d.style;
    Uniforms& u = points_u;
    glUseProgram(points_program);
    glUniformMatrix4fv(u["u_model"], 1, GL_FALSE, glm::value_ptr(s.model));
    glUniformMatrix4fv(u["u_view"], 1, GL_FALSE, glm::value_ptr(cam.view));
    glUniformMatrix4fv(u["u_projection"], 1, GL_FALSE, glm::value_ptr(cam.projection));
    glUniform1f(u["u_point_size"], std::clamp(s.point_size_px, 1.0f, max_point_size));
    int source = 0;  // base color
    switch (s.point_coloring) {
      case PointColoring::Auto: source = d.has_colors ? 1 : (d.has_normals ? 2 : 0); break;
      case PointColoring::VertexColor: source = d.has_colors ? 1 : 0; break;
      case PointColoring::Normal: source = d.has_normals ? 2 : 0; break;
      case PointColoring::BaseColor: source = 0; break;
    }
    glUniform1i(u["u_color_source"], source);
    glUniform3fv(u["u_base_color"], 1, glm::value_ptr(srgb_to_linear(s.base_color)));
    glUniform3fv(u["u_key_dir"], 1, glm::value_ptr(options.lights.key_dir));
    glUniform1f(u["u_exposure"], options.lights.exposure);
    glBindVertexArray(d.vao);
    glDrawArrays(GL_POINTS, 0, d.vertex_count);
  }
};

Renderer::Renderer() : impl_(std::make_unique<Impl>()) {}
Renderer::~Renderer() = default;

bool Renderer::ready() const { return impl_->ready; }

Status Renderer::init(const RendererOptions& options) {
  using namespace likeness_embedded;
  using shader_sources::text;
  impl_->release_all();
  impl_->options = options;
  Impl& m = *impl_;
  PendingProgram pending[] = {
      send_program(text(shaders_mesh_vert, shaders_mesh_vert_size), text(shaders_mesh_frag, shaders_mesh_frag_size), "mesh"),
      send_program(text(shaders_points_vert, shaders_points_vert_size), text(shaders_points_frag, shaders_points_frag_size),
                   "points"),
      send_program(text(shaders_background_vert, shaders_background_vert_size),
                   text(shaders_background_frag, shaders_background_frag_size), "background"),
      send_program(text(shaders_lines_vert, shaders_lines_vert_size), text(shaders_lines_frag, shaders_lines_frag_size),
                   "lines")};
  GLuint* programs[] = {&m.mesh_program, &m.points_program, &m.background_program, &m.lines_program};
  Status s = Status::success();
  for (size_t i = 0; i < std::size(pending); ++i) {  // every one checked, so every shader is freed
    const Status r = check_program(pending[i], *programs[i]);
    if (s && !r) s = r;
  }
  if (!s) {
    m.ready = true;  // so release_all frees what was made
    m.release_all();
    return s;
  }
  m.mesh_u = Uniforms{m.mesh_program, {}};
  m.points_u = Uniforms{m.points_program, {}};
  m.background_u = Uniforms{m.background_program, {}};
  m.lines_u = Uniforms{m.lines_program, {}};
  glGenVertexArrays(1, &m.background_vao);  // core profiles need a VAO bound even without attributes

  GLfloat range[2] = {1.0f, 64.0f};
  glGetFloatv(GL_ALIASED_POINT_SIZE_RANGE, range);
  m.max_point_size = std::max(range[1], 1.0f);
  GLfloat line_range[2] = {1.0f, 1.0f};  // WebGL: [1, 1]
  glGetFloatv(GL_ALIASED_LINE_WIDTH_RANGE, line_range);
  m.max_line_width = std::max(line_range[1], 1.0f);
  glGetIntegerv(GL_MAX_TEXTURE_SIZE, &m.max_texture_size);
  glGetIntegerv(GL_MAX_VERTEX_TEXTURE_IMAGE_UNITS, &m.max_vertex_texture_units);
  // Meshes without morph targets leave a_morph_mask (an integer attribute)
  // disabled: its constant value must be an integer one too (WebGL checks).
  glVertexAttribI4ui(kMorphMask, 0u, 0u, 0u, 0u);
  glGetIntegerv(GL_MAX_VERTEX_UNIFORM_VECTORS, &m.max_vertex_uniform_vectors);
#ifdef GL_PROGRAM_POINT_SIZE
  // Desktop GL needs this for gl_PointSize; GLES3/WebGL2 always honours it.
  glEnable(GL_PROGRAM_POINT_SIZE);
#endif
  m.ready = true;
  return check_gl("Renderer::init");
}

Status Renderer::upload_mesh(const TriMesh& mesh, DrawableHandle& out, MeshLayout layout) {
  out = kNoHandle;
  if (!impl_->ready) return Status::error(ErrorCode::InvalidInput, "renderer not initialized (call init() on a current GL context)");
  if (mesh.positions.empty() || mesh.triangles.empty())
    return Status::error(ErrorCode::Empty, "mesh has no vertices or no triangles");
  std::string why;
  if (!is_valid(mesh, &why)) return Status::error(ErrorCode::InvalidInput, "mesh is invalid: " + why);
  const size_t nv = mesh.positions.size(), nf = mesh.triangles.size();
  if (!mesh.normals.empty() && mesh.normals.size() != nv)
    return Status::error(ErrorCode::InvalidInput, "mesh has " + std::to_string(mesh.normals.size()) +
                                                      " normals for " + std::to_string(nv) + " vertices");
  if (!mesh.colors.empty() && mesh.colors.size() != nv)
    return Status::error(ErrorCode::InvalidInput, "mesh has " + std::to_string(mesh.colors.size()) +
                                                      " colors for " + std::to_string(nv) + " vertices");
  for (const Vec3& n : mesh.normals)
    if (!finite(n)) return Status::error(ErrorCode::InvalidInput, "mesh has a non-finite normal");
  const size_t want_uvs = mesh.uv_per_corner ? 3 * nf : nv;
  if (!mesh.uvs.empty() && mesh.uvs.size() != want_uvs)
    return Status::error(ErrorCode::InvalidInput,
                         "mesh has " + std::to_string(mesh.uvs.size()) + " uvs, expected " +
                             std::to_string(want_uvs) + (mesh.uv_per_corner ? " (per corner)" : " (per vertex)"));
  if (nf * 3 > static_cast<size_t>(1) << 30)
    return Status::error(ErrorCode::TooLarge, "mesh has too many triangles to draw");

  Impl& m = *impl_;
  Impl::Drawable d;
  d.layout = layout;
  d.num_vertices = static_cast<int>(nv);
  d.triangles = mesh.triangles;
  d.bbox = bounding_box(mesh.positions);
  d.has_normals = true;
  d.has_colors = !mesh.colors.empty();
  d.has_uvs = !mesh.uvs.empty();

  // GPU vertices and, for indexed meshes, the indices. Per-corner uvs: a
  // vertex keeps its first corner's uv; each further distinct uv at it
  // (a seam) becomes one appended copy.
  std::vector<std::uint32_t> indices;
  std::vector<Vec2> gpu_uvs;  // per GPU vertex
  if (layout == MeshLayout::Unrolled) {
    d.gpu_source.resize(nf * 3);
    for (size_t f = 0; f < nf; ++f)
      for (int c = 0; c < 3; ++c) d.gpu_source[f * 3 + c] = static_cast<std::uint32_t>(mesh.triangles[f][c]);
    if (d.has_uvs) {
      gpu_uvs.resize(nf * 3);
      for (size_t f = 0; f < nf; ++f)
        for (int c = 0; c < 3; ++c)
          gpu_uvs[f * 3 + c] = mesh.uv_per_corner ? mesh.uvs[f * 3 + c] : mesh.uvs[mesh.triangles[f][c]];
    }
  } else {
    indices.resize(nf * 3);
    for (size_t f = 0; f < nf; ++f)
      for (int c = 0; c < 3; ++c) indices[f * 3 + c] = static_cast<std::uint32_t>(mesh.triangles[f][c]);
    if (d.has_uvs && !mesh.uv_per_corner) {
      gpu_uvs = mesh.uvs;
    } else if (d.has_uvs) {
      gpu_uvs.assign(nv, Vec2::Zero());
      std::vector<char> assigned(nv, 0);
      // Copies of vertex v: a chain through next_copy (GPU indices), so
      // finding a matching uv looks only at v's own copies.
      std::vector<std::uint32_t> next_copy(nv, UINT32_MAX);
      for (size_t k = 0; k < nf * 3; ++k) {
        const std::uint32_t v = indices[k];
        const Vec2& uv = mesh.uvs[k];
        if (!assigned[v]) {
          assigned[v] = 1;
          gpu_uvs[v] = uv;
          continue;
        }
        std::uint32_t g = v, last = v;
        for (; g != UINT32_MAX; last = g, g = next_copy[g])
          if (gpu_uvs[g] == uv) break;
        if (g == UINT32_MAX) {
          g = static_cast<std::uint32_t>(gpu_uvs.size());
          gpu_uvs.push_back(uv);
          next_copy.push_back(UINT32_MAX);
          next_copy[last] = g;
          d.gpu_source.push_back(v);
        }
        indices[k] = g;
      }
    }
    d.index_count = static_cast<GLsizei>(indices.size());
  }
  d.vertex_count = static_cast<GLsizei>(layout == MeshLayout::Unrolled ? nf * 3 : nv + d.gpu_source.size());

  d.positions.resize(nv * 3);
  for (size_t v = 0; v < nv; ++v)
    for (int k = 0; k < 3; ++k) d.positions[3 * v + k] = static_cast<float>(mesh.positions[v][k]);
  Impl::build_vertex_faces(d);
  Impl::find_holes(d);
  Impl::compute_all_normals(d);  // face normals are needed by later updates either way
  if (!mesh.normals.empty())
    for (size_t v = 0; v < nv; ++v)
      for (int k = 0; k < 3; ++k) d.normals[3 * v + k] = static_cast<float>(mesh.normals[v][k]);
  d.face_stamp.assign(nf, 0);
  d.vertex_stamp.assign(nv, 0);
  d.gpu_geometry.resize(static_cast<size_t>(d.vertex_count) * 6);

  glGenVertexArrays(1, &d.vao);
  glBindVertexArray(d.vao);
  glGenBuffers(1, &d.geometry_buffer);
  Impl::send_geometry(d, 0, static_cast<size_t>(d.vertex_count), true);
  glEnableVertexAttribArray(kPosition);
  glVertexAttribPointer(kPosition, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float), nullptr);
  glEnableVertexAttribArray(kNormal);
  glVertexAttribPointer(kNormal, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float),
                        reinterpret_cast<const void*>(3 * sizeof(float)));

  if (layout == MeshLayout::Unrolled) {
    std::vector<float> bary(nf * 9, 0.0f);
    for (size_t f = 0; f < nf; ++f)
      for (int c = 0; c < 3; ++c) bary[f * 9 + c * 3 + c] = 1.0f;
    glGenBuffers(1, &d.barycentric_buffer);
    upload_vec3s(d.barycentric_buffer, bary, GL_STATIC_DRAW);
    bind_attribute(d.barycentric_buffer, kBarycentric, 3);
  } else {
    glDisableVertexAttribArray(kBarycentric);
    glGenBuffers(1, &d.index_buffer);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, d.index_buffer);  // recorded in the VAO
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(indices.size() * sizeof(std::uint32_t)),
                 indices.data(), GL_STATIC_DRAW);
  }

  if (d.has_colors) {
    std::vector<float> colors(nv * 3);
    for (size_t v = 0; v < nv; ++v)
      for (int k = 0; k < 3; ++k) colors[3 * v + k] = static_cast<float>(mesh.colors[v][k]);
    glGenBuffers(1, &d.color_buffer);
    upload_vec3s(d.color_buffer, Impl::per_gpu_vertex(d, colors, 3), GL_STATIC_DRAW);
    bind_attribute(d.color_buffer, kColor, 3);
  } else {
    glDisableVertexAttribArray(kColor);
  }
  if (d.has_uvs) {
    std::vector<float> uv;
    uv.reserve(gpu_uvs.size() * 2);
    for (const Vec2& t : gpu_uvs) {
      uv.push_back(static_cast<float>(t.x()));
      uv.push_back(static_cast<float>(t.y()));
    }
    glGenBuffers(1, &d.uv_buffer);
    glBindBuffer(GL_ARRAY_BUFFER, d.uv_buffer);
    glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(uv.size() * sizeof(float)), uv.data(),
                 GL_STATIC_DRAW);
    bind_attribute(d.uv_buffer, kUv, 2);
  } else {
    glDisableVertexAttribArray(kUv);
  }
  glBindVertexArray(0);
  Status s = check_gl("upload_mesh");
  if (!s) {
    m.release(d);
    return s;
  }
  out = m.next_handle++;
  m.drawables[out] = std::move(d);
  return Status::success();
}

Status Renderer::update_mesh(DrawableHandle handle, const std::vector<Vec3>& positions,
                             const std::vector<Vec3>& normals) {
  Impl& m = *impl_;
  Impl::Drawable* d = m.find(handle);
  if (!d || d->is_points) return Status::error(ErrorCode::InvalidInput, "update_mesh: no mesh with handle " + std::to_string(handle));
  if (positions.size() != static_cast<size_t>(d->num_vertices))
    return Status::error(ErrorCode::InvalidInput, "update_mesh: " + std::to_string(positions.size()) +
                                                      " positions for a mesh of " + std::to_string(d->num_vertices) + " vertices");
  if (!normals.empty() && normals.size() != positions.size())
    return Status::error(ErrorCode::InvalidInput, "update_mesh: " + std::to_string(normals.size()) +
                                                      " normals for " + std::to_string(positions.size()) + " vertices");
  for (const Vec3& n : normals)
    if (!finite(n)) return Status::error(ErrorCode::InvalidInput, "update_mesh: non-finite normal");
  std::vector<float> xyz(positions.size() * 3);
  for (size_t v = 0; v < positions.size(); ++v)
    for (int k = 0; k < 3; ++k) xyz[3 * v + k] = static_cast<float>(positions[v][k]);
  if (normals.empty()) return update_mesh_positions(handle, xyz.data(), positions.size());
  for (float x : xyz)
    if (!std::isfinite(x)) return Status::error(ErrorCode::InvalidInput, "update_mesh: non-finite position");
  // Given normals replace everything: the face normals still follow the
  // positions, for later updates without normals.
  d->positions = std::move(xyz);
  for (size_t f = 0; f < d->triangles.size(); ++f) Impl::compute_face_normal(*d, f);
  for (size_t v = 0; v < normals.size(); ++v)
    for (int k = 0; k < 3; ++k) d->normals[3 * v + k] = static_cast<float>(normals[v][k]);
  Impl::send_geometry(*d, 0, static_cast<size_t>(d->vertex_count), false);
  d->bbox = bounding_box(positions);
  return check_gl("update_mesh");
}

Status Renderer::update_mesh_positions(DrawableHandle handle, const float* xyz, size_t vertex_count,
                                       MeshUpdateStats* stats) {
  Impl& m = *impl_;
  if (stats) *stats = MeshUpdateStats{};
  Impl::Drawable* d = m.find(handle);
  if (!d || d->is_points)
    return Status::error(ErrorCode::InvalidInput, "update_mesh_positions: no mesh with handle " + std::to_string(handle));
  const size_t nv = static_cast<size_t>(d->num_vertices);
  if (vertex_count != nv)
    return Status::error(ErrorCode::InvalidInput, "update_mesh_positions: " + std::to_string(vertex_count) +
                                                      " positions for a mesh of " + std::to_string(nv) + " vertices");
  if (nv > 0 && !xyz) return Status::error(ErrorCode::InvalidInput, "update_mesh_positions: no position array");
  for (size_t i = 0; i < nv * 3; ++i)
    if (!std::isfinite(xyz[i])) return Status::error(ErrorCode::InvalidInput, "update_mesh_positions: non-finite position");

  // Stamps instead of clearing flags: one number per update.
  if (++d->update_number == 0) {
    std::fill(d->face_stamp.begin(), d->face_stamp.end(), 0);
    std::fill(d->vertex_stamp.begin(), d->vertex_stamp.end(), 0);
    d->update_number = 1;
  }
  const std::uint32_t stamp = d->update_number;
  // 1. Moved vertices: new positions, and the faces around them get new normals.
  std::vector<std::uint32_t> touched_faces;
  int moved = 0;
  float lo[3] = {xyz[0], xyz[1], xyz[2]}, hi[3] = {xyz[0], xyz[1], xyz[2]};
  for (size_t v = 0; v < nv; ++v) {
    const float* p = xyz + 3 * v;
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], p[k]);
      hi[k] = std::max(hi[k], p[k]);
    }
    float* q = &d->positions[3 * v];
    if (p[0] == q[0] && p[1] == q[1] && p[2] == q[2]) continue;
    q[0] = p[0];
    q[1] = p[1];
    q[2] = p[2];
    ++moved;
    for (std::uint32_t i = d->vertex_face_start[v]; i < d->vertex_face_start[v + 1]; ++i) {
      const std::uint32_t f = d->vertex_faces[i];
      if (d->face_stamp[f] == stamp) continue;
      d->face_stamp[f] = stamp;
      touched_faces.push_back(f);
    }
  }
  for (std::uint32_t f : touched_faces) Impl::compute_face_normal(*d, f);
  // 2. Corners of touched faces get new vertex normals; the GPU range to send
  // spans them (moved vertices are corners of touched faces, or isolated).
  size_t first = nv, last = 0;
  int renormalized = 0;
  for (std::uint32_t f : touched_faces)
    for (int c = 0; c < 3; ++c) {
      const size_t v = static_cast<size_t>(d->triangles[f][c]);
      if (d->vertex_stamp[v] == stamp) continue;
      d->vertex_stamp[v] = stamp;
      Impl::compute_vertex_normal(*d, v);
      ++renormalized;
      first = std::min(first, v);
      last = std::max(last, v + 1);
    }
  d->bbox.min = Vec3(lo[0], lo[1], lo[2]);
  d->bbox.max = Vec3(hi[0], hi[1], hi[2]);
  if (stats) {
    stats->moved_vertices = moved;
    stats->renormalized = renormalized;
  }
  if (moved == 0) return Status::success();

  // 3. Upload. Unrolled meshes and the whole-array option send everything.
  size_t uploaded = 0;
  const size_t total = static_cast<size_t>(d->vertex_count);
  if (d->layout == MeshLayout::Unrolled || !m.options.upload_dirty_range) {
    Impl::send_geometry(*d, 0, total, false);
    uploaded = total;
  } else {
    if (first < last) {
      Impl::send_geometry(*d, first, last, false);
      uploaded += last - first;
    }
    // Seam copies sit after the first #V GPU vertices.
    size_t copy_first = total, copy_last = nv;
    for (size_t g = nv; g < total; ++g)
      if (d->vertex_stamp[d->gpu_source[g - nv]] == stamp) {
        copy_first = std::min(copy_first, g);
        copy_last = g + 1;
      }
    if (copy_first < copy_last) {
      Impl::send_geometry(*d, copy_first, copy_last, false);
      uploaded += copy_last - copy_first;
    }
  }
  if (stats) stats->uploaded_vertices = static_cast<int>(uploaded);
  return m.options.check_errors_every_frame ? check_gl("update_mesh_positions") : Status::success();
}

Status Renderer::set_morph_targets(DrawableHandle handle, const std::vector<MorphShape>& shapes) {
  MorphData data;
  if (Status s = prepare_morph_targets(handle, shapes, data); !s.ok()) return s;
  return upload_morph_targets(handle, data);
}

// The prepare's state between steps: the mesh's rest state copied at
// begin (so posing the drawn mesh meanwhile changes nothing here), the
// shapes, the next one to do and the entries so far.
struct Renderer::MorphJob {
  struct Entry {
    std::uint32_t vertex, shape;
    float dp[3], dn[3];
  };
  DrawableHandle handle = kNoHandle;
  Impl::Drawable mesh;
  std::vector<MorphShape> shapes;
  size_t next = 0;
  std::vector<Entry> entries;
  std::vector<std::uint32_t> touched_faces, corners, moved;
  std::vector<float> saved_faces, saved_normals, saved_positions;
  std::vector<int> moved_slot;  // index into the shape's vertices, or -1
  int max_texture_size = 0;
  // Banded upload (finish without texels, then upload_morph_band): the
  // entry in each texel pair's slot, the rows sent so far, one band's texels.
  std::vector<std::uint32_t> order;
  int rows_sent = 0;
  std::vector<float> band;
};

void Renderer::MorphJobDeleter::operator()(MorphJob* job) const { delete job; }

namespace {
// An entry's two texels: (position offset, shape), (normal offset, 0).
void write_entry(const Renderer::MorphJob::Entry& e, float* t) {
  t[0] = e.dp[0], t[1] = e.dp[1], t[2] = e.dp[2], t[3] = static_cast<float>(e.shape);
  t[4] = e.dn[0], t[5] = e.dn[1], t[6] = e.dn[2], t[7] = 0.0f;
}
}  // namespace

Status Renderer::prepare_morph_targets(DrawableHandle handle, const std::vector<MorphShape>& shapes, MorphData& out) {
  out = MorphData{};
  MorphJobPtr job;
  if (Status s = begin_morph_targets(handle, shapes, job); !s.ok()) return s;
  bool done = false;
  if (Status s = step_morph_targets(*job, kMaxMorphTargets, done); !s.ok()) return s;
  return finish_morph_targets(*job, out);
}

Status Renderer::begin_morph_targets(DrawableHandle handle, std::vector<MorphShape> shapes, MorphJobPtr& out) {
  Impl& m = *impl_;
  out.reset();
  Impl::Drawable* d = m.find(handle);
  if (!d || d->is_points) return Status::error(ErrorCode::InvalidInput, "set_morph_targets: no mesh with handle " + std::to_string(handle));
  if (shapes.size() > static_cast<size_t>(kMaxMorphTargets))
    return Status::error(ErrorCode::TooLarge, "set_morph_targets: " + std::to_string(shapes.size()) +
                                                  " shapes, the shader takes at most " + std::to_string(kMaxMorphTargets));
  // The shader's morph uniforms (48 vec4s) beside its ~25 other vectors,
  // and one texture unit in the vertex stage (GLES3 guarantees 256 and 16;
  // checked for odd drivers).
  if (!shapes.empty() && (m.max_vertex_texture_units < 1 || m.max_vertex_uniform_vectors < 128))
    return Status::error(ErrorCode::Unsupported, "set_morph_targets: the GL has " + std::to_string(m.max_vertex_texture_units) +
                                                     " vertex texture units and " + std::to_string(m.max_vertex_uniform_vectors) +
                                                     " vertex uniform vectors");
  const size_t nv = static_cast<size_t>(d->num_vertices);
  std::vector<size_t> seen(nv, SIZE_MAX);
  for (size_t s = 0; s < shapes.size(); ++s) {
    const MorphShape& shape = shapes[s];
    if (shape.offsets.size() != 3 * shape.vertices.size())
      return Status::error(ErrorCode::InvalidInput, "set_morph_targets: shape " + std::to_string(s) + " has " +
                                                        std::to_string(shape.offsets.size()) + " offset values for " +
                                                        std::to_string(shape.vertices.size()) + " vertices");
    for (std::uint32_t v : shape.vertices) {
      if (v >= nv)
        return Status::error(ErrorCode::InvalidInput, "set_morph_targets: shape " + std::to_string(s) + " moves vertex " +
                                                          std::to_string(v) + " of " + std::to_string(nv));
      if (seen[v] == s)
        return Status::error(ErrorCode::InvalidInput, "set_morph_targets: shape " + std::to_string(s) + " lists vertex " +
                                                          std::to_string(v) + " twice");
      seen[v] = s;
    }
    for (float x : shape.offsets)
      if (!std::isfinite(x))
        return Status::error(ErrorCode::InvalidInput, "set_morph_targets: shape " + std::to_string(s) + " has a non-finite offset");
  }

  MorphJobPtr job(new MorphJob);
  job->handle = handle;
  job->mesh = *d;
  job->shapes = std::move(shapes);
  job->moved_slot.assign(nv, -1);
  job->max_texture_size = m.max_texture_size;
  out = std::move(job);
  return Status::success();
}

// Each shape at full weight, renormalized as update_mesh_positions would
// (the moved vertices' triangles, their corners), then restored. Entries:
// (vertex, shape, position offset, normal offset), all-zero ones dropped.
Status Renderer::step_morph_targets(MorphJob& job, int max_shapes, bool& done) {
  Impl::Drawable* d = &job.mesh;
  using Entry = MorphJob::Entry;
  std::vector<Entry>& entries = job.entries;
  std::vector<std::uint32_t>&touched_faces = job.touched_faces, &corners = job.corners, &moved = job.moved;
  std::vector<float>&saved_faces = job.saved_faces, &saved_normals = job.saved_normals, &saved_positions = job.saved_positions;
  std::vector<int>& moved_slot = job.moved_slot;
  const size_t end = std::min(job.shapes.size(), job.next + static_cast<size_t>(std::max(max_shapes, 0)));
  for (size_t s = job.next; s < end; ++s) {
    const MorphShape& shape = job.shapes[s];
    const std::uint32_t stamp = ++d->update_number;
    touched_faces.clear();
    corners.clear();
    moved.clear();
    saved_positions.clear();
    for (size_t k = 0; k < shape.vertices.size(); ++k) {
      const std::uint32_t v = shape.vertices[k];
      const float* o = &shape.offsets[3 * k];
      moved_slot[v] = static_cast<int>(k);
      moved.push_back(v);
      saved_positions.insert(saved_positions.end(), &d->positions[3 * size_t(v)], &d->positions[3 * size_t(v)] + 3);
      if (o[0] == 0.0f && o[1] == 0.0f && o[2] == 0.0f) continue;
      for (int c = 0; c < 3; ++c) d->positions[3 * v + c] += o[c];
      for (std::uint32_t i = d->vertex_face_start[v]; i < d->vertex_face_start[v + 1]; ++i) {
        const std::uint32_t f = d->vertex_faces[i];
        if (d->face_stamp[f] == stamp) continue;
        d->face_stamp[f] = stamp;
        touched_faces.push_back(f);
      }
    }
    saved_faces.resize(3 * touched_faces.size());
    for (size_t i = 0; i < touched_faces.size(); ++i) {
      std::copy_n(&d->face_normals[3 * size_t(touched_faces[i])], 3, &saved_faces[3 * i]);
      Impl::compute_face_normal(*d, touched_faces[i]);
    }
    for (std::uint32_t f : touched_faces)
      for (int c = 0; c < 3; ++c) {
        const std::uint32_t v = static_cast<std::uint32_t>(d->triangles[f][c]);
        if (d->vertex_stamp[v] == stamp) continue;
        d->vertex_stamp[v] = stamp;
        corners.push_back(v);
      }
    std::sort(corners.begin(), corners.end());
    saved_normals.resize(3 * corners.size());
    for (size_t i = 0; i < corners.size(); ++i) {
      const std::uint32_t v = corners[i];
      std::copy_n(&d->normals[3 * size_t(v)], 3, &saved_normals[3 * i]);
      Impl::compute_vertex_normal(*d, v);
      Entry e{v, static_cast<std::uint32_t>(s), {0, 0, 0}, {0, 0, 0}};
      for (int c = 0; c < 3; ++c) e.dn[c] = d->normals[3 * size_t(v) + c] - saved_normals[3 * i + c];
      if (moved_slot[v] >= 0) std::copy_n(&shape.offsets[3 * size_t(moved_slot[v])], 3, e.dp);
      bool any = false;
      for (int c = 0; c < 3; ++c) any = any || e.dp[c] != 0.0f || e.dn[c] != 0.0f;
      if (any) entries.push_back(e);
    }
    // Restore the rest pose exactly (the offsets were added in place).
    for (size_t i = 0; i < corners.size(); ++i) std::copy_n(&saved_normals[3 * i], 3, &d->normals[3 * size_t(corners[i])]);
    for (size_t i = 0; i < touched_faces.size(); ++i) std::copy_n(&saved_faces[3 * i], 3, &d->face_normals[3 * size_t(touched_faces[i])]);
    for (size_t i = 0; i < moved.size(); ++i) {
      std::copy_n(&saved_positions[3 * i], 3, &d->positions[3 * size_t(moved[i])]);
      moved_slot[moved[i]] = -1;
    }
  }
  job.next = end;
  done = job.next == job.shapes.size();
  return Status::success();
}

Status Renderer::finish_morph_targets(MorphJob& job, MorphData& out, bool with_texels) {
  out = MorphData{};
  if (job.next != job.shapes.size())
    return Status::error(ErrorCode::InvalidInput, "set_morph_targets: " + std::to_string(job.shapes.size() - job.next) +
                                                      " shapes not prepared yet");
  if (job.shapes.empty()) return Status::success();
  const Impl::Drawable* d = &job.mesh;
  const std::vector<MorphJob::Entry>& entries = job.entries;
  const size_t nv = static_cast<size_t>(d->num_vertices);
  const int max_texture_size = job.max_texture_size;
  // Grouped by vertex (stable: shapes in order within a vertex).
  std::vector<std::uint32_t> start(nv + 1, 0);
  for (const MorphJob::Entry& e : entries) ++start[e.vertex + 1];
  for (size_t v = 0; v < nv; ++v) start[v + 1] += start[v];
  const size_t total = entries.size();
  // Indices reach the shader as floats: exact below 2^24.
  const int width = std::min(kMorphTextureWidth, max_texture_size - max_texture_size % 2);
  const size_t rows = (2 * total + size_t(width) - 1) / size_t(width);
  if (total >= (size_t(1) << 23) || rows > static_cast<size_t>(max_texture_size))
    return Status::error(ErrorCode::TooLarge, "set_morph_targets: " + std::to_string(total) +
                                                  " morph entries do not fit a " + std::to_string(max_texture_size) +
                                                  " texture");
  {
    std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
    if (with_texels) {
      std::vector<float>& texels = out.texels;
      texels.assign(std::max<size_t>(rows, 1) * size_t(width) * 4, 0.0f);
      for (const MorphJob::Entry& e : entries) write_entry(e, &texels[8 * size_t(fill[e.vertex]++)]);
    } else {
      job.order.assign(total, 0);
      for (size_t i = 0; i < total; ++i) job.order[fill[entries[i].vertex]++] = static_cast<std::uint32_t>(i);
      job.rows_sent = 0;
    }
  }
  std::vector<std::uint32_t> vertex_masks(4 * nv, 0u);
  for (const MorphJob::Entry& e : entries) vertex_masks[4 * size_t(e.vertex) + e.shape / 32] |= 1u << (e.shape % 32);
  std::vector<float>& ranges = out.ranges;
  std::vector<std::uint32_t>& masks = out.masks;
  ranges.assign(2 * static_cast<size_t>(d->vertex_count), 0.0f);
  masks.assign(4 * static_cast<size_t>(d->vertex_count), 0u);
  for (size_t g = 0; g < static_cast<size_t>(d->vertex_count); ++g) {
    const size_t v = Impl::source_of(*d, g);
    ranges[2 * g] = static_cast<float>(start[v]);
    ranges[2 * g + 1] = static_cast<float>(start[v + 1] - start[v]);
    std::copy_n(&vertex_masks[4 * v], 4, &masks[4 * g]);
  }

  out.count = static_cast<int>(job.shapes.size());
  out.width = width;
  out.rows = static_cast<int>(std::max<size_t>(rows, 1));
  out.entries = total;
  return Status::success();
}

Status Renderer::upload_morph_targets(DrawableHandle handle, const MorphData& data) {
  Impl::Drawable* d = impl_->find(handle);
  if (!d || d->is_points) return Status::error(ErrorCode::InvalidInput, "set_morph_targets: no mesh with handle " + std::to_string(handle));
  if (data.count == 0) {
    Impl::release_morph(*d);
    return Status::success();
  }
  if (data.ranges.size() != 2 * static_cast<size_t>(d->vertex_count) || data.masks.size() != 4 * static_cast<size_t>(d->vertex_count) ||
      data.texels.size() != 4 * size_t(data.width) * size_t(data.rows) || data.count > kMaxMorphTargets)
    return Status::error(ErrorCode::InvalidInput, "set_morph_targets: the prepared data is not this mesh's");
  const std::vector<float>& texels = data.texels;
  const std::vector<float>& ranges = data.ranges;
  const std::vector<std::uint32_t>& masks = data.masks;
  const int width = data.width;
  Impl::release_morph(*d);
  glGenTextures(1, &d->morph_texture);
  glBindTexture(GL_TEXTURE_2D, d->morph_texture);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
  glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA32F, width, data.rows, 0, GL_RGBA, GL_FLOAT,
               texels.data());
  // Float textures are not filterable in WebGL2: texelFetch only, no mipmaps.
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  glBindTexture(GL_TEXTURE_2D, 0);
  glBindVertexArray(d->vao);
  glGenBuffers(1, &d->morph_buffer);
  glBindBuffer(GL_ARRAY_BUFFER, d->morph_buffer);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(ranges.size() * sizeof(float)), ranges.data(), GL_STATIC_DRAW);
  bind_attribute(d->morph_buffer, kMorph, 2);
  glGenBuffers(1, &d->morph_mask_buffer);
  glBindBuffer(GL_ARRAY_BUFFER, d->morph_mask_buffer);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(masks.size() * sizeof(std::uint32_t)), masks.data(), GL_STATIC_DRAW);
  glEnableVertexAttribArray(kMorphMask);
  glVertexAttribIPointer(kMorphMask, 4, GL_UNSIGNED_INT, 0, nullptr);
  glBindVertexArray(0);
  if (Status s = check_gl("set_morph_targets"); !s) {
    glBindVertexArray(d->vao);
    glDisableVertexAttribArray(kMorph);
    glDisableVertexAttribArray(kMorphMask);
    glBindVertexArray(0);
    Impl::release_morph(*d);
    return s;
  }
  d->morph_count = data.count;
  d->morph_texture_width = width;
  d->morph_weights.assign(kMaxMorphTargets, 0.0f);
  return Status::success();
}

Status Renderer::upload_morph_band(DrawableHandle handle, MorphJob& job, const MorphData& data, int max_rows, bool& done) {
  done = false;
  Impl::Drawable* d = impl_->find(handle);
  if (!d || d->is_points) return Status::error(ErrorCode::InvalidInput, "set_morph_targets: no mesh with handle " + std::to_string(handle));
  if (data.count == 0) {
    Impl::release_morph(*d);
    done = true;
    return Status::success();
  }
  if (data.ranges.size() != 2 * static_cast<size_t>(d->vertex_count) || data.masks.size() != 4 * static_cast<size_t>(d->vertex_count) ||
      job.order.size() != data.entries || data.count > kMaxMorphTargets || max_rows < 1)
    return Status::error(ErrorCode::InvalidInput, "set_morph_targets: the prepared data is not this mesh's");
  const int width = data.width;
  if (job.rows_sent == 0) {  // the texture, its texels sent band by band
    Impl::release_morph(*d);
    glGenTextures(1, &d->morph_texture);
    glBindTexture(GL_TEXTURE_2D, d->morph_texture);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA32F, width, data.rows, 0, GL_RGBA, GL_FLOAT, nullptr);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glBindTexture(GL_TEXTURE_2D, 0);
  }
  const int r0 = job.rows_sent, r1 = std::min(data.rows, r0 + max_rows);
  const size_t slots_per_row = size_t(width) / 2, first = size_t(r0) * slots_per_row;
  const size_t last = std::min(size_t(r1) * slots_per_row, job.order.size());
  job.band.assign(size_t(r1 - r0) * size_t(width) * 4, 0.0f);
  for (size_t slot = first; slot < last; ++slot) write_entry(job.entries[job.order[slot]], &job.band[8 * (slot - first)]);
  glBindTexture(GL_TEXTURE_2D, d->morph_texture);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
  glTexSubImage2D(GL_TEXTURE_2D, 0, 0, r0, width, r1 - r0, GL_RGBA, GL_FLOAT, job.band.data());
  glBindTexture(GL_TEXTURE_2D, 0);
  job.rows_sent = r1;
  done = r1 == data.rows;
  return Status::success();
}

Status Renderer::finish_morph_upload(DrawableHandle handle, MorphJob& job, const MorphData& data) {
  Impl::Drawable* d = impl_->find(handle);
  if (!d || d->is_points) return Status::error(ErrorCode::InvalidInput, "set_morph_targets: no mesh with handle " + std::to_string(handle));
  if (data.count == 0) return Status::success();
  if (job.rows_sent != data.rows || !d->morph_texture ||
      data.ranges.size() != 2 * static_cast<size_t>(d->vertex_count) || data.masks.size() != 4 * static_cast<size_t>(d->vertex_count))
    return Status::error(ErrorCode::InvalidInput, "set_morph_targets: the texture's bands are not all sent");
  glBindVertexArray(d->vao);
  glGenBuffers(1, &d->morph_buffer);
  glBindBuffer(GL_ARRAY_BUFFER, d->morph_buffer);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(data.ranges.size() * sizeof(float)), data.ranges.data(), GL_STATIC_DRAW);
  bind_attribute(d->morph_buffer, kMorph, 2);
  glGenBuffers(1, &d->morph_mask_buffer);
  glBindBuffer(GL_ARRAY_BUFFER, d->morph_mask_buffer);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(data.masks.size() * sizeof(std::uint32_t)), data.masks.data(), GL_STATIC_DRAW);
  glEnableVertexAttribArray(kMorphMask);
  glVertexAttribIPointer(kMorphMask, 4, GL_UNSIGNED_INT, 0, nullptr);
  glBindVertexArray(0);
  // Errors are asked for once, here (they stay set until read): in a
  // browser glGetError waits for the GPU process to finish the work queued
  // before it (under SwiftShader, the CPU path's last draws), which every
  // band would pay.
  if (Status s = check_gl("set_morph_targets"); !s) {
    glBindVertexArray(d->vao);
    glDisableVertexAttribArray(kMorph);
    glDisableVertexAttribArray(kMorphMask);
    glBindVertexArray(0);
    Impl::release_morph(*d);
    job.rows_sent = 0;
    return s;
  }
  d->morph_count = data.count;
  d->morph_texture_width = data.width;
  d->morph_weights.assign(kMaxMorphTargets, 0.0f);
  job.band = {};
  return Status::success();
}

Status Renderer::set_morph_weights(DrawableHandle handle, const float* weights, size_t count) {
  Impl::Drawable* d = impl_->find(handle);
  if (!d || d->is_points) return Status::error(ErrorCode::InvalidInput, "set_morph_weights: no mesh with handle " + std::to_string(handle));
  if (count > static_cast<size_t>(d->morph_count))
    return Status::error(ErrorCode::InvalidInput, "set_morph_weights: " + std::to_string(count) + " weights for " +
                                                      std::to_string(d->morph_count) + " morph targets");
  if (count > 0 && !weights) return Status::error(ErrorCode::InvalidInput, "set_morph_weights: no weights");
  for (size_t i = 0; i < count; ++i)
    if (!std::isfinite(weights[i])) return Status::error(ErrorCode::InvalidInput, "set_morph_weights: a weight is not finite");
  d->morph_active_shapes.assign(kMaxActiveMorphs, 0);
  d->morph_active_weights.assign(kMaxActiveMorphs, 0.0f);
  int active = 0;
  for (size_t i = 0; i < d->morph_weights.size(); ++i) {
    const float w = i < count ? weights[i] : 0.0f;
    d->morph_weights[i] = w;
    if (w == 0.0f) continue;
    if (active < kMaxActiveMorphs) {
      d->morph_active_shapes[size_t(active)] = static_cast<int>(i);
      d->morph_active_weights[size_t(active)] = w;
    }
    ++active;
  }
  d->morph_mode = active == 0 ? 0 : active <= kMaxActiveMorphs ? 1 : 2;
  return Status::success();
}

int Renderer::morph_target_count(DrawableHandle handle) const {
  const Impl::Drawable* d = impl_->find(handle);
  return d ? d->morph_count : 0;
}

Status Renderer::set_occlusion(DrawableHandle handle, const std::vector<float>& per_vertex) {
  Impl::Drawable* d = impl_->find(handle);
  if (!d || d->is_points) return Status::error(ErrorCode::InvalidInput, "set_occlusion: no mesh with handle " + std::to_string(handle));
  if (per_vertex.empty()) {
    d->has_occlusion = false;
    return Status::success();
  }
  if (per_vertex.size() != static_cast<size_t>(d->num_vertices))
    return Status::error(ErrorCode::InvalidInput, "set_occlusion: " + std::to_string(per_vertex.size()) +
                                                      " values for a mesh of " + std::to_string(d->num_vertices) + " vertices");
  std::vector<float> clamped(per_vertex.size());
  for (size_t v = 0; v < per_vertex.size(); ++v)
    clamped[v] = std::isfinite(per_vertex[v]) ? std::clamp(per_vertex[v], 0.0f, 1.0f) : 1.0f;
  const std::vector<float> gpu = Impl::per_gpu_vertex(*d, clamped, 1);
  glBindVertexArray(d->vao);
  if (!d->occlusion_buffer) glGenBuffers(1, &d->occlusion_buffer);
  glBindBuffer(GL_ARRAY_BUFFER, d->occlusion_buffer);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(gpu.size() * sizeof(float)), gpu.data(), GL_STATIC_DRAW);
  bind_attribute(d->occlusion_buffer, kOcclusion, 1);
  glBindVertexArray(0);
  d->has_occlusion = true;
  return check_gl("set_occlusion");
}

Status Renderer::upload_points(const PointCloud& cloud, DrawableHandle& out) {
  out = kNoHandle;
  if (!impl_->ready) return Status::error(ErrorCode::InvalidInput, "renderer not initialized (call init() on a current GL context)");
  const size_t n = cloud.positions.size();
  if (n == 0) return Status::error(ErrorCode::Empty, "point cloud has no points");
  if (!cloud.normals.empty() && cloud.normals.size() != n)
    return Status::error(ErrorCode::InvalidInput, "point cloud has " + std::to_string(cloud.normals.size()) +
                                                      " normals for " + std::to_string(n) + " points");
  if (!cloud.colors.empty() && cloud.colors.size() != n)
    return Status::error(ErrorCode::InvalidInput, "point cloud has " + std::to_string(cloud.colors.size()) +
                                                      " colors for " + std::to_string(n) + " points");
  if (n > static_cast<size_t>(1) << 30) return Status::error(ErrorCode::TooLarge, "point cloud too large to draw");
  for (const Vec3& p : cloud.positions)
    if (!finite(p)) return Status::error(ErrorCode::InvalidInput, "point cloud has a non-finite position");

  auto flat = [](const std::vector<Vec3>& v) {
    std::vector<float> out_f;
    out_f.reserve(v.size() * 3);
    for (const Vec3& p : v)
      for (int k = 0; k < 3; ++k) out_f.push_back(static_cast<float>(p[k]));
    return out_f;
  };
  Impl& m = *impl_;
  Impl::Drawable d;
  d.is_points = true;
  d.num_vertices = static_cast<int>(n);
  d.vertex_count = static_cast<GLsizei>(n);
  d.bbox = bounding_box(cloud.positions);
  d.has_normals = !cloud.normals.empty();
  d.has_colors = !cloud.colors.empty();
  d.style.point_coloring = PointColoring::Auto;
  glGenVertexArrays(1, &d.vao);
  glBindVertexArray(d.vao);
  glGenBuffers(1, &d.position_buffer);
  upload_vec3s(d.position_buffer, flat(cloud.positions), GL_STATIC_DRAW);
  bind_attribute(d.position_buffer, kPosition, 3);
  if (d.has_normals) {
    glGenBuffers(1, &d.normal_buffer);
    upload_vec3s(d.normal_buffer, flat(cloud.normals), GL_STATIC_DRAW);
    bind_attribute(d.normal_buffer, kNormal, 3);
  }
  if (d.has_colors) {
    glGenBuffers(1, &d.color_buffer);
    upload_vec3s(d.color_buffer, flat(cloud.colors), GL_STATIC_DRAW);
    bind_attribute(d.color_buffer, kColor, 3);
  }
  glBindVertexArray(0);
  Status s = check_gl("upload_points");
  if (!s) {
    m.release(d);
    return s;
  }
  out = m.next_handle++;
  m.drawables[out] = std::move(d);
  return Status::success();
}

Status Renderer::upload_texture(const Image& image, TextureHandle& out) {
  out = kNoHandle;
  Impl& m = *impl_;
  if (!m.ready) return Status::error(ErrorCode::InvalidInput, "renderer not initialized (call init() on a current GL context)");
  if (image.empty()) return Status::error(ErrorCode::Empty, "texture image is empty");
  if (image.channels < 1 || image.channels > 4 ||
      image.pixels.size() != static_cast<size_t>(image.width) * image.height * image.channels)
    return Status::error(ErrorCode::InvalidInput, "texture image has inconsistent size/channels");
  if (image.width > m.max_texture_size || image.height > m.max_texture_size)
    return Status::error(ErrorCode::TooLarge, "texture " + std::to_string(image.width) + "x" +
                                                  std::to_string(image.height) + " exceeds GL_MAX_TEXTURE_SIZE " +
                                                  std::to_string(m.max_texture_size));
  // RGBA rows, bottom row first: uv (0,0) is the image's lower-left corner
  // (the OBJ convention) while lk::Image stores the top row first.
  const int w = image.width, h = image.height, c = image.channels;
  std::vector<std::uint8_t> rgba(static_cast<size_t>(w) * h * 4);
  for (int y = 0; y < h; ++y) {
    const std::uint8_t* src = image.at(0, h - 1 - y);
    std::uint8_t* dst = &rgba[static_cast<size_t>(y) * w * 4];
    for (int x = 0; x < w; ++x, src += c, dst += 4) {
      dst[0] = src[0];
      dst[1] = c >= 3 ? src[1] : src[0];
      dst[2] = c >= 3 ? src[2] : src[0];
      dst[3] = c == 4 ? src[3] : (c == 2 ? src[1] : 255);
      // Premultiplied alpha: filtering then averages only the visible texels'
      // colours (the shader divides by alpha), so the colour code of a
      // transparent texel (the teeth voids' blue) never bleeds into its
      // neighbours or into coarser mip levels.
      if (dst[3] < 255)
        for (int k = 0; k < 3; ++k) dst[k] = static_cast<std::uint8_t>((dst[k] * dst[3] + 127) / 255);
    }
  }
  GLuint tex = 0;
  glGenTextures(1, &tex);
  glBindTexture(GL_TEXTURE_2D, tex);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glTexImage2D(GL_TEXTURE_2D, 0, GL_SRGB8_ALPHA8, w, h, 0, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
  glGenerateMipmap(GL_TEXTURE_2D);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  glBindTexture(GL_TEXTURE_2D, 0);
  Status s = check_gl("upload_texture");
  if (!s) {
    glDeleteTextures(1, &tex);
    return s;
  }
  out = m.next_texture++;
  m.textures[out] = tex;
  for (size_t i = 3; i < rgba.size(); i += 4)
    if (rgba[i] < 255) {
      m.transparent_textures.insert(out);
      break;
    }
  return Status::success();
}

Status Renderer::attach_texture(DrawableHandle mesh, TextureHandle texture) {
  Impl::Drawable* d = impl_->find(mesh);
  if (!d || d->is_points) return Status::error(ErrorCode::InvalidInput, "attach_texture: no mesh with handle " + std::to_string(mesh));
  if (texture != kNoHandle && !impl_->textures.count(texture))
    return Status::error(ErrorCode::InvalidInput, "attach_texture: no texture with handle " + std::to_string(texture));
  if (texture != kNoHandle && !d->has_uvs)
    return Status::error(ErrorCode::InvalidInput, "attach_texture: the mesh has no uvs");
  d->texture = texture;
  return Status::success();
}

DrawStyle* Renderer::style(DrawableHandle handle) {
  Impl::Drawable* d = impl_->find(handle);
  return d ? &d->style : nullptr;
}

namespace {
Status no_drawable(const char* what, DrawableHandle h) {
  return Status::error(ErrorCode::InvalidInput, std::string(what) + ": no drawable with handle " + std::to_string(h));
}
}  // namespace

Status Renderer::set_visible(DrawableHandle handle, bool visible) {
  DrawStyle* s = style(handle);
  if (!s) return no_drawable("set_visible", handle);
  s->visible = visible;
  return Status::success();
}

Status Renderer::set_base_color(DrawableHandle handle, const glm::vec3& srgb) {
  DrawStyle* s = style(handle);
  if (!s) return no_drawable("set_base_color", handle);
  s->base_color = srgb;
  return Status::success();
}

Status Renderer::set_model_matrix(DrawableHandle handle, const glm::mat4& model) {
  DrawStyle* s = style(handle);
  if (!s) return no_drawable("set_model_matrix", handle);
  s->model = model;
  return Status::success();
}

Status Renderer::set_wireframe(DrawableHandle handle, bool wireframe) {
  DrawStyle* s = style(handle);
  if (!s) return no_drawable("set_wireframe", handle);
  s->wireframe = wireframe;
  return Status::success();
}

Status Renderer::set_point_size(DrawableHandle handle, float pixels) {
  DrawStyle* s = style(handle);
  if (!s) return no_drawable("set_point_size", handle);
  if (!(pixels > 0.0f)) return Status::error(ErrorCode::InvalidInput, "set_point_size: size must be positive");
  s->point_size_px = pixels;
  return Status::success();
}

Status Renderer::bounds(DrawableHandle handle, BBox& out) const {
  Impl::Drawable* d = impl_->find(handle);
  if (!d) return no_drawable("bounds", handle);
  out = d->bbox;
  return Status::success();
}

void Renderer::remove(DrawableHandle handle) {
  Impl::Drawable* d = impl_->find(handle);
  if (!d) return;
  impl_->release(*d);
  impl_->drawables.erase(handle);
}

void Renderer::remove_texture(TextureHandle texture) {
  auto it = impl_->textures.find(texture);
  if (it == impl_->textures.end()) return;
  glDeleteTextures(1, &it->second);
  impl_->textures.erase(it);
  impl_->transparent_textures.erase(texture);
  for (auto& [h, d] : impl_->drawables)
    if (d.texture == texture) d.texture = kNoHandle;
}

void Renderer::clear() {
  for (auto& [h, d] : impl_->drawables) impl_->release(d);
  impl_->drawables.clear();
  for (auto& [h, t] : impl_->textures) glDeleteTextures(1, &t);
  impl_->textures.clear();
  impl_->transparent_textures.clear();
}

void Renderer::set_background(const glm::vec3& srgb) { set_background_gradient(srgb, srgb); }

void Renderer::set_background_gradient(const glm::vec3& top_srgb, const glm::vec3& bottom_srgb) {
  impl_->options.background_top = top_srgb;
  impl_->options.background_bottom = bottom_srgb;
}

void Renderer::set_lights(const LightRig& lights) { impl_->options.lights = lights; }

Status Renderer::draw(const CameraMatrices& camera, const Viewport& viewport) {
  Impl& m = *impl_;
  if (!m.ready) return Status::error(ErrorCode::InvalidInput, "renderer not initialized (call init() on a current GL context)");
  if (viewport.width <= 0 || viewport.height <= 0)
    return Status::error(ErrorCode::InvalidInput, "draw: empty viewport");
  glViewport(viewport.x, viewport.y, viewport.width, viewport.height);
  glScissor(viewport.x, viewport.y, viewport.width, viewport.height);
  glEnable(GL_SCISSOR_TEST);
  glDisable(GL_BLEND);
  // Back faces are drawn (open scans show their insides, lit as seen)
  // unless a mesh proves they cannot be seen (draw_mesh).
  glDisable(GL_CULL_FACE);

  // Background: drawn, not cleared, so it can be a gradient.
  glDisable(GL_DEPTH_TEST);
  glDepthMask(GL_FALSE);
  glUseProgram(m.background_program);
  glUniform3fv(m.background_u["u_top"], 1, glm::value_ptr(m.options.background_top));
  glUniform3fv(m.background_u["u_bottom"], 1, glm::value_ptr(m.options.background_bottom));
  glBindVertexArray(m.background_vao);
  glDrawArrays(GL_TRIANGLES, 0, 3);
  glDepthMask(GL_TRUE);
  glClearDepthf(1.0f);
  glClear(GL_DEPTH_BUFFER_BIT);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LEQUAL);  // wire-only passes over coincident surfaces

  // Opaque things first, then blended edge-only meshes.
  for (auto& [h, d] : m.drawables) {
    if (!d.style.visible) continue;
    if (d.is_points) {
      m.draw_points(d, camera);
    } else if (d.style.surface) {
      m.draw_mesh(d, camera);
      if (d.style.wireframe && d.layout == MeshLayout::Indexed) m.draw_edges(d, camera);
    }
  }
  for (auto& [h, d] : m.drawables) {
    if (!d.style.visible || d.is_points || d.style.surface || !d.style.wireframe) continue;
    if (d.layout == MeshLayout::Unrolled) {
      m.draw_mesh(d, camera);
    } else {
      glDepthMask(GL_FALSE);  // as the unrolled edges: over, never hiding, what follows
      m.draw_edges(d, camera);
      glDepthMask(GL_TRUE);
    }
  }

  glBindVertexArray(0);
  glUseProgram(0);
  glDisable(GL_SCISSOR_TEST);
  return m.options.check_errors_every_frame ? check_gl("Renderer::draw") : Status::success();
}

}  // namespace lk
