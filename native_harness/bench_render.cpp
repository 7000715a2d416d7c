// likeness bench --only render: what a render costs natively on llvmpipe
// (OSMesa, CPU): ambient-occlusion baking per mesh size, and one offscreen
// frame (context, shader compile, upload, draw, read back) per image size.
// Median of 3 runs (1 with --quick). No paper figures: a tool, not a stage.
#include "command.h"
#include "timing.h"

#include "head/generic_head.h"
#include "render/ambient_occlusion.h"
#include "render/camera.h"
#include "render/offscreen.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <functional>
#include <string>

namespace lk::cli {
namespace {



// A UV sphere with about n vertices: a stand-in for subdivided heads.
TriMesh sphere(int n) {
  const int rings = std::max(4, static_cast<int>(std::sqrt(n / 2.0)));
  const int segments = 2 * rings;
  TriMesh m;
  for (int i = 0; i <= rings; ++i)
    for (int j = 0; j < segments; ++j) {
      const double t = 3.14159265358979 * i / rings, p = 2 * 3.14159265358979 * j / segments;
      m.positions.emplace_back(0.1 * std::sin(t) * std::sin(p), 0.12 * std::cos(t), 0.1 * std::sin(t) * std::cos(p));
    }
  auto id = [&](int i, int j) { return i * segments + (j % segments); };
  for (int i = 0; i < rings; ++i)
    for (int j = 0; j < segments; ++j) {
      if (i > 0) m.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      if (i < rings - 1) m.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return m;
}

void row(const std::string& what, Timing t, bool ok, const std::string& extra = "") {
  std::printf("   %-60s %10.1f ms %10.1f ms  %s%s\n", what.c_str(), t.wall_ms, t.cpu_ms, extra.c_str(),
              ok ? "" : " (FAILED)");
}

int run_bench_render(const Args& args) {
  const int reps = args.has("quick") ? 1 : 3;
  GenericHead head;
  if (Status s = load_generic_head(head); !s) {
    std::printf("   generic head unavailable: %s\n", s.message.c_str());
    return 1;
  }
  std::printf("   %-60s %13s %13s\n", "case", "wall", "cpu");
  int failures = 0;

  struct Case {
    std::string name;
    TriMesh mesh;
  };
  std::vector<Case> cases = {{"generic head", head.mesh}, {"sphere", sphere(10000)}};
  if (!args.has("quick")) cases.push_back({"sphere", sphere(100000)});
  for (const Case& c : cases) {
    std::vector<float> ao;
    bool ok = false;
    const Timing t = median_ms(reps, [&] { return vertex_ambient_occlusion(c.mesh, OcclusionOptions{}, ao).ok(); }, ok);
    failures += !ok;
    row("AO bake, 48 rays: " + c.name + " " + std::to_string(c.mesh.num_vertices()) + " v", t, ok,
        std::to_string(static_cast<int>(c.mesh.num_vertices() / std::max(t.cpu_ms, 1e-3))) + " vertices per cpu ms");
  }

  for (const int size : {512, 1024}) {
    for (const Case& c : cases) {
      OffscreenOptions o;
      o.width = o.height = size;
      o.supersample = 2;
      Image im;
      bool ok = false;
      const Timing t = median_ms(reps, [&] {
        return render_offscreen(
                   [&](Renderer& r) {
                     DrawableHandle h;
                     Status s = r.upload_mesh(c.mesh, h);
                     if (s) r.style(h)->wireframe = true;
                     return s;
                   },
                   [&](float aspect) {
                     return canonical_view(CanonicalView::ThreeQuarter, c.mesh.positions, aspect).matrices(aspect);
                   },
                   o, im)
            .ok();
      }, ok);
      failures += !ok;
      row("frame " + std::to_string(size) + " px (2x supersampled): " + c.name + " " +
              std::to_string(c.mesh.num_triangles()) + " tri",
          t, ok);
    }
  }
  return failures ? 1 : 0;
}

BenchRegistrar reg({"render", "OSMesa frame time and ambient-occlusion baking (CPU, llvmpipe)", run_bench_render});

}  // namespace
}  // namespace lk::cli
