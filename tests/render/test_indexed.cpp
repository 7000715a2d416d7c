// The indexed draw path (MeshLayout::Indexed) against the unrolled one, and
// animation updates against fresh uploads, under OSMesa. The unrolled layout
// is the reference: both must give the same image for smooth shading,
// vertex colours and textures with uv seams. An incremental update (only
// the moved vertices, their faces' normals and the dirty GPU range) must
// give exactly the image of uploading the moved mesh from scratch.
#include <catch2/catch.hpp>

#include "mesh/geometry.h"
#include "render/camera.h"
#include "render/offscreen.h"
#include "render/renderer.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <vector>

using namespace lk;

namespace {

constexpr double kPi = 3.14159265358979323846;

// An ellipsoid (rings x segments) with per-corner spherical uvs: the
// triangles closing the ring use u = 1 where their other corners' vertex
// has u = 0, so every vertex on the seam meridian carries two uvs (and the
// poles one per segment). Per-vertex colours vary with height.
TriMesh seamed_ellipsoid(const Vec3& radii, int rings, int segments) {
  TriMesh m;
  for (int i = 0; i <= rings; ++i)
    for (int j = 0; j < segments; ++j) {
      const double theta = kPi * i / rings, phi = 2 * kPi * j / segments;
      m.positions.emplace_back(radii.x() * std::sin(theta) * std::sin(phi), radii.y() * std::cos(theta),
                               radii.z() * std::sin(theta) * std::cos(phi));
      m.colors.emplace_back(0.2 + 0.6 * i / rings, 0.3, 0.8 - 0.6 * i / rings);
    }
  auto id = [&](int i, int j) { return i * segments + (j % segments); };
  auto uv = [&](int i, int j) { return Vec2(double(j) / segments, 1.0 - double(i) / rings); };
  m.uv_per_corner = true;
  for (int i = 0; i < rings; ++i)
    for (int j = 0; j < segments; ++j) {
      if (i > 0) {
        m.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
        for (const Vec2& t : {uv(i, j), uv(i + 1, j), uv(i + 1, j + 1)}) m.uvs.push_back(t);
      }
      if (i < rings - 1) {
        m.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
        for (const Vec2& t : {uv(i, j), uv(i + 1, j + 1), uv(i, j + 1)}) m.uvs.push_back(t);
      }
    }
  return m;
}

// A watertight ellipsoid: one vertex per pole, outward CCW faces.
TriMesh closed_ellipsoid(const Vec3& radii, int rings, int segments) {
  TriMesh m;
  m.positions.emplace_back(0.0, radii.y(), 0.0);
  for (int i = 1; i < rings; ++i)
    for (int j = 0; j < segments; ++j) {
      const double theta = kPi * i / rings, phi = 2 * kPi * j / segments;
      m.positions.emplace_back(radii.x() * std::sin(theta) * std::sin(phi), radii.y() * std::cos(theta),
                               radii.z() * std::sin(theta) * std::cos(phi));
    }
  m.positions.emplace_back(0.0, -radii.y(), 0.0);
  const int south = m.num_vertices() - 1;
  auto id = [&](int i, int j) { return 1 + (i - 1) * segments + (j % segments); };
  for (int j = 0; j < segments; ++j) {
    m.triangles.push_back({0, id(1, j), id(1, j + 1)});
    m.triangles.push_back({south, id(rings - 1, j + 1), id(rings - 1, j)});
  }
  for (int i = 1; i < rings - 1; ++i)
    for (int j = 0; j < segments; ++j) {
      m.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      m.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return m;
}

// 8x8 checker of saturated colours, so a wrong uv at a seam shows.
Image checker_texture() {
  Image tex = Image::make(64, 64, 3);
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x) {
      std::uint8_t* p = tex.at(x, y);
      const int cell = (x / 8 + y / 8) % 2;
      p[0] = cell ? 230 : 40;
      p[1] = cell ? 200 : 120;
      p[2] = static_cast<std::uint8_t>(x * 4);
    }
  return tex;
}

// A smooth bump of height `amount` on the +z side, moving only the vertices
// within `radius` of the bump's centre (the animation's local update).
std::vector<Vec3> bumped(const std::vector<Vec3>& p, double amount, double radius = 0.05) {
  const Vec3 centre(0.02, 0.03, 0.09);
  std::vector<Vec3> out = p;
  for (Vec3& q : out) {
    const double d = (q - centre).norm();
    if (d < radius) q += Vec3(0.0, 0.0, amount * 0.5 * (1 + std::cos(kPi * d / radius)));
  }
  return out;
}

std::vector<float> flat(const std::vector<Vec3>& p) {
  std::vector<float> out(p.size() * 3);
  for (size_t i = 0; i < p.size(); ++i)
    for (int k = 0; k < 3; ++k) out[3 * i + k] = static_cast<float>(p[i][k]);
  return out;
}

struct ImageDiff {
  int max = 0;             // largest channel difference
  double fraction = 0;     // pixels differing by more than 2 in some channel
};

ImageDiff compare(const Image& a, const Image& b) {
  REQUIRE(a.width == b.width);
  REQUIRE(a.height == b.height);
  REQUIRE(a.channels == b.channels);
  ImageDiff d;
  int differing = 0;
  for (int y = 0; y < a.height; ++y)
    for (int x = 0; x < a.width; ++x) {
      int worst = 0;
      for (int c = 0; c < a.channels; ++c) worst = std::max(worst, std::abs(int(a.at(x, y)[c]) - int(b.at(x, y)[c])));
      d.max = std::max(d.max, worst);
      differing += worst > 2;
    }
  d.fraction = double(differing) / (a.width * a.height);
  return d;
}

Image render(const SceneSetup& setup, const CameraMatrices& cam, bool dirty_range = true) {
  OffscreenOptions o;
  o.width = o.height = 160;
  o.supersample = 1;
  o.renderer.upload_dirty_range = dirty_range;
  Image im;
  const Status s = render_offscreen(setup, [&](float) { return cam; }, o, im);
  INFO(s.message);
  REQUIRE(s.ok());
  return im;
}

CameraMatrices three_quarter(const TriMesh& m) {
  return canonical_view(CanonicalView::ThreeQuarter, bounding_box(m.positions), 1.0f).matrices(1.0f);
}

const Vec3 kRadii(0.075, 0.11, 0.095);

}  // namespace

