// likeness bench --only photos-optimizers: fua1998 Fig. 6-7 on synthetic
// sessions. The same observations (landmarks, the truth's outlines as
// silhouettes, stereo attractors from rendered views) and the same schedule
// (stiffness stages, reweighting rounds) minimized by Levenberg-Marquardt,
// plain gradient descent and L-BFGS (photos/descent.h), for
// lambda_sil = lambda_feat in [0, 0.5] with lambda_stereo = 1. Printed: the
// median distance of the stereo points to the fitted surface (Fig. 7's
// measure), the truth to the fitted face (which the paper could not
// measure), the minimizer's iterations and CPU time; then Fig. 6(b-d)'s
// histograms of the stereo points' distances to the fitted surface, per
// seed and optimizer, one row per x.
#include "command.h"
#include "synthetic_session_images.h"
#include "timing.h"

#include "head/generic_head.h"
#include "photos/ground_truth.h"
#include "photos/photos_job.h"
#include "photos/synthetic_outlines.h"
#include "photos/synthetic_views.h"
#include "synth/synth_head.h"

#include <algorithm>
#include <array>
#include <cstdio>
#include <string>
#include <vector>

namespace lk::cli {
namespace {

// Fig. 6's bins: 0.1 mm wide up to 1 mm, then one bin for the rest.
constexpr int kBins = 11;
constexpr double kBinMm = 0.1;

struct Histogram {
  double share[kBins] = {};  // percent of the stereo points in each bin
};

Histogram histogram_mm(const std::vector<double>& distances_m) {
  Histogram h;
  if (distances_m.empty()) return h;
  for (double d : distances_m) h.share[std::min(kBins - 1, int(1000 * d / kBinMm))] += 1;
  for (double& v : h.share) v *= 100.0 / double(distances_m.size());
  return h;
}

void print_histogram_header() {
  std::printf("  %-4s %-8s %-4s |", "seed", "method", "x");
  for (int b = 0; b < kBins - 1; ++b) std::printf(" <%3.1f", (b + 1) * kBinMm);
  std::printf("  >=%.1f mm (%% of the stereo points)\n", (kBins - 1) * kBinMm);
}

void print_histogram_row(const char* seed, const char* method, double x, const Histogram& h) {
  std::printf("  %-4s %-8s %-4.1f |", seed, method, x);
  for (double v : h.share) std::printf(" %4.1f", v);
  std::printf("\n");
}

struct Optimizer {
  const char* name;
  ShapeFitOptions::Optimizer kind;
};

int run_bench_photos_optimizers(const Args& args) {
  int seeds = 3, cameras = 10, max_iterations = 300;
  if (!args.get_int("photos-seeds", 3, seeds, 1, 50) || !args.get_int("photos-cameras", 10, cameras, 2, 64) ||
      !args.get_int("photos-descent-iterations", 300, max_iterations, 1, 100000))
    return 1;
  GenericHead generic;
  if (!load_generic_head(generic)) return 1;
  LandmarkMap map;
  std::vector<SurfacePoint> landmarks;
  if (!placeholder_landmark_map(generic, 468, map) || !attach_landmark_map(map, generic.mesh, 1e-3, landmarks)) return 1;
  const std::vector<int>& face = generic.annotations.regions.at("face");
  const Optimizer optimizers[] = {{"LM", ShapeFitOptions::Optimizer::LevenbergMarquardt},
                                  {"gradient", ShapeFitOptions::Optimizer::GradientDescent},
                                  {"L-BFGS", ShapeFitOptions::Optimizer::QuasiNewton}};
  const double lambdas[] = {0.0, 0.1, 0.3, 0.5};
  std::printf("photos-optimizers (fua1998 Fig. 6-7): %d seeds, %d cameras, 2 px landmark noise, landmarks + the truth's "
              "outlines + stereo, lambda_stereo 1, lambda_sil = lambda_feat = x; gradient descent and L-BFGS up to %d "
              "iterations a round (LM: %d)%s\n",
              seeds, cameras, max_iterations, ShapeFitOptions{}.max_lm_iterations,
              args.has("photos-no-lips") ? "; the lips' binding edges and mouth bag off" : "");
  std::printf("  %-4s %-4s | %-32s | %-32s | %-32s\n", "seed", "x", "LM: stereo med / truth face mm", "gradient descent",
              "L-BFGS");
  // sums[o][l]: stereo median, truth face mean, iterations, cpu ms
  double sums[3][4][4] = {};
  std::vector<std::string> seed_names;
  std::vector<std::array<std::array<Histogram, 4>, 3>> histograms;  // [seed][optimizer][lambda]
  Histogram mean_histograms[3][4];
  int counted = 0;
  for (int seed = 1; seed <= seeds; ++seed) {
    GenericHead person;
    SyntheticViewsOptions vo;
    vo.num_cameras = cameras;
    SyntheticSession session;
    std::vector<Image> images;
    if (!synthesize_head(generic, std::uint32_t(seed), SynthHeadOptions{}, person) ||
        !make_synthetic_views(person, landmarks, std::uint32_t(seed), vo, session) ||
        !render_session_images(generic, person, std::uint32_t(seed), session.cameras, images))
      return 1;
    PhotosJobOptions opt;
    PhotosJobResult r;
    Status st = self_calibrate(session.photos, generic.mesh, landmarks, opt.calib, r.calib);
    if (st) st = run_photos_stereo(generic, session.photos, r.calib, images, opt.stereo_options, r.stereo);
    std::vector<PhotoOutline> outlines;
    if (st) st = synthetic_outlines(person.mesh, session.cameras, OutlineOptions{}, outlines, 0);
    if (!st) {
      std::printf("  %-4d failed: %s\n", seed, st.message.c_str());
      continue;
    }
    ++counted;
    seed_names.push_back(std::to_string(seed));
    histograms.emplace_back();
    for (int l = 0; l < 4; ++l) {
      std::printf("  %-4d %-4.1f", seed, lambdas[l]);
      for (int o = 0; o < 3; ++o) {
        PhotosJobOptions v = opt;
        v.fit.optimizer = optimizers[o].kind;
        v.fit.max_descent_iterations = max_iterations;
        v.fit.lambda_features = v.lambda_silhouettes = lambdas[l];
        if (args.has("photos-no-lips")) v.bind_lips = v.keep_mouth_bag = false;
        ShapeFitResult fit;
        PhotosStereoFit sf;
        const double t0 = cpu_clock_ms();
        st = fit_photos_shape(generic, landmarks, session.photos, r.calib, v, fit, &outlines, &r.stereo, &sf);
        const double ms = cpu_clock_ms() - t0;
        if (!st) {
          std::printf(" | %-32s", ("failed: " + st.message).substr(0, 32).c_str());
          continue;
        }
        int iterations = 0;
        for (const ShapeFitStage& s : fit.stages) iterations += s.lm_iterations;
        const Similarity sim = fit_similarity(fit.mesh.positions, person.mesh.positions, face);
        TriMesh aligned = fit.mesh;
        for (Vec3& p : aligned.positions) p = sim.apply(p);
        const DistanceStats tf = surface_distances(person.mesh, face, aligned);
        std::printf(" | %5.2f / %5.2f, %4d it %6.0f ms", 1000 * sf.median_fit_m, 1000 * tf.mean, iterations, ms);
        double* acc = sums[o][l];
        acc[0] += 1000 * sf.median_fit_m;
        acc[1] += 1000 * tf.mean;
        acc[2] += iterations;
        acc[3] += ms;
        const Histogram h = histogram_mm(sf.distances_fit_m);
        histograms.back()[o][l] = h;
        for (int b = 0; b < kBins; ++b) mean_histograms[o][l].share[b] += h.share[b];
      }
      std::printf("\n");
    }
  }
  if (!counted) return 1;
  std::printf("  mean over %d seeds (stereo points to the fit, median mm / truth to the fitted face, mean mm / "
              "iterations / CPU ms):\n",
              counted);
  for (int l = 0; l < 4; ++l) {
    std::printf("  x=%-4.1f", lambdas[l]);
    for (int o = 0; o < 3; ++o)
      std::printf(" | %-8s %5.2f / %5.2f / %5.0f / %6.0f", optimizers[o].name, sums[o][l][0] / counted,
                  sums[o][l][1] / counted, sums[o][l][2] / counted, sums[o][l][3] / counted);
    std::printf("\n");
  }
  std::printf("  Fig. 6(b-d): the stereo points' distances to the fitted surface, per seed (LM: the paper's (b), "
              "gradient descent ~ its Euler-Lagrange (c), L-BFGS ~ its MINOS (d))\n");
  print_histogram_header();
  for (std::size_t s = 0; s < seed_names.size(); ++s)
    for (int o = 0; o < 3; ++o)
      for (int l = 0; l < 4; ++l)
        print_histogram_row(seed_names[s].c_str(), optimizers[o].name, lambdas[l], histograms[s][o][l]);
  for (int o = 0; o < 3; ++o)
    for (int l = 0; l < 4; ++l) {
      Histogram m = mean_histograms[o][l];
      for (double& v : m.share) v /= counted;
      print_histogram_row("mean", optimizers[o].name, lambdas[l], m);
    }
  std::printf("  paper Fig. 7 (median stereo distance, real faces, lambda 0): LM 2.33 / 6.38 / 0.55 for its three "
              "people; Fig. 6(c,d): Euler-Lagrange and MINOS leave fewer points near zero than LM\n");
  return 0;
}

BenchRegistrar reg({"photos-optimizers",
                    "fua1998 Fig. 6-7: the photos shape fit by LM, gradient descent and L-BFGS for lambda_sil = "
                    "lambda_feat in [0, 0.5] (--photos-seeds N --photos-cameras C --photos-descent-iterations K --photos-no-lips)",
                    run_bench_photos_optimizers});

}  // namespace
}  // namespace lk::cli
