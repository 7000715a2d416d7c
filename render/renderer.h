// The shared GL renderer (not from the papers: the display layer every stage's
// results are looked at through): one small forward renderer written against the
// OpenGL ES 3.0 / WebGL2 subset, used by the wasm viewer (SDL2 + WebGL2) and
// by the native harness (OSMesa, see offscreen.h). No windowing here: create
// a Renderer while a GL context is current and use it only on that context.
//
// What it draws:
//   - triangle meshes (TriMesh: positions #V by 3, triangles #F by 3, optional
//     normals #V by 3, colors #V by 3, uvs #V by 2 or 3*#F by 2 per corner),
//     shaded with a key + fill + rim light rig (Blinn-Phong with a skin-tone
//     default albedo), optionally textured (RGB/RGBA image) and optionally with
//     a wireframe overlay;
//   - point clouds (PointCloud: positions #P by 3, optional normals, colors)
//     as round point sprites of a settable size in pixels.
// Shading is done in linear RGB and written gamma-encoded (sRGB), so the
// default framebuffer (not sRGB-aware in WebGL2 or OSMesa) shows correct tones.
//
// Color conventions: DrawStyle colors and backgrounds are sRGB in [0,1] (what
// a person picks); TriMesh::colors are linear RGB (see tri_mesh.h);
// PointCloud::colors are taken as sRGB (scanner colors as stored in files);
// textures are sRGB-encoded images.
//
// Mesh layouts (MeshLayout): meshes are drawn INDEXED by default: one GPU
// vertex per mesh vertex (position + normal interleaved, 24 bytes) and one
// 32-bit index buffer (glDrawElements, GL_UNSIGNED_INT: WebGL2 core), so the
// vertex shader runs once per vertex instead of three times per triangle and
// an animation frame re-uploads only the vertices that moved (and their
// neighbours' normals), never the indices. Per-corner uvs with seams split a
// seam vertex once per distinct uv at upload (the copies are moved with their
// vertex). The wireframe of an indexed mesh is a GL_LINES index buffer of the
// unique edges (built on first use), drawn over the surface pushed back by
// polygon offset; lines are aliased and as wide as the GL allows (WebGL: 1 px).
// The UNROLLED layout (three GPU vertices per triangle) is the old path, kept
// for its wireframe: antialiased barycentric edges of any width, no geometry
// shader; it costs three times the vertex work and GPU memory (~13 MB per
// 100k triangles against ~2.5 MB indexed). Indexed meshes keep CPU copies
// for incremental updates (positions, normals, face normals, the interleaved
// array, vertex-to-triangle lists: ~110 bytes per vertex).
#pragma once
#include "common/status.h"
#include "image/image.h"
#include "mesh/tri_mesh.h"

#include <glm/glm.hpp>

#include <cstdint>
#include <memory>
#include <vector>