TEST_CASE("indexed and unrolled layouts draw the same image", "[render][indexed]") {
  const TriMesh seamed = seamed_ellipsoid(kRadii, 40, 56);
  TriMesh plain = seamed;  // no colours, no uvs: the untextured skin-tone head
  plain.colors.clear();
  plain.uvs.clear();
  plain.uv_per_corner = false;
  const Image tex = checker_texture();
  // The three-quarter view looks at the seam meridian (phi = 0 faces +z).
  const CameraMatrices cam = three_quarter(seamed);

  struct Case {
    const char* name;
    const TriMesh* mesh;
    bool textured, flat_shading;
  };
  for (const Case& c : {Case{"smooth", &plain, false, false}, Case{"flat", &plain, false, true},
                        Case{"vertex colours", &seamed, false, false}, Case{"textured, uv seam", &seamed, true, false}}) {
    auto scene = [&](MeshLayout layout) {
      return [&, layout](Renderer& r) {
        DrawableHandle h;
        Status s = r.upload_mesh(*c.mesh, h, layout);
        if (s) r.style(h)->flat_shading = c.flat_shading;
        if (s && c.textured) {
          TextureHandle t;
          s = r.upload_texture(tex, t);
          if (s) s = r.attach_texture(h, t);
        }
        return s;
      };
    };
    const Image indexed = render(scene(MeshLayout::Indexed), cam);
    const Image unrolled = render(scene(MeshLayout::Unrolled), cam);
    const ImageDiff d = compare(indexed, unrolled);
    INFO(c.name << ": max channel difference " << d.max << ", " << 100 * d.fraction << " % of pixels differ by > 2");
    // Same vertices, same interpolation: at most rounding at a few pixels.
    CHECK(d.fraction < 0.001);
    CHECK(d.max <= 8);
  }
}

TEST_CASE("a seam-split textured mesh shows both sides of the seam right", "[render][indexed]") {
  // Per-corner uvs that jump at the seam: if the split copies were missing,
  // the seam triangles would interpolate u from 1 back to 0 and show the
  // whole texture squeezed into one column of triangles. The unrolled
  // layout never shares vertices, so it is the ground truth; comparing only
  // near the seam makes the check sensitive there.
  const TriMesh seamed = seamed_ellipsoid(kRadii, 24, 16);  // wide seam triangles
  const CameraMatrices cam = canonical_view(CanonicalView::Front, bounding_box(seamed.positions), 1.0f).matrices(1.0f);
  const Image tex = checker_texture();
  auto scene = [&](MeshLayout layout) {
    return [&, layout](Renderer& r) {
      DrawableHandle h;
      TextureHandle t;
      Status s = r.upload_mesh(seamed, h, layout);
      if (s) s = r.upload_texture(tex, t);
      if (s) s = r.attach_texture(h, t);
      return s;
    };
  };
  const ImageDiff d = compare(render(scene(MeshLayout::Indexed), cam), render(scene(MeshLayout::Unrolled), cam));
  INFO("max channel difference " << d.max << ", " << 100 * d.fraction << " % differ");
  CHECK(d.fraction < 0.001);
}

