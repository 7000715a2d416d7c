// likeness bench --only draw: what one animation frame of a level-3-sized
// head costs the renderer natively (OSMesa llvmpipe, CPU): the unrolled
// layout (three GPU vertices per triangle, the old path) against the indexed
// one, back-face culling on and off, and the per-frame update sending the
// dirty range or the whole vertex array. The mesh is the generic head split
// 1-to-4 three times (the web's level 3 has the same counts: 85,729 vertices,
// 171,136 triangles); a frame moves the lower half of the head (a jaw-like
// rotation, ~half the vertices, as the web animation does). Canvas 870x858,
// the web viewer's size in the measurement page. Median of 9 frames (3 with
// --quick), after one warm-up frame.
#include "command.h"
#include "timing.h"

#include "head/generic_head.h"
#include "mesh/geometry.h"
#include "mesh/midpoint_split.h"
#include "render/camera.h"
#include "render/gl.h"
#include "render/offscreen.h"

#include <cmath>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

namespace lk::cli {
namespace {

// One 1-to-4 split: a new vertex at each edge midpoint.
TriMesh split4(const TriMesh& m) {
  std::vector<std::array<int, 2>> edges;
  TriMesh out;
  out.triangles = split_at_midpoints(m.triangles, m.num_vertices(), edges);
  out.positions = m.positions;
  for (const auto& e : edges) out.positions.push_back(0.5 * (m.positions[e[0]] + m.positions[e[1]]));
  return out;
}

// The pose at time `phase` in [0,1]: vertices below the mouth rotate about
// a hinge behind it (like the web's jaw), everything else stays.
std::vector<float> pose(const TriMesh& m, const BBox& box, double phase) {
  const Vec3 size = box.max - box.min;
  const double hinge_y = box.min.y() + 0.45 * size.y(), hinge_z = box.min.z() + 0.4 * size.z();
  const double angle = 0.14 * phase;  // radians, ~8 degrees
  std::vector<float> xyz(m.positions.size() * 3);
  for (size_t i = 0; i < m.positions.size(); ++i) {
    Vec3 p = m.positions[i];
    if (p.y() < hinge_y) {
      const double y = p.y() - hinge_y, z = p.z() - hinge_z;
      p.y() = hinge_y + std::cos(angle) * y - std::sin(angle) * z;
      p.z() = hinge_z + std::sin(angle) * y + std::cos(angle) * z;
    }
    for (int k = 0; k < 3; ++k) xyz[3 * i + k] = static_cast<float>(p[k]);
  }
  return xyz;
}

void row(const std::string& what, Timing t, bool ok, const std::string& extra = "") {
  std::printf("   %-62s %9.1f ms %9.1f ms  %s%s\n", what.c_str(), t.wall_ms, t.cpu_ms, extra.c_str(),
              ok ? "" : " (FAILED)");
}

int run_bench_draw(const Args& args) {
  const int reps = args.has("quick") ? 3 : 9;
  GenericHead head;
  if (Status s = load_generic_head(head); !s) {
    std::printf("   generic head unavailable: %s\n", s.message.c_str());
    return 1;
  }
  TriMesh level3 = split4(split4(split4(head.mesh)));
  const BBox box = bounding_box(level3.positions);
  const int width = 870, height = 858;
  OffscreenContext context;
  if (Status s = context.create(width, height); !s) {
    std::printf("   no OSMesa context: %s\n", s.message.c_str());
    return 1;
  }
  const CameraMatrices camera =
      canonical_view(CanonicalView::ThreeQuarter, level3.positions, float(width) / height).matrices(float(width) / height);
  Viewport viewport;
  viewport.width = width;
  viewport.height = height;
  std::printf("   mesh: %d vertices, %d triangles; canvas %dx%d; wall and process cpu (llvmpipe's threads included)\n",
              level3.num_vertices(), level3.num_triangles(), width, height);
  std::printf("   %-62s %12s %12s\n", "case", "wall", "cpu");
  int failures = 0;

  struct Case {
    const char* name;
    MeshLayout layout;
    bool cull, dirty_range;
  };
  const Case cases[] = {
      {"unrolled layout (the old draw path)", MeshLayout::Unrolled, false, true},
      {"indexed, every face", MeshLayout::Indexed, false, true},
      {"indexed, hidden back faces culled", MeshLayout::Indexed, true, true},
      {"indexed, culled, whole array sent per frame", MeshLayout::Indexed, true, false},
  };
  for (const Case& c : cases) {
    RendererOptions options;
    options.upload_dirty_range = c.dirty_range;
    Renderer renderer;
    DrawableHandle handle = kNoHandle;
    Status s = renderer.init(options);
    if (s) s = renderer.upload_mesh(level3, handle, c.layout);
    if (!s) {
      std::printf("   %s: %s\n", c.name, s.message.c_str());
      ++failures;
      continue;
    }
    renderer.style(handle)->cull_hidden_back_faces = c.cull;
    bool ok = renderer.draw(camera, viewport).ok();  // warm-up: shader compile, first upload
    glFinish();
    // Draw alone (the view changes, the mesh does not).
    bool draw_ok = false;
    const Timing draw = median_ms(reps, [&] {
      const bool fine = renderer.draw(camera, viewport).ok();
      glFinish();
      return fine;
    }, draw_ok);
    // An animation frame: new pose, update, draw.
    int frame = 0;
    MeshUpdateStats stats;
    bool anim_ok = false;
    std::vector<float> xyz;
    const Timing update = median_ms(reps, [&] {
      xyz = pose(level3, box, 0.5 + 0.5 * std::sin(++frame));
      return true;
    }, anim_ok);  // the pose itself, subtracted below
    const Timing animated = median_ms(reps, [&] {
      xyz = pose(level3, box, 0.5 + 0.5 * std::sin(++frame));
      bool fine = renderer.update_mesh_positions(handle, xyz.data(), level3.positions.size(), &stats).ok();
      fine = renderer.draw(camera, viewport).ok() && fine;
      glFinish();
      return fine;
    }, anim_ok);
    // The update alone (normals around moved vertices, staging, buffer call).
    bool update_ok = false;
    const Timing update_only = median_ms(reps, [&] {
      xyz = pose(level3, box, 0.5 + 0.5 * std::sin(++frame));
      return renderer.update_mesh_positions(handle, xyz.data(), level3.positions.size(), &stats).ok();
    }, update_ok);
    glFinish();
    ok = ok && draw_ok && anim_ok && update_ok;
    failures += !ok;
    row(std::string(c.name) + ": draw", draw, ok);
    row(std::string(c.name) + ": update alone",
        Timing{update_only.wall_ms - update.wall_ms, update_only.cpu_ms - update.cpu_ms}, ok);
    row(std::string(c.name) + ": update + draw", Timing{animated.wall_ms - update.wall_ms, animated.cpu_ms - update.cpu_ms},
        ok,
        std::to_string(stats.moved_vertices) + " moved, " + std::to_string(stats.uploaded_vertices) + " GPU vertices sent");
  }
  return failures ? 1 : 0;
}

BenchRegistrar reg({"draw", "one animation frame of a level-3-sized head: unrolled vs indexed, culling, dirty range (OSMesa)",
                    run_bench_draw});

}  // namespace
}  // namespace lk::cli
