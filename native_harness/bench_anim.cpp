// likeness bench --only anim: the muscle layer (core/anim, issue 38) on
// synthetic person 1's head refined three levels with the eye and lip
// creases (the levels a fit makes; displacements are zero here, which costs
// the update the same arithmetic): posing the control mesh alone, a full
// expression change (smile <-> surprise: every moved control vertex moves)
// followed by the local update of level 2 and of level 3, a small change
// (one eye blinking) up to level 3, baking all 77
// shapes on level 2 and 3, and the level-2 GLB's size with all shapes
// (untextured; the browser flow `glb` measures a textured one). Medians of
// process CPU time (the machine is shared).
#include "command.h"
#include "timing.h"

#include "anim/bake.h"
#include "components/components.h"
#include "head/generic_head.h"
#include "head/head_creases.h"
#include "project/glb_export.h"
#include "project/pose.h"
#include "synth/synth_head.h"

#include <cstdio>

namespace lk::cli {
namespace {

int run_bench_anim(const Args& args) {
  const int reps = args.has("quick") ? 5 : 21;
  GenericHead generic;
  if (Status s = load_generic_head(generic); !s) {
    std::printf("   generic head unavailable: %s\n", s.message.c_str());
    return 1;
  }
  const GenericHead head = synthesize_head(generic, 1);
  FaceRig rig;
  MultiresMesh mr;
  Status s = make_face_rig(head.mesh, generic, rig);
  if (s) s = build_multires(head.mesh, head_creases(head.mesh, head.annotations), 3, mr);
  if (!s) {
    std::printf("   cannot build the head: %s\n", s.message.c_str());
    return 1;
  }
  FaceControls smile, surprise;
  face_shape("smile", smile);
  face_shape("surprise", surprise);
  std::printf("   head: synthetic person 1, %d control vertices (%zu moved by the rig), level 3: %zu vertices\n",
              head.mesh.num_vertices(), rig.moved.size(), mr.state.displaced[3].size());
  std::printf("   %-66s %10s\n", "case", "cpu (median)");
  int failures = 0;
  int flip = 0;
  const double pose_ms = median_cpu_ms(reps, [&] { (void)pose_face(rig, (++flip & 1) ? smile : surprise); });
  std::printf("   %-66s %7.3f ms\n", "pose the control mesh (pose_face)", pose_ms);
  const double rig_ms = median_cpu_ms(reps, [&] { FaceRig r; (void)make_face_rig(head.mesh, generic, r); });
  std::printf("   %-66s %7.3f ms\n", "make the rig (make_face_rig, with the teeth's placement)", rig_ms);
  const double place_ms = median_cpu_ms(reps, [&] { ComponentPlacement p; (void)place_components(head, generic, p); });
  std::printf("   %-66s %7.3f ms\n", "place the eyes and teeth (place_components)", place_ms);
  for (int level : {2, 3}) {
    MultiresMesh live = mr;
    UpdateFootprint fp;
    bool ok = true;
    const double ms = median_cpu_ms(reps, [&] { ok = pose_multires(live, rig, (++flip & 1) ? smile : surprise, level, &fp).ok() && ok; });
    failures += !ok;
    char what[128];
    std::snprintf(what, sizeof what, "full expression change + local update up to level %d", level);
    std::printf("   %-66s %7.3f ms  (%d of %zu level-%d vertices recomputed)%s\n", what, ms, fp.displaced_changed[level],
                live.state.displaced[level].size(), level, ok ? "" : " FAILED");
  }
  {
    // A small change: one eye blinking (its lids' support only).
    FaceControls blink;
    face_shape("eyeBlinkLeft", blink);
    MultiresMesh live = mr;
    UpdateFootprint fp;
    bool ok = true;
    const double ms = median_cpu_ms(reps, [&] { ok = pose_multires(live, rig, (++flip & 1) ? blink : FaceControls{}, 3, &fp).ok() && ok; });
    failures += !ok;
    std::printf("   %-66s %7.3f ms  (%d of %zu level-3 vertices recomputed)%s\n", "rest <-> eyeBlinkLeft + local update up to level 3", ms,
                fp.displaced_changed[3], live.state.displaced[3].size(), ok ? "" : " FAILED");
  }
  std::printf("   %-66s %7s     (jeong2002: 40-50 ms per update at level 2)\n", "", "");
  for (int level : {2, 3}) {
    MultiresMesh work = mr;
    std::vector<BakedShape> baked;
    bool ok = true;
    const double ms = median_cpu_ms(args.has("quick") ? 1 : 3, [&] { ok = bake_face_shapes(rig, &work, level, {}, baked).ok() && ok; });
    failures += !ok;
    char what[128];
    std::snprintf(what, sizeof what, "bake all %zu shapes on level %d", face_shape_names().size(), level);
    std::printf("   %-66s %7.1f ms%s  (goal: under 2 s)\n", what, ms, ok ? "" : " FAILED");
  }
  // The GLB of a project holding this head (levels 0-2, untextured).
  HeadProject p;
  p.fit.control = head.mesh;
  if (!build_multires(head.mesh, head_creases(head.mesh, head.annotations), 2, p.fit.multires).ok()) return 1;
  p.rig = make_animation_rig(head.mesh, generic.annotations);
  GlbExportOptions options;
  use_generic_part_textures(options);
  Bytes glb;
  GlbExportReport report;
  double export_ms = 0;
  {
    const double t0 = cpu_clock_ms();
    s = export_glb(p, generic, options, glb, &report);
    export_ms = cpu_clock_ms() - t0;
  }
  if (!s) {
    std::printf("   GLB export failed: %s\n", s.message.c_str());
    return 1;
  }
  std::printf("   %-66s %7.1f ms  %.2f MB, %d head vertices, %d morph targets on the head (goal: under 8 MB)\n",
              "GLB at level 2 with every shape (untextured skin, generic eye/teeth)", export_ms,
              double(glb.size()) / 1048576.0, report.head_vertices, report.head_targets);
  return failures ? 1 : 0;
}

BenchRegistrar reg({"anim", "the muscle layer: posing, local update to levels 2 and 3, baking the 77 shapes, GLB size",
                    run_bench_anim});

}  // namespace
}  // namespace lk::cli