TEST_CASE("an animation update gives the image of a fresh upload", "[render][indexed]") {
  const TriMesh rest = seamed_ellipsoid(kRadii, 48, 64);
  const CameraMatrices cam =
      canonical_view(CanonicalView::Front, bounding_box(rest.positions), 1.0f).matrices(1.0f);
  const Image tex = checker_texture();
  const std::vector<double> poses = {0.02, 0.035, 0.01};  // the bump rises, rises more, falls back

  for (const bool textured : {false, true})
    for (const bool dirty_range : {true, false}) {
      MeshUpdateStats last_stats;
      auto attach = [&](Renderer& r, DrawableHandle h) {
        if (!textured) return Status::success();
        TextureHandle t;
        Status s = r.upload_texture(tex, t);
        return s ? r.attach_texture(h, t) : s;
      };
      // Animated: the rest pose uploaded, then every pose as a partial update.
      const Image animated = render(
          [&](Renderer& r) {
            DrawableHandle h;
            Status s = r.upload_mesh(rest, h);
            if (s) s = attach(r, h);
            for (double amount : poses) {
              if (!s) break;
              const std::vector<float> xyz = flat(bumped(rest.positions, amount));
              s = r.update_mesh_positions(h, xyz.data(), rest.positions.size(), &last_stats);
            }
            return s;
          },
          cam, dirty_range);
      // Fresh: the last pose uploaded as a new mesh (normals computed at upload).
      TriMesh last = rest;
      last.positions = bumped(rest.positions, poses.back());
      const Image fresh = render(
          [&](Renderer& r) {
            DrawableHandle h;
            Status s = r.upload_mesh(last, h);
            return s ? attach(r, h) : s;
          },
          cam, dirty_range);
      const Image at_rest = render(
          [&](Renderer& r) {
            DrawableHandle h;
            Status s = r.upload_mesh(rest, h);
            return s ? attach(r, h) : s;
          },
          cam, dirty_range);
      const ImageDiff same = compare(animated, fresh);
      const ImageDiff moved = compare(animated, at_rest);
      INFO("textured " << textured << ", dirty range " << dirty_range << ": animated vs fresh max " << same.max
                       << " (" << 100 * same.fraction << " %), vs rest " << 100 * moved.fraction << " % differ; moved "
                       << last_stats.moved_vertices << ", renormalized " << last_stats.renormalized << ", uploaded "
                       << last_stats.uploaded_vertices << " of " << rest.positions.size());
      CHECK(same.max == 0);             // the same floats reach the GPU
      CHECK(moved.fraction > 0.002);    // and the bump is really visible
      // Only the bump moved: a local update, not a whole-mesh one.
      CHECK(last_stats.moved_vertices > 10);
      CHECK(last_stats.moved_vertices < int(rest.positions.size()) / 10);
      CHECK(last_stats.renormalized > last_stats.moved_vertices);  // their neighbours' normals too
      if (dirty_range) CHECK(last_stats.uploaded_vertices < int(rest.positions.size()) / 2);
      else CHECK(last_stats.uploaded_vertices >= int(rest.positions.size()));
    }
}

// Draws `rest` as uploaded, and again after bad_calls(renderer, handle) ran
// on it: a refused call must leave the image bit for bit as it was.
template <class BadCalls>
void check_leaves_mesh_as_it_was(const TriMesh& rest, const BadCalls& bad_calls) {
  const CameraMatrices cam = three_quarter(rest);
  const Image before = render(
      [&](Renderer& r) {
        DrawableHandle h;
        return r.upload_mesh(rest, h);
      },
      cam);
  const Image after = render(
      [&](Renderer& r) {
        DrawableHandle h;
        const Status s = r.upload_mesh(rest, h);
        return s ? bad_calls(r, h) : s;
      },
      cam);
  CHECK(compare(before, after).max == 0);
}

