// likeness uv: one-chart stretch-minimizing parameterization of a disk mesh
// (tarini2002 Sec. 3.1). Writes the mesh with per-vertex UVs and, with --png,
// the UV layout with every triangle coloured by its stretch.
#include "command.h"

#include "head/generic_head.h"
#include "io/io.h"
#include "uv/stretch_param.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>

namespace lk::cli {
namespace {

const char* kName = "uv";

int usage_error(const std::string& message) {
  fail(kName, message);
  return 2;
}

// Green (stretch 1) through yellow to red (stretch >= 3): Gamma per triangle.
Vec3 stretch_colour(double gamma) {
  const double s = std::clamp((gamma - 1.0) / 2.0, 0.0, 1.0);
  return s < 0.5 ? Vec3(2 * s, 0.8, 0.2) : Vec3(1.0, 0.8 * (2 - 2 * s), 0.2);
}

// A plain software rasterizer: filled triangles, then dark edges.
Image draw_layout(const TriMesh& mesh, const std::vector<Vec2>& uv, int size) {
  Image im = Image::make(size, size, 3, 255);
  const auto stretch = triangle_stretch(mesh, uv);
  auto px = [&](const Vec2& p) { return Vec2(p.x() * size, (1 - p.y()) * size); };  // v up
  for (int f = 0; f < mesh.num_triangles(); ++f) {
    const Tri& t = mesh.triangles[f];
    const Vec2 a = px(uv[t[0]]), b = px(uv[t[1]]), c = px(uv[t[2]]);
    const Vec3 col = stretch_colour(stretch[f].x());
    const int x0 = std::max(0, int(std::floor(std::min({a.x(), b.x(), c.x()}))));
    const int x1 = std::min(size - 1, int(std::ceil(std::max({a.x(), b.x(), c.x()}))));
    const int y0 = std::max(0, int(std::floor(std::min({a.y(), b.y(), c.y()}))));
    const int y1 = std::min(size - 1, int(std::ceil(std::max({a.y(), b.y(), c.y()}))));
    const double area = (b - a).x() * (c - a).y() - (c - a).x() * (b - a).y();
    if (area == 0) continue;
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        const Vec2 p(x + 0.5, y + 0.5);
        const double w0 = ((b - p).x() * (c - p).y() - (c - p).x() * (b - p).y()) / area;
        const double w1 = ((c - p).x() * (a - p).y() - (a - p).x() * (c - p).y()) / area;
        const double w2 = 1 - w0 - w1;
        if (w0 < 0 || w1 < 0 || w2 < 0) continue;
        for (int k = 0; k < 3; ++k) im.at(x, y)[k] = std::uint8_t(255 * col[k]);
      }
  }
  for (const Tri& t : mesh.triangles)
    for (int k = 0; k < 3; ++k) {
      const Vec2 a = px(uv[t[k]]), b = px(uv[t[(k + 1) % 3]]);
      const int steps = int(std::ceil((b - a).norm())) + 1;
      for (int s = 0; s <= steps; ++s) {
        const Vec2 p = a + (b - a) * (double(s) / steps);
        const int x = int(p.x()), y = int(p.y());
        if (x >= 0 && y >= 0 && x < size && y < size)
          for (int c = 0; c < 3; ++c) im.at(x, y)[c] = std::uint8_t(im.at(x, y)[c] * 0.35);
      }
    }
  return im;
}

int run_uv(const Args& args) {
  if (!only_known_options(kName, args, {"mesh", "out", "k", "png", "size", "unweighted"})) return 2;
  const std::string mesh_path = args.get("mesh"), out = args.get("out"), png = args.get("png");
  if (mesh_path.empty()) return usage_error("--mesh FILE (or --mesh generic) is required");
  if (out.empty() && png.empty()) return usage_error("--out FILE.obj and/or --png FILE is required");
  UvOptions opt;
  int size = 1024;
  if (!args.get_double("k", 1.2, opt.k, 0) || !args.get_int("size", 1024, size, 16, 8192)) return 2;
  opt.view_weighted = !args.has("unweighted");
  TriMesh mesh;
  if (mesh_path == "generic") {
    GenericHead head;
    const Status s = load_generic_head(head);
    if (!s.ok()) return fail(kName, s.message);
    mesh = head.mesh;
    opt.face_vertices = head.annotations.regions["face"];
  } else {
    const Status s = load_mesh_file(mesh_path, mesh);
    if (!s.ok()) return fail(kName, s.message);
  }
  std::vector<Vec2> uv;
  UvStats st;
  timespec t0{}, t1{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t0);
  const Status s = parameterize_stretch(mesh, opt, uv, st);
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t1);
  if (!s.ok()) return fail(kName, mesh_path + ": " + s.message);
  const double ms = 1e3 * double(t1.tv_sec - t0.tv_sec) + 1e-6 * double(t1.tv_nsec - t0.tv_nsec);
  std::printf("%s: %d vertices, %d triangles; %.0f ms CPU, %d iterations, %ld triangle evaluations\n",
              mesh_path.c_str(), mesh.num_vertices(), mesh.num_triangles(), ms, st.iterations, st.evaluations);
  std::printf("L2 stretch %.4f (initial map %.4f, unweighted %.4f), Linf %.4f, flipped %d\n", st.l2_stretch,
              st.initial_l2_stretch, st.l2_stretch_unweighted, st.linf_stretch, st.flipped);
  if (!opt.face_vertices.empty())
    std::printf("face: %.1f%% of the texture for %.1f%% of the surface\n", 100 * st.face_texture_share,
                100 * st.face_area_share);
  if (!out.empty()) {
    mesh.uvs = uv;
    mesh.uv_per_corner = false;
    const Status w = write_file(out, write_obj(mesh));
    if (!w.ok()) return fail(kName, w.message);
    std::printf("wrote %s\n", out.c_str());
  }
  if (!png.empty()) {
    const Status w = save_png_file(png, draw_layout(mesh, uv, size));
    if (!w.ok()) return fail(kName, w.message);
    std::printf("wrote %s (triangles coloured by stretch: green 1, yellow 2, red >= 3)\n", png.c_str());
  }
  return 0;
}

const Registrar reg({kName, "likeness uv --mesh FILE|generic [--out FILE.obj] [--k 1.2] [--unweighted] [--png FILE] [--size 1024]",
                     "one-chart stretch-minimizing UV map of a disk mesh (tarini2002 Sec. 3.1)", run_uv});

}  // namespace
}  // namespace lk::cli