namespace lk {

// Identifies an uploaded mesh or point cloud (one namespace for both), or a
// texture. Negative = none.
using DrawableHandle = int;
using TextureHandle = int;
constexpr int kNoHandle = -1;

// How a mesh is laid out on the GPU (see the top of this file).
enum class MeshLayout {
  Indexed,   // one GPU vertex per mesh vertex + 32-bit indices; line wireframe
  Unrolled,  // three GPU vertices per triangle; antialiased barycentric wireframe
};

// What an animation update did (for profiling and tests).
struct MeshUpdateStats {
  int moved_vertices = 0;     // vertices whose position changed
  int renormalized = 0;       // vertices whose normal was recomputed
  int uploaded_vertices = 0;  // GPU vertices re-sent (the dirty range, or all)
};

// How point sprites get their color.
enum class PointColoring {
  Auto,         // colors if present, else normals if present, else base_color
  VertexColor,  // falls back to base_color when the cloud has no colors
  Normal,       // normal mapped to RGB (n * 0.5 + 0.5); base_color when absent
  BaseColor,
};

// Per-drawable appearance and placement. Defaults give a good-looking head.
struct DrawStyle {
  bool visible = true;
  glm::mat4 model = glm::mat4(1.0f);             // object -> world
  glm::vec3 base_color = {0.78f, 0.60f, 0.52f};  // sRGB albedo (skin tone) when no color/texture
  bool use_vertex_colors = true;  // meshes: TriMesh::colors, when present, replace base_color
  bool use_texture = true;        // meshes: attached texture replaces base_color (needs uvs)
  float specular = 0.3f;          // Blinn-Phong specular strength (0 = matte)
  float shininess = 24.0f;        // Blinn-Phong exponent (skin: broad sheen)
  bool flat_shading = false;      // one normal per triangle (facets of a control mesh)
  // Meshes: skip back faces when none can be seen: the mesh is consistently
  // oriented, every edge has at most two triangles, the camera is on the
  // mesh's side of every hole's plane (a head's neck opening: unless it looks
  // up into the neck) and no alpha-tested texture lets one look through.
  // Same image (up to self-intersections), about half the triangles to
  // rasterize: software WebGL's cost. false draws every face, always.
  bool cull_hidden_back_faces = true;
  // Surfaces. With surface = false and wireframe = true only the edges are
  // drawn (a control mesh over its subdivided surface).
  bool surface = true;
  bool wireframe = false;                         // overlay the triangle edges
  glm::vec3 wire_color = {0.10f, 0.12f, 0.16f};   // sRGB
  float wire_width_px = 1.0f;                     // line width in pixels (antialiased)
  // Point clouds.
  float point_size_px = 4.0f;  // sprite diameter in pixels
  PointColoring point_coloring = PointColoring::Auto;
};

// View and projection (GLM conventions: right-handed view, clip z in [-1,1]).
struct CameraMatrices {
  glm::mat4 view = glm::mat4(1.0f);
  glm::mat4 projection = glm::mat4(1.0f);
};

// Pixel rectangle of the framebuffer to draw into (origin bottom-left, as GL).
struct Viewport {
  int x = 0, y = 0, width = 0, height = 0;
};

// Lights are fixed to the camera so every view is lit the same way; the
// directions point from the surface towards the light, in view space.
struct LightRig {
  glm::vec3 key_dir = {-0.60f, 0.60f, 0.50f};   // upper left, in front: models the face
  glm::vec3 key_color = {1.30f, 1.18f, 1.05f};  // warm, linear intensity
  glm::vec3 fill_dir = {0.75f, -0.05f, 0.65f};  // right, low and soft
  glm::vec3 fill_color = {0.16f, 0.19f, 0.26f}; // cool, about 1:6 against the key
  glm::vec3 rim_dir = {0.35f, 0.55f, -0.75f};   // behind, upper right: outlines the silhouette
  glm::vec3 rim_color = {1.00f, 1.00f, 1.05f};
  glm::vec3 ambient_sky = {0.13f, 0.14f, 0.18f};     // hemisphere ambient, from above
  glm::vec3 ambient_ground = {0.05f, 0.045f, 0.045f};  // from below
  float exposure = 1.0f;
};

struct RendererOptions {
  // The background, sRGB: a vertical gradient from top to bottom (equal
  // colors give a flat background).
  glm::vec3 background_top = {0.30f, 0.32f, 0.36f};
  glm::vec3 background_bottom = {0.13f, 0.14f, 0.16f};
  LightRig lights;
  // Animation updates of indexed meshes send only the range of GPU vertices
  // that changed (glBufferSubData); false sends the whole vertex array each
  // time (still without re-allocating it). Measured in `likeness bench --only
  // render` (docs/design/render.md).
  bool upload_dirty_range = true;
  // glGetError after every draw() and animation update. Natively it is
  // cheap; in a browser it is a synchronous round trip to the GPU process
  // that waits for every queued command (SwiftShader: the whole previous
  // draw), which stalls the page once per frame. The web viewer turns it off;
  // uploads always check.
  bool check_errors_every_frame = true;
};

class Renderer {
 public:
  Renderer();
  ~Renderer();  // frees GL objects; the context must still be current
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  // Compiles the embedded shaders on the current context. Fails (with the
  // GLSL log) if they do not compile; every other call is a no-op until
  // init() has succeeded.
  Status init(const RendererOptions& options = {});
  bool ready() const;