TEST_CASE("update_mesh_positions refuses bad input and leaves the mesh as it was", "[render][indexed]") {
  const TriMesh rest = seamed_ellipsoid(kRadii, 12, 16);
  check_leaves_mesh_as_it_was(rest, [&](Renderer& r, DrawableHandle h) {
        std::vector<float> xyz = flat(bumped(rest.positions, 0.05, 0.2));
        CHECK(r.update_mesh_positions(h, xyz.data(), rest.positions.size() - 1).code == ErrorCode::InvalidInput);
        CHECK(r.update_mesh_positions(h + 7, xyz.data(), rest.positions.size()).code == ErrorCode::InvalidInput);
        CHECK(r.update_mesh_positions(h, nullptr, rest.positions.size()).code == ErrorCode::InvalidInput);
        xyz[3 * 5 + 1] = std::nanf("");
        CHECK(r.update_mesh_positions(h, xyz.data(), rest.positions.size()).code == ErrorCode::InvalidInput);
        MeshUpdateStats stats;
        const std::vector<float> same = flat(rest.positions);
        const Status s = r.update_mesh_positions(h, same.data(), rest.positions.size(), &stats);
        CHECK(stats.moved_vertices == 0);
        CHECK(stats.uploaded_vertices == 0);
        return s;
      });
}

TEST_CASE("the indexed wireframe draws every edge once, over the surface", "[render][indexed]") {
  TriMesh coarse = seamed_ellipsoid(kRadii, 8, 12);
  coarse.colors.clear();
  coarse.uvs.clear();
  coarse.uv_per_corner = false;
  const CameraMatrices cam =
      canonical_view(CanonicalView::Front, bounding_box(coarse.positions), 1.0f).matrices(1.0f);
  auto scene = [&](MeshLayout layout, bool wire) {
    return [&, layout, wire](Renderer& r) {
      DrawableHandle h;
      Status s = r.upload_mesh(coarse, h, layout);
      if (s) s = r.set_wireframe(h, wire);
      return s;
    };
  };
  auto luminance = [](const Image& im, int x, int y) {
    const std::uint8_t* p = im.at(x, y);
    return 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
  };
  const Image plain = render(scene(MeshLayout::Indexed, false), cam);
  const Image lines = render(scene(MeshLayout::Indexed, true), cam);
  const Image bary = render(scene(MeshLayout::Unrolled, true), cam);
  // How much an overlay darkens each pixel of the plain surface.
  auto darkening = [&](const Image& im, int x, int y) { return std::max(0.0, luminance(plain, x, y) - luminance(im, x, y)); };
  double line_ink = 0, bary_ink = 0;
  int line_px = 0, near = 0;
  for (int y = 1; y + 1 < plain.height; ++y)
    for (int x = 1; x + 1 < plain.width; ++x) {
      line_ink += darkening(lines, x, y);
      bary_ink += darkening(bary, x, y);
      if (darkening(lines, x, y) < 40) continue;
      ++line_px;
      bool found = false;
      for (int dy = -1; dy <= 1 && !found; ++dy)
        for (int dx = -1; dx <= 1 && !found; ++dx) found = darkening(bary, x + dx, y + dy) > 10;
      near += found;
    }
  INFO("ink (summed darkening): lines " << line_ink << ", barycentric " << bary_ink << "; " << near << " of "
                                        << line_px << " line pixels lie on a barycentric edge");
  // Both draw the visible edges ~1 px wide: similar ink (the barycentric
  // edges are antialiased, the lines are not; hidden edges are in neither).
  CHECK(line_px > 300);
  CHECK(line_ink > 0.6 * bary_ink);
  CHECK(line_ink < 1.6 * bary_ink);
  // And the lines lie where the unrolled layout draws the edges.
  CHECK(near > 0.95 * line_px);
}

