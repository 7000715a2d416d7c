// likeness bench --only uv: the one-chart stretch-minimizing parameterization
// (tarini2002 Sec. 3.1) on the generic head, timed, with L2/Linf stretch and
// the face's share of texture space; beside the initial mean-value map and,
// when CGAL was found at configure time, CGAL's LSCM and ARAP on the same
// mesh. Also a calibration timing line (tarini2002 Sec. 3).
#include "command.h"
#include "timing.h"

#include "calib/calibrate.h"
#include "head/generic_head.h"
#include "uv/stretch_param.h"

#ifdef LK_HAVE_CGAL
#include <CGAL/Polygon_mesh_processing/border.h>
#include <CGAL/Polygon_mesh_processing/measure.h>
#include <CGAL/Simple_cartesian.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Surface_mesh_parameterization/ARAP_parameterizer_3.h>
#include <CGAL/Surface_mesh_parameterization/LSCM_parameterizer_3.h>
#include <CGAL/Surface_mesh_parameterization/parameterize.h>
#endif

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <functional>

namespace lk::cli {
namespace {

void row(const char* name, double ms, const UvStats& st) {
  std::printf("  %-28s %9.1f %9.4f %9.4f %9.4f %8.1f%% %7d\n", name, ms, st.l2_stretch, st.l2_stretch_unweighted,
              st.linf_stretch, 100 * st.face_texture_share, st.flipped);
}

#ifdef LK_HAVE_CGAL
using Kernel = CGAL::Simple_cartesian<double>;
using SurfaceMesh = CGAL::Surface_mesh<Kernel::Point_3>;
namespace SMP = CGAL::Surface_mesh_parameterization;

// Runs one CGAL parameterizer; uv comes back per vertex in our order.
template <class Parameterizer>
bool cgal_param(const TriMesh& mesh, std::vector<Vec2>& uv) {
  SurfaceMesh sm;
  std::vector<SurfaceMesh::Vertex_index> vs;
  for (const auto& p : mesh.positions) vs.push_back(sm.add_vertex(Kernel::Point_3(p.x(), p.y(), p.z())));
  for (const Tri& t : mesh.triangles) sm.add_face(vs[t[0]], vs[t[1]], vs[t[2]]);
  const auto border = CGAL::Polygon_mesh_processing::longest_border(sm).first;
  auto uvmap = sm.add_property_map<SurfaceMesh::Vertex_index, Kernel::Point_2>("v:uv").first;
  if (SMP::parameterize(sm, Parameterizer(), border, uvmap) != SMP::OK) return false;
  uv.resize(mesh.positions.size());
  for (size_t i = 0; i < vs.size(); ++i) uv[i] = Vec2(uvmap[vs[i]].x(), uvmap[vs[i]].y());
  return true;
}
#endif

int run_bench_uv(const Args&) {
  GenericHead head;
  if (!load_generic_head(head).ok()) {
    std::printf("uv: the generic head could not be loaded\n");
    return 1;
  }
  const TriMesh& mesh = head.mesh;
  UvOptions opt;
  opt.face_vertices = head.annotations.regions["face"];
  std::printf("uv: one-chart parameterization of the generic head (%d vertices, %d triangles), k = %.2f\n",
              mesh.num_vertices(), mesh.num_triangles(), opt.k);
  std::printf("  paper (tarini2002 Sec. 3.1): 80 minutes for ~1,600 triangles (spring mesh, Sander's L2 norm)\n");
  std::printf("  %-28s %9s %9s %9s %9s %9s %7s\n", "method", "CPU ms", "L2(w)", "L2", "Linf", "face", "flipped");
  std::vector<Vec2> uv;
  UvStats st;
  double ms = median_cpu_ms(3, [&] { parameterize_tutte(mesh, opt, uv); });
  measure_stretch(mesh, uv, opt, st);
  row("mean-value (initial map)", ms, st);
  ms = median_cpu_ms(3, [&] { parameterize_stretch(mesh, opt, uv, st); });
  row("ours, k = 1.2", ms, st);
  UvOptions plain = opt;
  plain.view_weighted = false;
  ms = median_cpu_ms(3, [&] { parameterize_stretch(mesh, plain, uv, st); });
  measure_stretch(mesh, uv, opt, st);  // columns use the k = 1.2 weights
  row("ours, unweighted", ms, st);
#ifdef LK_HAVE_CGAL
  bool ok = true;
  ms = median_cpu_ms(3, [&] { ok = cgal_param<SMP::LSCM_parameterizer_3<SurfaceMesh>>(mesh, uv); });
  if (ok && measure_stretch(mesh, uv, opt, st).ok()) row("CGAL LSCM", ms, st);
  else std::printf("  CGAL LSCM failed on this mesh\n");
  ms = median_cpu_ms(1, [&] { ok = cgal_param<SMP::ARAP_parameterizer_3<SurfaceMesh>>(mesh, uv); });
  if (ok && measure_stretch(mesh, uv, opt, st).ok()) row("CGAL ARAP", ms, st);
  else std::printf("  CGAL ARAP failed on this mesh\n");
#else
  std::printf("  CGAL LSCM / ARAP: unavailable (CGAL was not found at configure time; apt-get install libcgal-dev)\n");
#endif
  std::printf("  L2(w): the paper's view-weighted L2; L2, Linf: Sander's unweighted norms; face: texture share\n"
              "  of the \"face\" region (%.1f%% of the 3-D area)\n", 100 * st.face_area_share);

  // Calibration: 15 exact correspondences, free focal (+ centre and k1).
  std::vector<Correspondence> cs;
  Camera cam;
  cam.fx = cam.fy = 3813.6;
  cam.cx = 900;
  cam.cy = 600;
  cam.k1 = -0.05;
  cam.R = Eigen::AngleAxisd(3.14159265358979 + 0.3, Vec3::UnitY()).toRotationMatrix();
  cam.t = Vec3(0, 0, 0.9);
  for (int i = 0; i < 15; ++i) {
    const int v = int((long(i) * 7919) % mesh.num_vertices());
    Correspondence c;
    c.point = mesh.positions[v];
    if (cam.project(c.point, c.pixel)) cs.push_back(c);
  }
  // One bad click, so RANSAC runs all its trials (exact points stop it early).
  if (cs.size() > 3) cs[3].pixel += Vec2(50, 0);
  CalibOptions copt;
  copt.fix_principal_point = false;
  copt.estimate_k1 = true;
  CalibResult res;
  Status s;
  ms = median_cpu_ms(5, [&] { s = calibrate_camera(cs, 1800, 1200, copt, res); });
  std::printf("calib: %zu correspondences (one off by 50 px), free focal/centre/k1, RANSAC %d trials: %.1f ms CPU,\n"
              "  inlier RMS %.2g px, %d inliers, focal %.1f px (true 3813.6) (%s)\n",
              cs.size(), copt.ransac_iterations, ms, res.rms, res.num_inliers, res.camera.fx,
              s.ok() ? "ok" : s.message.c_str());
  return 0;
}

const BenchRegistrar reg({"uv", "one-chart stretch parameterization vs CGAL LSCM/ARAP; calibration timing",
                          run_bench_uv});

}  // namespace
}  // namespace lk::cli