  // --- Meshes -----------------------------------------------------------
  // Uploads a mesh; normals are computed (area-weighted) when absent. Fails
  // on empty or invalid meshes (bad indices, NaN) and on attribute arrays of
  // the wrong length.
  Status upload_mesh(const TriMesh& mesh, DrawableHandle& out, MeshLayout layout = MeshLayout::Indexed);
  // Animation: replaces positions (#V, same count and triangles as uploaded)
  // and normals (#V, or empty to recompute them) in place. Without normals
  // this is update_mesh_positions (only what moved is recomputed and sent).
  Status update_mesh(DrawableHandle handle, const std::vector<Vec3>& positions,
                     const std::vector<Vec3>& normals = {});
  // Animation, the fast path: positions_xyz holds vertex_count * 3 floats
  // (x, y, z per vertex; vertex_count must be the uploaded #V). Vertices
  // whose position did not change are skipped: face normals are recomputed
  // for the triangles around moved vertices, vertex normals for those
  // triangles' corners (area-weighted, as at upload), and only the changed
  // GPU vertex range is re-sent. Non-finite values are refused (nothing is
  // changed then). `stats` (optional) says how much was done.
  Status update_mesh_positions(DrawableHandle handle, const float* positions_xyz, size_t vertex_count,
                               MeshUpdateStats* stats = nullptr);

  // Morph targets blended in the vertex shader (glTF-style: position and
  // normal offsets times weights, summed): a frame of animation is then one
  // uniform update, nothing re-sent. `shapes` are sparse offsets from the
  // mesh's CURRENT positions (the rest pose; do not mix with
  // update_mesh_positions while weights are non-zero). The normal offset of
  // each shape is computed here, at full weight, as update_mesh_positions
  // would renormalize that pose (moved vertices and their triangles'
  // corners), so one shape at weight 1 shades as the CPU path does; mixes
  // blend normals linearly (then normalized), as glTF viewers do. Stored as
  // a float data texture: per vertex its entries (shape, position offset,
  // normal offset), 32 bytes each, and per GPU vertex two attributes:
  // (first entry, count) and a 128-bit mask of the shapes it has, so the
  // shader reads only the shapes with a weight (up to 32 of them; more,
  // and it walks every entry). Fails, changing nothing, on bad input or when the GL
  // limits (texture size, vertex texture units, uniform vectors) cannot
  // hold them; the caller then blends on the CPU. An empty list removes them.
  struct MorphShape {
    std::vector<std::uint32_t> vertices;  // source vertex indices (< #V), each at most once
    std::vector<float> offsets;           // 3 per vertex
  };
  static constexpr int kMaxMorphTargets = 128;
  Status set_morph_targets(DrawableHandle handle, const std::vector<MorphShape>& shapes);
  // set_morph_targets in its two halves, for callers that time them or run
  // them apart: prepare (the checks, the normal offsets, the texture's
  // texels and the per-vertex attributes, all on the CPU; the mesh is left
  // as it was) and upload (the GL calls; `data` must come from prepare on
  // the same mesh, unchanged since). An empty shape list prepares a removal.
  struct MorphData {
    int count = 0;                      // shapes
    int width = 0, rows = 0;            // texture size in texels
    std::size_t entries = 0;            // (vertex, shape) entries, 2 texels each
    std::vector<float> texels;          // RGBA32F, width * rows * 4
    std::vector<float> ranges;          // per GPU vertex: first entry, count
    std::vector<std::uint32_t> masks;   // per GPU vertex: 4 words of shape bits
  };
  Status prepare_morph_targets(DrawableHandle handle, const std::vector<MorphShape>& shapes, MorphData& out);
  // The prepare in steps, so that a page can spread it over frames (it
  // measured 2.3 s at once for 77 shapes on 87k vertices in wasm): begin
  // checks the shapes and copies the mesh's current (rest) state, so the
  // mesh may be posed meanwhile (update_mesh_positions) without changing
  // the result; each step prepares up to max_shapes more (done when all
  // are); finish packs the data for upload_morph_targets.
  // prepare_morph_targets is begin, one step of all, finish.
  struct MorphJob;
  struct MorphJobDeleter {
    void operator()(MorphJob* job) const;
  };
  using MorphJobPtr = std::unique_ptr<MorphJob, MorphJobDeleter>;
  Status begin_morph_targets(DrawableHandle handle, std::vector<MorphShape> shapes, MorphJobPtr& out);
  Status step_morph_targets(MorphJob& job, int max_shapes, bool& done);
  // with_texels false: no texels in `out` (43 MB at level 3 of our heads,
  // a heap growth in wasm); upload_morph_band then writes and sends them a
  // band of max_rows rows per call (done after the last), and
  // finish_morph_upload sets the per-vertex attributes and checks for GL
  // errors (the only check: in a browser it waits for the GPU process).
  // The mesh has no morph targets in between.
  Status finish_morph_targets(MorphJob& job, MorphData& out, bool with_texels = true);
  Status upload_morph_band(DrawableHandle handle, MorphJob& job, const MorphData& data, int max_rows, bool& done);
  Status finish_morph_upload(DrawableHandle handle, MorphJob& job, const MorphData& data);
  Status upload_morph_targets(DrawableHandle handle, const MorphData& data);
  // Weights, one per shape (fewer: the rest are 0). All zero draws the rest
  // pose exactly (the shader skips the blend).
  Status set_morph_weights(DrawableHandle handle, const float* weights, size_t count);
  // Shapes attached to the mesh (0: none).
  int morph_target_count(DrawableHandle handle) const;