TEST_CASE("hidden back faces are culled only when none can be seen", "[render][indexed][cull]") {
  // Renders with DrawStyle::cull_hidden_back_faces on and off; they must
  // agree whenever the renderer decides to cull, and a case where culling
  // would show must prove it does cull.
  const TriMesh closed = closed_ellipsoid(kRadii, 24, 32);
  // An open "neck": the bottom cap's triangles (around the -y pole) removed.
  TriMesh open = closed;
  open.triangles.erase(std::remove_if(open.triangles.begin(), open.triangles.end(),
                                      [&](const Tri& t) {
                                        for (int c = 0; c < 3; ++c)
                                          if (open.positions[t[c]].y() < -0.1) return true;
                                        return false;
                                      }),
                       open.triangles.end());
  // The same shell with every other triangle flipped: no consistent outside.
  TriMesh mixed = closed;
  for (size_t f = 0; f < mixed.triangles.size(); f += 2) std::swap(mixed.triangles[f][1], mixed.triangles[f][2]);
  // Inside out: consistently oriented, so culled, and then the far side shows.
  TriMesh inverted = closed;
  for (Tri& t : inverted.triangles) std::swap(t[1], t[2]);

  auto draw = [&](const TriMesh& m, const OrbitCamera& cam, bool cull) {
    return render(
        [&, cull](Renderer& r) {
          DrawableHandle h;
          Status s = r.upload_mesh(m, h);
          if (s) r.style(h)->cull_hidden_back_faces = cull;
          return s;
        },
        cam.matrices(1.0f));
  };
  OrbitCamera side = canonical_view(CanonicalView::ThreeQuarter, bounding_box(closed.positions), 1.0f);
  OrbitCamera below = side;
  below.pitch_deg = -70.0f;  // looking up into the open bottom
  for (const OrbitCamera& cam : {side, below}) {
    for (const TriMesh* m : std::vector<const TriMesh*>{&closed, &open, &mixed}) {
      const ImageDiff d = compare(draw(*m, cam, true), draw(*m, cam, false));
      INFO("pitch " << cam.pitch_deg << ", mesh of " << m->triangles.size() << " triangles: max difference " << d.max);
      CHECK(d.max == 0);
    }
  }
  // From below the open shell's inside shows (lit, not background): the
  // hole test kept the back faces.
  const Image up = draw(open, below, true);
  const Image up_closed = draw(closed, below, true);
  CHECK(compare(up, up_closed).fraction > 0.01);
  const ImageDiff inv = compare(draw(inverted, side, true), draw(inverted, side, false));
  INFO("inside-out shell, culled vs not: " << 100 * inv.fraction << " % differ");
  CHECK(inv.fraction > 0.05);
}

namespace {

// A morph target from rest to `posed`: the vertices that moved and their offsets.
Renderer::MorphShape morph_from(const std::vector<Vec3>& rest, const std::vector<Vec3>& posed) {
  Renderer::MorphShape shape;
  for (size_t v = 0; v < rest.size(); ++v) {
    const Vec3 d = posed[v] - rest[v];
    if (d.isZero(0.0)) continue;
    shape.vertices.push_back(static_cast<std::uint32_t>(v));
    for (int k = 0; k < 3; ++k) shape.offsets.push_back(static_cast<float>(posed[v][k]) - static_cast<float>(rest[v][k]));
  }
  return shape;
}

// A second, overlapping shape: a dent on the upper left of the +z side.
std::vector<Vec3> dented(const std::vector<Vec3>& p, double amount) {
  const Vec3 centre(-0.01, 0.05, 0.085);
  std::vector<Vec3> out = p;
  for (Vec3& q : out) {
    const double d = (q - centre).norm();
    if (d < 0.06) q += Vec3(0.3 * amount, 0.0, -amount) * 0.5 * (1 + std::cos(kPi * d / 0.06));
  }
  return out;
}

}  // namespace

