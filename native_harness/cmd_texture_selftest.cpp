// likeness texture-selftest: synthetic photos of a head with a known skin
// albedo -> calibration -> texture_head -> re-render of a held-out view,
// scored against the truth (see texture_selftest.h).
#include "command.h"
#include "photos_texture.h"
#include "texture_selftest.h"

#include "io/io.h"

#include <cstdio>
#include <iostream>
#include <sys/stat.h>

namespace lk::cli {
namespace {

const char* kName = "texture-selftest";

int usage_error(const std::string& message) {
  fail(kName, message);
  return 2;
}

int run_texture_selftest_command(const Args& args) {
  if (!only_known_options(kName, args,
                          {"seed", "out", "size", "photos", "photo-size", "levels", "light-spread", "noise",
                           "per-photo-focal", "diagnose", "supersample", "perturb-deg", "surface-error-mm",
                           "register", "label-regions"}))
    return 2;
  const std::string out = args.get("out");
  if (out.empty()) return usage_error("--out DIR is required");
  SelftestOptions opt;
  int seed = 1, photo_size = 0;
  if (!args.get_int("seed", 1, seed, 0) || !args.get_int("size", 1024, opt.texture_size, 64, 8192) ||
      !args.get_int("photos", 5, opt.photos, 1, 7) || !args.get_int("photo-size", 1200, photo_size, 96, 4096) ||
      !args.get_int("levels", 3, opt.subdivision_levels, 0, 4) || !args.get_int("supersample", 2, opt.supersample, 1, 4) ||
      !args.get_double("light-spread", 0.12, opt.light_spread, 0, 1) ||
      !args.get_double("noise", 0.5, opt.landmark_noise_px, 0) ||
      !args.get_double("perturb-deg", 0, opt.perturb_deg, 0, 10) ||
      !args.get_double("surface-error-mm", 0, opt.surface_error_mm, 0, 20))
    return 2;
  opt.seed = static_cast<std::uint32_t>(seed);
  opt.photo_width = opt.eval_width = photo_size;
  opt.photo_height = opt.eval_height = photo_size * 2 / 3;
  opt.shared_focal = !args.has("per-photo-focal");
  opt.diagnostics = args.has("diagnose");
  opt.register_photos = args.has("register");
  opt.label_regions = args.has("label-regions");
  // Fail before minutes of work when the results cannot be written.
  ::mkdir(out.c_str(), 0755);
  struct stat folder;
  if (::stat(out.c_str(), &folder) != 0 || !S_ISDIR(folder.st_mode)) return fail(kName, out + ": cannot create the folder");

  SelftestResult r;
  Status s = run_texture_selftest(opt, r, [](const std::string& line) { std::cout << line << "\n" << std::flush; });
  if (!s) return fail(kName, s.message);

  auto save = [&](const std::string& name, const Image& image) {
    if (image.empty()) return true;
    Status st = save_png_file(out + "/" + name, image);
    if (!st) fail(kName, st.message);
    return st.ok();
  };
  bool ok = save("truth.png", r.truth) && save("ours.png", r.ours) && save("nospline.png", r.nospline) &&
            save("skin.png", r.skin) && save("skin_nospline.png", r.skin_nospline) &&
            save("skin_truth.png", r.truth_skin) &&
            save("face_mask.png", r.face_mask) && save("error.png", r.error);
  for (size_t i = 0; ok && i < r.photos.size(); ++i) ok = save("photo_" + std::to_string(i) + ".png", r.photos[i]);
  if (!ok) return 1;
  s = write_file(out + "/report.json", selftest_report_json(opt, r));
  if (!s) return fail(kName, s.message);

  std::printf("\ntexture self-test, seed %u: %d photos %dx%d, texture %d^2, mesh %d triangles\n", opt.seed,
              opt.photos, opt.photo_width, opt.photo_height, opt.texture_size, r.triangles);
  std::printf("  held-out view, face region (%lld px), unlit albedo vs truth:\n", r.face_pixels);
  std::printf("    %-34s %9s %8s %11s %13s\n", "", "PSNR dB", "SSIM", "seam (err)", "seam (tex)");
  auto row = [](const char* name, const SelftestScores& sc) {
    std::printf("    %-34s %9.2f %8.4f %11.3f %13.3f\n", name, sc.psnr_db, sc.ssim, sc.seam, sc.seam_texture);
  };
  row("with multiresolution spline", r.with_spline);
  row("without spline", r.without_spline);
  if (opt.diagnostics) {
    row("neutral light, spline", r.neutral_light);
    row("neutral light, no spline", r.neutral_light_nospline);
    row("neutral light, true cameras, spline", r.neutral_light_true_cameras);
    row("neutral light, true cameras, no spline", r.neutral_light_true_cameras_nospline);
  }
  std::printf("  calibration (%s): focal err, rotation err, centre err, mean vertex reprojection err:\n",
              opt.shared_focal ? "one shared focal" : "per photo");
  for (size_t i = 0; i < r.calibration.size(); ++i) {
    const PhotoCalibration& c = r.calibration[i];
    std::printf("    photo %zu: %2d landmarks, rms %.2f px, f %.1f (true %.1f, %+.2f%%), %.3f deg, %.2f mm, %.2f px\n", i,
                c.landmarks, c.rms_px, c.focal, c.focal_true, 100 * c.focal_error, c.rotation_error_deg,
                c.centre_error_mm, c.vertex_error_px);
  }
  if (opt.perturb_deg > 0 || opt.surface_error_mm > 0)
    std::printf("  misregistered on purpose: photos 1.. turned %.2f deg, surface off by up to %.1f mm\n",
                opt.perturb_deg, opt.surface_error_mm);
  std::printf("  cameras used, mean vertex reprojection err vs the truth (px):");
  for (double e : r.vertex_error_used_px) std::printf(" %.2f", e);
  std::printf("\n");
  if (r.texture_report.registered) {
    const RegisterReport& g = r.texture_report.registration;
    std::printf("  registration (reference photo %d, %d vertices): luminance rms %.4f -> %.4f\n", g.reference,
                g.vertices, g.rms_before, g.rms_after);
    for (size_t i = 0; i < g.photos.size(); ++i)
      std::printf("    photo %zu: rms %.4f -> %.4f, turned %.3f deg, moved %.2f mm, field <= %.2f px, gain %.3f\n", i,
                  g.photos[i].rms_before, g.photos[i].rms_after, g.photos[i].rotation_deg, g.photos[i].translation_mm,
                  g.photos[i].field_max_px, g.photos[i].gain);
  }
  print_blend_figures(r.texture_report, "  ");
  std::printf("  timings (wall ms):");
  for (const auto& [name, ms] : r.timings_ms) std::printf(" %s %.0f;", name.c_str(), ms);
  std::printf("\nwrote %s/{truth,ours,nospline,error,skin,skin_nospline,skin_truth,face_mask,photo_*}.png and report.json\n",
              out.c_str());
  return 0;
}

Registrar reg({"texture-selftest",
               "likeness texture-selftest --out DIR [--seed N] [--size 1024] [--photos 5] [--photo-size 1200] "
               "[--levels 3] [--light-spread 0.12] [--noise 0.5] [--per-photo-focal] [--diagnose] [--supersample 2] "
               "[--perturb-deg D] [--surface-error-mm A] [--register] [--label-regions]",
               "ground-truth texturing check (tarini2002 Sec. 3.2): synthetic photos under different lights, "
               "calibration, texture_head with/without spline, held-out view scored by PSNR/SSIM/seam",
               run_texture_selftest_command});

}  // namespace
}  // namespace lk::cli