  // Per-vertex ambient occlusion (#V values in [0,1], 1 = open; see
  // ambient_occlusion.h) darkening ambient and, partly, direct light in
  // cavities. An empty vector removes it. Kept when update_mesh moves vertices.
  Status set_occlusion(DrawableHandle handle, const std::vector<float>& per_vertex);

  // --- Point clouds -----------------------------------------------------
  Status upload_points(const PointCloud& cloud, DrawableHandle& out);

  // --- Textures ---------------------------------------------------------
  // RGB or RGBA 8-bit, sRGB-encoded; mipmapped, linear filtering.
  Status upload_texture(const Image& image, TextureHandle& out);
  // Attaches (or with kNoHandle detaches) a texture to a mesh.
  Status attach_texture(DrawableHandle mesh, TextureHandle texture);

  // --- Per-drawable state -----------------------------------------------
  // style() returns nullptr for an unknown handle.
  DrawStyle* style(DrawableHandle handle);
  Status set_visible(DrawableHandle handle, bool visible);
  Status set_base_color(DrawableHandle handle, const glm::vec3& srgb);
  Status set_model_matrix(DrawableHandle handle, const glm::mat4& model);
  Status set_wireframe(DrawableHandle handle, bool wireframe);
  Status set_point_size(DrawableHandle handle, float pixels);
  // Bounding box of the drawable's positions in object space (before model).
  Status bounds(DrawableHandle handle, BBox& out) const;
  void remove(DrawableHandle handle);
  void remove_texture(TextureHandle texture);
  void clear();  // removes every drawable and texture

  // --- Frame ------------------------------------------------------------
  void set_background(const glm::vec3& srgb);  // flat
  void set_background_gradient(const glm::vec3& top_srgb, const glm::vec3& bottom_srgb);
  void set_lights(const LightRig& lights);
  // Clears the viewport to the background and draws every visible drawable.
  // Returns an error if GL reported one.
  Status draw(const CameraMatrices& camera, const Viewport& viewport);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace lk