TEST_CASE("morph targets blended in the vertex shader match the CPU blend", "[render][indexed][morph]") {
  // The GPU path (set_morph_targets + weights) against the CPU path
  // (rest + sum w_i offsets_i through update_mesh_positions, normals
  // recomputed). One shape at weight 1 carries the CPU's own normals, so
  // the images agree to rounding; a mix blends normals linearly (glTF's
  // way), so smooth shading differs a little where the shapes overlap, but
  // flat shading (normals from the blended positions alone) shows the
  // positions agree; all weights zero is the rest image exactly.
  const TriMesh rest = seamed_ellipsoid(kRadii, 48, 64);
  const CameraMatrices cam =
      canonical_view(CanonicalView::Front, bounding_box(rest.positions), 1.0f).matrices(1.0f);
  const Image tex = checker_texture();
  const std::vector<Vec3> bump = bumped(rest.positions, 0.03), dent = dented(rest.positions, 0.02);
  const std::vector<Renderer::MorphShape> shapes = {morph_from(rest.positions, bump), morph_from(rest.positions, dent)};
  REQUIRE(shapes[0].vertices.size() > 10);
  REQUIRE(shapes[1].vertices.size() > 10);

  for (const bool textured : {false, true}) {
    auto attach = [&](Renderer& r, DrawableHandle h) {
      if (!textured) return Status::success();
      TextureHandle t;
      Status s = r.upload_texture(tex, t);
      return s ? r.attach_texture(h, t) : s;
    };
    // The rest mesh uploaded, shaded as asked, textured or not.
    auto uploaded = [&](Renderer& r, DrawableHandle& h, bool flat_shading) {
      Status s = r.upload_mesh(rest, h);
      if (s) r.style(h)->flat_shading = flat_shading;
      return s ? attach(r, h) : s;
    };
    auto gpu = [&](std::vector<float> weights, bool flat_shading = false) {
      return render(
          [&, weights, flat_shading](Renderer& r) {
            DrawableHandle h;
            Status s = uploaded(r, h, flat_shading);
            if (s) s = r.set_morph_targets(h, shapes);
            if (s) CHECK(r.morph_target_count(h) == 2);
            if (s) s = r.set_morph_weights(h, weights.data(), weights.size());
            return s;
          },
          cam);
    };
    auto cpu = [&](std::vector<float> weights, bool flat_shading = false) {
      return render(
          [&, weights, flat_shading](Renderer& r) {
            DrawableHandle h;
            Status s = uploaded(r, h, flat_shading);
            std::vector<float> xyz = flat(rest.positions);
            for (size_t i = 0; i < shapes.size(); ++i)
              for (size_t k = 0; k < shapes[i].vertices.size(); ++k)
                for (int c = 0; c < 3; ++c) xyz[3 * shapes[i].vertices[k] + c] += weights[i] * shapes[i].offsets[3 * k + c];
            if (s) s = r.update_mesh_positions(h, xyz.data(), rest.positions.size());
            return s;
          },
          cam);
    };
    const Image at_rest = render(
        [&](Renderer& r) {
          DrawableHandle h;
          Status s = r.upload_mesh(rest, h);
          return s ? attach(r, h) : s;
        },
        cam);
    const ImageDiff one = compare(gpu({1.0f, 0.0f}), cpu({1.0f, 0.0f}));
    const ImageDiff mix = compare(gpu({0.6f, 0.8f}), cpu({0.6f, 0.8f}));
    const ImageDiff mix_flat = compare(gpu({0.6f, 0.8f}, true), cpu({0.6f, 0.8f}, true));
    const ImageDiff zero = compare(gpu({0.0f, 0.0f}), at_rest);
    const ImageDiff shown = compare(gpu({0.6f, 0.8f}), at_rest);
    // The GPU blend must be the weighted one: weights swapped look different.
    const ImageDiff swapped = compare(gpu({0.8f, 0.6f}, true), cpu({0.6f, 0.8f}, true));
    INFO("textured " << textured << ": one shape max " << one.max << " (" << 100 * one.fraction << " %), mix max "
                     << mix.max << " (" << 100 * mix.fraction << " %), flat mix max " << mix_flat.max << " ("
                     << 100 * mix_flat.fraction << " %), flat swapped " << 100 * swapped.fraction
                     << " %, zero weights max " << zero.max << ", mix vs rest " << 100 * shown.fraction << " %");
    CHECK(one.fraction < 0.001);
    CHECK(one.max <= 8);
    CHECK(mix_flat.fraction < 0.002);
    CHECK(mix.fraction < 0.06);  // linear normals, exaggerated shapes (3 and 2 cm on an 11 cm head)
    CHECK(zero.max == 0);
    CHECK(shown.fraction > 0.05);
    CHECK(swapped.fraction > 10 * std::max(mix_flat.fraction, 0.001));
  }
}

TEST_CASE("morph targets prepared in steps while the mesh is posed equal those prepared at once", "[render][indexed][morph]") {
  // The page spreads the prepare over frames and draws the pose on the CPU
  // meanwhile (update_mesh_positions on the same mesh): the job works on
  // the rest state copied at begin, so its data must be the one-call data
  // exactly; with the mesh posed before begin, it must differ (the normal
  // offsets are taken from the mesh as it is at begin).
  const TriMesh rest = seamed_ellipsoid(kRadii, 48, 64);
  const CameraMatrices cam =
      canonical_view(CanonicalView::Front, bounding_box(rest.positions), 1.0f).matrices(1.0f);
  const std::vector<Vec3> bump = bumped(rest.positions, 0.03), dent = dented(rest.positions, 0.02);
  const std::vector<Renderer::MorphShape> shapes = {morph_from(rest.positions, bump), morph_from(rest.positions, dent),
                                                    morph_from(rest.positions, bumped(rest.positions, -0.02))};
  const std::vector<float> posed = flat(bump);
  render(
      [&](Renderer& r) {
        DrawableHandle h;
        Status s = r.upload_mesh(rest, h);
        if (!s) return s;
        Renderer::MorphData once, stepped, from_posed;
        REQUIRE(r.prepare_morph_targets(h, shapes, once));
        Renderer::MorphJobPtr job;
        REQUIRE(r.begin_morph_targets(h, shapes, job));
        bool done = false;
        REQUIRE(r.step_morph_targets(*job, 1, done));
        CHECK(!done);
        CHECK(r.finish_morph_targets(*job, stepped).code == ErrorCode::InvalidInput);  // two shapes to go
        REQUIRE(r.update_mesh_positions(h, posed.data(), rest.positions.size()));   // the CPU path's pose meanwhile
        REQUIRE(r.step_morph_targets(*job, 1, done));
        CHECK(!done);
        REQUIRE(r.step_morph_targets(*job, 5, done));
        CHECK(done);
        REQUIRE(r.finish_morph_targets(*job, stepped));
        CHECK(stepped.entries == once.entries);
        CHECK(stepped.width == once.width);
        CHECK(stepped.rows == once.rows);
        CHECK(stepped.texels == once.texels);
        CHECK(stepped.ranges == once.ranges);
        CHECK(stepped.masks == once.masks);
        // Begun on the posed mesh: other normal offsets.
        REQUIRE(r.prepare_morph_targets(h, shapes, from_posed));
        CHECK(from_posed.texels != once.texels);
        // The stepped data uploads and draws as the one-call data.
        const std::vector<float> rest_xyz = flat(rest.positions);
        REQUIRE(r.update_mesh_positions(h, rest_xyz.data(), rest.positions.size()));
        s = r.upload_morph_targets(h, stepped);
        if (s) CHECK(r.morph_target_count(h) == 3);
        return s;
      },
      cam);

  // Uploaded band by band (no texels in the data, one row per call) it
  // draws the image of the one-call upload exactly; 12 shapes, so that
  // the entries fill more than one row of the texture.
  std::vector<Renderer::MorphShape> many;
  for (int k = 1; k <= 12; ++k) many.push_back(morph_from(rest.positions, bumped(rest.positions, 0.003 * k * (k % 2 ? 1 : -1))));
  std::vector<float> weights(many.size(), 0.0f);
  weights[0] = 0.7f, weights[5] = 0.5f, weights[11] = 0.4f;
  int rows = 0, calls = 0;
  const Image at_once = render(
      [&](Renderer& r) {
        DrawableHandle h;
        Status s = r.upload_mesh(rest, h);
        if (s) s = r.set_morph_targets(h, many);
        return s ? r.set_morph_weights(h, weights.data(), weights.size()) : s;
      },
      cam);
  const Image banded = render(
      [&](Renderer& r) {
        DrawableHandle h;
        Status s = r.upload_mesh(rest, h);
        if (!s) return s;
        Renderer::MorphJobPtr job;
        Renderer::MorphData data;
        bool done = false;
        REQUIRE(r.begin_morph_targets(h, many, job));
        REQUIRE(r.step_morph_targets(*job, 12, done));
        REQUIRE(r.finish_morph_targets(*job, data, false));
        CHECK(data.texels.empty());
        rows = data.rows;
        done = false;
        while (s && !done) {
          s = r.upload_morph_band(h, *job, data, 1, done);
          ++calls;
          CHECK(r.morph_target_count(h) == 0);  // none until the upload is finished
        }
        if (s) s = r.finish_morph_upload(h, *job, data);
        if (s) CHECK(r.morph_target_count(h) == 12);
        return s ? r.set_morph_weights(h, weights.data(), weights.size()) : s;
      },
      cam);
  INFO(rows << " rows in " << calls << " calls");
  CHECK(rows > 1);
  CHECK(calls == rows);
  CHECK(compare(banded, at_once).max == 0);
}

TEST_CASE("morph targets: shapes past the first 32, and more than 32 weights at once", "[render][indexed][morph]") {
  // The shader finds a vertex's entry of shape s from a 128-bit mask (bit
  // counts over the words before s); with more than 32 non-zero weights it
  // walks every entry instead. Both against the CPU blend, flat shaded (the
  // positions alone decide the image).
  const TriMesh rest = seamed_ellipsoid(kRadii, 48, 64);
  const CameraMatrices cam =
      canonical_view(CanonicalView::Front, bounding_box(rest.positions), 1.0f).matrices(1.0f);
  const Renderer::MorphShape bump = morph_from(rest.positions, bumped(rest.positions, 0.03));
  const Renderer::MorphShape dent = morph_from(rest.positions, dented(rest.positions, 0.02));
  auto draw = [&](const std::vector<Renderer::MorphShape>& shapes, const std::vector<float>& weights, bool on_gpu) {
    return render(
        [&, on_gpu](Renderer& r) {
          DrawableHandle h;
          Status s = r.upload_mesh(rest, h);
          if (s) r.style(h)->flat_shading = true;
          if (s && on_gpu) {
            s = r.set_morph_targets(h, shapes);
            if (s) s = r.set_morph_weights(h, weights.data(), weights.size());
            return s;
          }
          std::vector<float> xyz = flat(rest.positions);
          for (size_t i = 0; i < shapes.size(); ++i)
            for (size_t k = 0; k < shapes[i].vertices.size(); ++k)
              for (int c = 0; c < 3; ++c) xyz[3 * shapes[i].vertices[k] + c] += weights[i] * shapes[i].offsets[3 * k + c];
          return s ? r.update_mesh_positions(h, xyz.data(), rest.positions.size()) : s;
        },
        cam);
  };
  // Bump at 5, dent at 70 (third mask word), empty shapes between.
  std::vector<Renderer::MorphShape> far(72);
  far[5] = bump;
  far[70] = dent;
  std::vector<float> far_w(72, 0.0f);
  far_w[5] = 0.7f;
  far_w[70] = 0.9f;
  const ImageDiff words = compare(draw(far, far_w, true), draw(far, far_w, false));
  // The bump cut into 40 slices of its vertices, all at weight 1 (mode 2),
  // and the dent at 0.5 after them.
  std::vector<Renderer::MorphShape> slices(41);
  for (size_t k = 0; k < bump.vertices.size(); ++k) {
    Renderer::MorphShape& piece = slices[k % 40];
    piece.vertices.push_back(bump.vertices[k]);
    piece.offsets.insert(piece.offsets.end(), &bump.offsets[3 * k], &bump.offsets[3 * k] + 3);
  }
  slices[40] = dent;
  std::vector<float> slice_w(41, 1.0f);
  slice_w[40] = 0.5f;
  const ImageDiff many = compare(draw(slices, slice_w, true), draw(slices, slice_w, false));
  const ImageDiff moved = compare(draw(slices, slice_w, true), draw(slices, std::vector<float>(41, 0.0f), false));
  INFO("shapes 5 and 70: max " << words.max << " (" << 100 * words.fraction << " %); 41 weights: max " << many.max << " ("
                               << 100 * many.fraction << " %), vs rest " << 100 * moved.fraction << " %");
  CHECK(words.fraction < 0.002);
  CHECK(many.fraction < 0.002);
  CHECK(moved.fraction > 0.05);
}

TEST_CASE("set_morph_targets refuses bad input and changes nothing", "[render][indexed][morph]") {
  const TriMesh rest = seamed_ellipsoid(kRadii, 12, 16);
  check_leaves_mesh_as_it_was(rest, [&](Renderer& r, DrawableHandle h) {
        const Renderer::MorphShape good = morph_from(rest.positions, bumped(rest.positions, 0.05, 0.2));
        REQUIRE(!good.vertices.empty());
        Renderer::MorphShape bad_index = good, short_offsets = good, nan = good, twice = good;
        bad_index.vertices[0] = static_cast<std::uint32_t>(rest.positions.size());
        short_offsets.offsets.pop_back();
        nan.offsets[1] = std::nanf("");
        twice.vertices.push_back(twice.vertices[0]);
        twice.offsets.insert(twice.offsets.end(), {0.0f, 0.0f, 0.0f});
        for (const Renderer::MorphShape& bad : {bad_index, short_offsets, nan, twice})
          CHECK(r.set_morph_targets(h, {good, bad}).code == ErrorCode::InvalidInput);
        CHECK(r.set_morph_targets(h, std::vector<Renderer::MorphShape>(Renderer::kMaxMorphTargets + 1, good)).code ==
              ErrorCode::TooLarge);
        CHECK(r.set_morph_targets(h + 7, {good}).code == ErrorCode::InvalidInput);
        CHECK(r.morph_target_count(h) == 0);
        const float w = 1.0f;
        CHECK(r.set_morph_weights(h, &w, 1).code == ErrorCode::InvalidInput);  // no targets
        // Attached, then a bad weight: refused, the weights stay zero.
        const Status s = r.set_morph_targets(h, {good});
        const float nan_w = std::nanf("");
        CHECK(r.set_morph_weights(h, &nan_w, 1).code == ErrorCode::InvalidInput);
        const float two[2] = {1.0f, 1.0f};
        CHECK(r.set_morph_weights(h, two, 2).code == ErrorCode::InvalidInput);
        return s;
      });
}
