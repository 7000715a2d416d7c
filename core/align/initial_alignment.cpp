// Silhouette-based initial alignment (jeong2002 Sec. 4.1); see the header.
#include "align/initial_alignment.h"

#include "align/face_alignment.h"
#include "align/face_refine.h"
#include "common/cloud_tree.h"
#include "common/helper_thread.h"
#include "common/rotation.h"
#include "mesh/geometry.h"
#include "numeric/powell.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>

namespace lk {

namespace {

constexpr int kMinPoints = 50;         // fewer cannot outline a head in 64^2 pixels
constexpr int kMinResolution = 16;
constexpr int kMaxResolution = 4096;
constexpr double kPi = 3.14159265358979323846;

// Value at fraction q of the sorted values (q in [0,1]), by selection.
double quantile(std::vector<double> values, double q) {
  if (values.empty()) return 0.0;
  const size_t k = static_cast<size_t>(std::clamp(q, 0.0, 1.0) * (values.size() - 1) + 0.5);
  std::nth_element(values.begin(), values.begin() + k, values.end());
  return values[k];
}

// The 9 parameters (translation in head heights, rotation vector in
// radians, log scale per axis of the faced generic head) around the
// initialization world = s * (g' - ref_g) + ref_c with g' = facing * g.
struct AffineModel {
  Mat3 facing = Mat3::Identity();  // generic frame -> world axes (look -> +z, up -> +y)
  double scale = 1.0;              // initial uniform scale s
  Vec3 pivot = Vec3::Zero();       // centre of rotation / scaling, faced generic coordinates
  Vec3 ref_generic = Vec3::Zero();
  Vec3 ref_world = Vec3::Zero();
  double head_height = 1.0;        // world units, the translation unit

  void transform_of(const double* q, Mat3& linear, Vec3& translation) const {
    const Vec3 rv(q[3], q[4], q[5]);
    const Mat3 rot = rotation_from_vector(rv);
    const Vec3 scales(scale * std::exp(q[6]), scale * std::exp(q[7]), scale * std::exp(q[8]));
    const Mat3 rs = rot * scales.asDiagonal();
    linear = rs * facing;
    translation = -rs * pivot + scale * (pivot - ref_generic) + ref_world +
                  head_height * Vec3(q[0], q[1], q[2]);
  }
};

Status validate_inputs(const TriMesh& generic, const PointCloud& cloud, const AlignOptions& o) {
  if (generic.triangles.empty() || generic.positions.empty())
    return Status::error(ErrorCode::Empty, "align: the generic head has no triangles");
  std::string why;
  if (!is_valid(generic, &why)) return Status::error(ErrorCode::InvalidInput, "align: generic head: " + why);
  if (cloud.positions.empty()) return Status::error(ErrorCode::Empty, "align: the point cloud has no points");
  for (size_t i = 0; i < cloud.positions.size(); ++i)
    if (!cloud.positions[i].allFinite())
      return Status::error(ErrorCode::InvalidInput,
                           "align: point " + std::to_string(i) + " of the cloud is not finite (NaN or inf)");
  if (cloud.size() < kMinPoints)
    return Status::error(ErrorCode::InvalidInput, "align: the point cloud has only " + std::to_string(cloud.size()) +
                         " points; at least " + std::to_string(kMinPoints) + " are needed to draw its silhouette");
  const BBox box = bounding_box(cloud.positions);
  const Vec3 size = box.size();
  if (!(size.minCoeff() > 1e-9 * std::max(1.0, box.max.cwiseAbs().maxCoeff())))
    return Status::error(ErrorCode::InvalidInput,
                         "align: the point cloud is flat or a single point (bounding box " +
                         std::to_string(size.x()) + " x " + std::to_string(size.y()) + " x " +
                         std::to_string(size.z()) + "); a head scan needs extent in x, y and z");
  std::vector<int> levels = o.coarse_resolutions;
  levels.push_back(o.resolution);
  for (int r : levels)
    if (r < kMinResolution || r > kMaxResolution)
      return Status::error(ErrorCode::InvalidInput, "align: resolution " + std::to_string(r) + " is outside [" +
                           std::to_string(kMinResolution) + ", " + std::to_string(kMaxResolution) + "]");
  if (!(o.window_margin >= 0.0 && o.window_margin < 10.0) || !(o.init_slab_fraction > 0.0 && o.init_slab_fraction <= 1.0) ||
      !(o.init_outlier_fraction >= 0.0 && o.init_outlier_fraction < 0.2) || !(o.step_translation > 0.0) ||
      !(o.step_rotation_deg > 0.0) || !(o.step_scale > 0.0) || !(o.tolerance > 0.0))
    return Status::error(ErrorCode::InvalidInput, "align: an option is out of range (margin, slab/outlier fraction, steps, tolerance)");
  return Status::success();
}

ClipPlane transform_plane(const ClipPlane& plane, const Mat3& linear, const Vec3& translation) {
  ClipPlane out;
  out.point = linear * plane.point + translation;
  // Normals transform with the inverse transpose.
  out.normal = (linear.inverse().transpose() * plane.normal).normalized();
  return out;
}

// Initialization: match the top of the head, the width of its upper part
// and its front (see the header for why not the bounding boxes).
Status initialize(const TriMesh& generic, const HeadAnnotations& ann, const PointCloud& cloud,
                  const AlignOptions& o, AffineModel& model, std::vector<ClipPlane>& generic_clips) {
  // Facing: the generic's look / up onto the world's +z / +y.
  Vec3 look = ann.look.normalized(), up = ann.up.normalized();
  if (!look.allFinite() || !up.allFinite() || std::fabs(look.dot(up)) > 0.5)
    return Status::error(ErrorCode::InvalidInput, "align: the generic head's look and up directions are unusable");
  up = (up - up.dot(look) * look).normalized();
  Mat3 generic_axes;
  generic_axes << up.cross(look), up, look;
  model.facing = generic_axes.transpose();  // rows: the generic's left, up, look

  generic_clips.clear();
  if (o.use_neck_clip) generic_clips.push_back(transform_plane(ann.neck_clip, model.facing, Vec3::Zero()));
  if (o.use_back_clip) generic_clips.push_back(transform_plane(ann.back_clip, model.facing, Vec3::Zero()));

  std::vector<Vec3> kept;
  for (const Vec3& p : generic.positions) {
    const Vec3 q = model.facing * p;
    bool keep = true;
    for (const ClipPlane& c : generic_clips) keep = keep && c.keeps(q);
    if (keep) kept.push_back(q);
  }
  if (kept.size() < 4)
    return Status::error(ErrorCode::NotAHead, "align: the generic head's clip planes remove all of its vertices");
  const BBox gbox = bounding_box(kept);
  const double top_g = gbox.max.y(), height_g = gbox.size().y();
  double xmin_g = 1e300, xmax_g = -1e300, front_g = -1e300;
  for (const Vec3& p : kept) {
    if (p.y() < top_g - o.init_slab_fraction * height_g) continue;
    xmin_g = std::min(xmin_g, p.x());
    xmax_g = std::max(xmax_g, p.x());
    front_g = std::max(front_g, p.z());
  }
  const double width_g = xmax_g - xmin_g;
  if (!(width_g > 0.0) || !(height_g > 0.0))
    return Status::error(ErrorCode::NotAHead, "align: the generic head has no width or height above its neck plane");
  BBox full_g;  // the whole generic head, faced
  for (const Vec3& p : generic.positions) full_g.extend(model.facing * p);

  // Cloud: robust extents, then a fixed point for the scale s that makes the
  // generic's upper-head slab as wide as the cloud's slab of height s * slab.
  const double q = o.init_outlier_fraction;
  std::vector<double> ys(cloud.positions.size());
  for (size_t i = 0; i < ys.size(); ++i) ys[i] = cloud.positions[i].y();
  const double top_c = quantile(ys, 1.0 - q);
  // Start from the smallest ratio of extents: extra body parts in the scan
  // (neck, shoulders) only make the cloud larger, so the smallest ratio is
  // the least inflated; missing parts make it too small, which the fixed
  // point below corrects (a thin slab under-measures the width, but each
  // step widens the slab).
  double s = 1e300;
  for (int axis = 0; axis < 3; ++axis) {
    std::vector<double> values(cloud.positions.size());
    for (size_t i = 0; i < values.size(); ++i) values[i] = cloud.positions[i][axis];
    const double extent_c = quantile(values, 1.0 - q) - quantile(values, q);
    s = std::min(s, extent_c / std::max(1e-300, full_g.size()[axis]));
  }
  double cx_c = 0.0, front_c = 0.0;
  std::vector<double> xs, zs;
  for (int iter = 0; iter < 30; ++iter) {
    xs.clear();
    zs.clear();
    const double bottom = top_c - o.init_slab_fraction * s * height_g;
    for (const Vec3& p : cloud.positions)
      if (p.y() >= bottom) {
        xs.push_back(p.x());
        zs.push_back(p.z());
      }
    if (xs.size() < 3) break;  // slab too thin to measure: keep s
    const double x0 = quantile(xs, q), x1 = quantile(xs, 1.0 - q);
    cx_c = 0.5 * (x0 + x1);
    front_c = quantile(zs, 1.0 - q);
    const double s_new = (x1 - x0) / width_g;
    if (!(s_new > 0.0)) break;
    const bool settled = std::fabs(s_new - s) < 1e-4 * s;
    s = s_new;
    if (settled) break;
  }
  if (xs.size() < 3 || !(s > 0.0) || !std::isfinite(s))
    return Status::error(ErrorCode::NotAHead, "align: could not measure the head's width in the point cloud");

  model.scale = s;
  model.pivot = gbox.center();
  model.ref_generic = Vec3(0.5 * (xmin_g + xmax_g), top_g, front_g);
  model.ref_world = Vec3(cx_c, top_c, front_c);
  model.head_height = s * height_g;
  return Status::success();
}

void views_xor(const std::array<SilhouetteMask, kSilhouetteViews>& a,
               const std::array<SilhouetteMask, kSilhouetteViews>& b, std::array<int, kSilhouetteViews>& out) {
  for (int v = 0; v < kSilhouetteViews; ++v) out[v] = xor_count(a[v], b[v]);
}

}  // namespace

int total_xor(const std::array<int, kSilhouetteViews>& per_view) {
  int sum = 0;
  for (int c : per_view) sum += c;
  return sum;
}

Status align_initial(const TriMesh& generic, const HeadAnnotations& ann, const PointCloud& cloud,
                     const AlignOptions& options, AlignResult& out, const ProgressFn& progress) {
  out = AlignResult{};
  Status st = validate_inputs(generic, cloud, options);
  if (!st) return st;

  AffineModel model;
  std::vector<ClipPlane> generic_clips;
  st = initialize(generic, ann, cloud, options, model, generic_clips);
  if (!st) return st;
  double q[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
  model.transform_of(q, out.initial_linear, out.initial_translation);

  // The clip planes are placed once from the initial T and then stay fixed
  // in the world while T changes (Sec. 4.1).
  AlignFrame& frame = out.frame;
  for (const ClipPlane& c : generic_clips) {
    // generic_clips are in faced coordinates: world = s (g' - ref_g) + ref_c.
    frame.clips.push_back(transform_plane(c, model.scale * Mat3::Identity(),
                                          model.ref_world - model.scale * model.ref_generic));
  }
  std::vector<Vec3> cloud_kept;
  cloud_kept.reserve(cloud.positions.size());
  for (const Vec3& p : cloud.positions) {
    bool keep = true;
    for (const ClipPlane& c : frame.clips) keep = keep && c.keeps(p);
    if (keep) cloud_kept.push_back(p);
  }
  if (static_cast<int>(cloud_kept.size()) < kMinPoints)
    return Status::error(ErrorCode::NotAHead, "align: only " + std::to_string(cloud_kept.size()) +
                         " scan points remain above the neck plane and in front of the back plane");

  // The world-fixed window: the kept cloud and the initially placed generic.
  BBox box = bounding_box(cloud_kept);
  std::vector<Vec3> placed(generic.positions.size());
  for (size_t i = 0; i < placed.size(); ++i) {
    placed[i] = out.initial_linear * generic.positions[i] + out.initial_translation;
    bool keep = true;
    for (const ClipPlane& c : frame.clips) keep = keep && c.keeps(placed[i]);
    if (keep) box.extend(placed[i]);
  }
  frame.window = make_view_window(box, options.window_margin, options.resolution);

  std::vector<int> resolutions;
  for (int r : options.coarse_resolutions)
    if (r < options.resolution) resolutions.push_back(r);
  resolutions.push_back(options.resolution);

  // Buffers reused by every evaluation of the objective.
  std::array<SilhouetteMask, kSilhouetteViews> cloud_masks, mesh_masks, other_masks;
  std::vector<Vec3> moved(generic.positions.size());
  MeshTopology topology;  // the smooth score's outline points follow its edges
  if (options.smooth_score) {
    const Status built = build_topology(generic, topology);
    if (!built) return with_context(built, "align: the smooth score needs the head's edges");
  }
  std::array<std::vector<Vec2>, kSilhouetteViews> outline_points;
  auto move_mesh = [&](const double* params) {
    Mat3 linear;
    Vec3 translation;
    model.transform_of(params, linear, translation);
    for (size_t i = 0; i < moved.size(); ++i) moved[i] = linear * generic.positions[i] + translation;
  };
  auto render_mesh = [&](const double* params, const ViewWindow& window) {
    move_mesh(params);
    rasterize_mesh_silhouettes(moved, generic.triangles, window, frame.clips, mesh_masks,
                               options.cull_back_faces);
  };

  Eigen::VectorXd x = Eigen::VectorXd::Zero(9);
  Eigen::VectorXd step(9);
  const double rot_step = options.step_rotation_deg * kPi / 180.0;
  step << options.step_translation, options.step_translation, options.step_translation,
      rot_step, rot_step, rot_step, options.step_scale, options.step_scale, options.step_scale;

  const int num_levels = static_cast<int>(resolutions.size());
  // One resolution level of Powell from x (updated), its record into level.
  auto run_level = [&](int li, double progress_from, double progress_span, Eigen::VectorXd& at,
                       AlignLevel& level) -> Status {
    ViewWindow window = frame.window;
    window.resolution = resolutions[li];
    level = AlignLevel{};
    level.resolution = window.resolution;
    rasterize_point_silhouettes(cloud_kept, window, frame.clips, options.splat, cloud_masks, &level.cloud);
    render_mesh(at.data(), window);
    views_xor(mesh_masks, cloud_masks, level.xor_before);

    // Each evaluation draws the two halves of the triangles on two threads,
    // into two sets of masks, and counts their union against the cloud's:
    // the same pixels, so the same D. (Powell's evaluations follow one
    // another, so they cannot be spread instead.)
    HelperThread helper;
    const int half_triangles = static_cast<int>(generic.triangles.size()) / 2;
    const std::function<void(int)> draw_half = [&](int k) {
      const TriangleRange range = k == 0 ? TriangleRange{0, half_triangles} : TriangleRange{half_triangles};
      rasterize_mesh_silhouettes(moved, generic.triangles, window, frame.clips, k == 0 ? mesh_masks : other_masks,
                                 options.cull_back_faces, range);
    };
    OutlineField fields[kSilhouetteViews];
    if (options.smooth_score) {
      const double cap = std::max(4.0, window.resolution / static_cast<double>(std::max(1, options.smooth_cap_divisor)));
      for (int v = 0; v < kSilhouetteViews; ++v) fields[v] = make_outline_field(cloud_masks[v], cap);
    }
    const ObjectiveFn objective = [&](const Eigen::VectorXd& p) -> double {
      if (options.smooth_score) {
        if (!helper.threaded()) {
          render_mesh(p.data(), window);
        } else {
          move_mesh(p.data());
          helper.run(draw_half);
          for (int v = 0; v < kSilhouetteViews; ++v)
            for (size_t w = 0; w < mesh_masks[v].bits.size(); ++w) mesh_masks[v].bits[w] |= other_masks[v].bits[w];
        }
        mesh_outline_points(moved, generic.triangles, topology.edges, window, frame.clips, mesh_masks, outline_points);
        double d = 0.0;
        for (int v = 0; v < kSilhouetteViews; ++v) d += outline_chamfer(fields[v], outline_points[v]);
        return d;
      }
      if (!helper.threaded()) {
        render_mesh(p.data(), window);
        double d = 0.0;
        for (int v = 0; v < kSilhouetteViews; ++v) d += xor_count(mesh_masks[v], cloud_masks[v]);
        return d;
      }
      move_mesh(p.data());
      helper.run(draw_half);
      double d = 0.0;
      for (int v = 0; v < kSilhouetteViews; ++v) d += union_xor_count(mesh_masks[v], other_masks[v], cloud_masks[v]);
      return d;
    };
    PowellOptions po;
    po.tolerance = options.tolerance;
    po.max_iterations = options.max_iterations;
    po.max_evaluations = options.max_evaluations;
    // Finer levels start closer to the answer: smaller initial steps.
    const double level_scale = std::pow(0.5, li);
    po.initial_step = step * level_scale;
    // D cannot change for moves well below a pixel: stop line searches at a
    // quarter pixel of translation, in units of the direction length.
    po.line_tolerance = 0.01;
    // The smooth score has a slope below a pixel: a twentieth of one.
    po.line_absolute_tolerance =
        (options.smooth_score ? 0.05 : 0.25) * window.pixel_size() / (model.head_height * options.step_translation * level_scale);
    PowellResult pr;
    const ProgressFn level_progress = [&](const char*, double f) {
      return report(progress, "align", progress_from + f * progress_span);
    };
    Status r = powell_minimize(objective, at, po, pr, level_progress);
    out.evaluations += pr.evaluations;
    out.iterations += pr.iterations;
    if (!r) return with_context(r, "align at " + std::to_string(window.resolution) + "^2");
    at = pr.x;
    render_mesh(at.data(), window);
    views_xor(mesh_masks, cloud_masks, level.xor_after);
    level.evaluations = pr.evaluations;
    level.iterations = pr.iterations;
    level.xor_per_iteration = pr.value_per_iteration;
    if (!report(progress, "align", progress_from + progress_span))
      return Status::error(ErrorCode::Cancelled, "align: cancelled");
    return Status::success();
  };
  // The polish (AlignOptions::polish) of the pose with parameters p: every
  // k-th kept scan point (by index, so the same points however the scan is
  // turned) onto the placed head, about the head's own axes (linear =
  // rotation * scales * facing).
  const bool polish = options.polish && options.polish_points >= 10;
  std::vector<Vec3> polish_samples;
  if (polish) {
    const size_t stride = std::max<size_t>(1, (cloud_kept.size() + options.polish_points - 1) / options.polish_points);
    for (size_t i = 0; i < cloud_kept.size(); i += stride) polish_samples.push_back(cloud_kept[i]);
  }
  const double polish_clamp = FaceAlignOptions{}.score_clamp_fraction * bounding_box(cloud_kept).diagonal();
  auto polish_of = [&](const Eigen::VectorXd& p, ScaledRotationFit& fit) -> bool {
    Mat3 linear;
    Vec3 translation;
    model.transform_of(p.data(), linear, translation);
    TriMesh head = generic;
    transform(head, linear, translation);
    FaceAlignOptions fo;
    fo.max_iterations = options.polish_iterations;
    return static_cast<bool>(fit_scaled_rotation_icp(head, polish_samples, rotation_from_vector(Vec3(p[3], p[4], p[5])),
                                                     fo, polish_clamp, fit, options.polish_loss));
  };
  // The face's distance (AlignOptions::choose_by_face) of a polished pose:
  // the upper face's samples placed by it, each to its nearest kept scan
  // point, clamped and averaged.
  const bool by_face = polish && options.choose_by_face && options.face_samples >= 10;
  std::vector<Vec3> face_samples;
  if (by_face) face_samples = upper_face_samples(generic, ann, options.face_samples);
  const double face_clamp = by_face ? options.face_clamp_fraction * bounding_box(cloud_kept).diagonal() : 0.0;
  CloudAdaptor kept_adaptor{cloud_kept};
  std::unique_ptr<CloudTree> kept_tree;
  if (by_face && !face_samples.empty())
    kept_tree = std::make_unique<CloudTree>(3, kept_adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(16));
  auto face_distance_of = [&](const Eigen::VectorXd& p, const ScaledRotationFit& fit) -> double {
    Mat3 linear;
    Vec3 translation;
    model.transform_of(p.data(), linear, translation);
    double sum = 0;
    for (const Vec3& g : face_samples) {
      const Vec3 w = fit.linear * (linear * g + translation) + fit.translation;
      size_t idx = 0;
      double d2 = 0;
      kept_tree->knnSearch(w.data(), 1, &idx, &d2);
      sum += std::min(std::sqrt(d2), face_clamp);
    }
    return sum / double(face_samples.size());
  };
  ScaledRotationFit best_fit;
  bool have_fit = false;

  // Every start (AlignOptions::pitch_starts_deg) through the coarse levels;
  // the one with the least D on the last of them goes on to the finest.
  // With choose_at_final every start runs through the final level too and
  // is polished, and the least polished score is kept (the coarse D was a
  // near-tie that a 0.05 deg turn of the scan decided).
  std::vector<double> starts = options.pitch_starts_deg;
  if (starts.empty()) starts.push_back(0.0);
  const int coarse = options.choose_at_final && starts.size() > 1 ? num_levels : num_levels - 1;
  const double span = 1.0 / (static_cast<double>(starts.size()) * std::max(coarse, 1) + 1.0);
  int best_d = -1;
  Eigen::VectorXd best_x = x;
  std::vector<AlignLevel> best_levels;
  for (size_t k = 0; k < starts.size(); ++k) {
    Eigen::VectorXd xs = Eigen::VectorXd::Zero(9);
    xs[3] = starts[k] * kPi / 180.0;
    std::vector<AlignLevel> levels;
    int d = -1;
    if (coarse == 0) {
      // One level: each start runs it, the least D is the answer.
      AlignLevel level;
      st = run_level(0, k * span, span, xs, level);
      if (!st) return st;
      d = total_xor(level.xor_after);
      levels.push_back(std::move(level));
    } else {
      for (int li = 0; li < coarse; ++li) {
        AlignLevel level;
        st = run_level(li, (k * coarse + li) * span, span, xs, level);
        if (!st) return st;
        d = total_xor(level.xor_after);
        levels.push_back(std::move(level));
      }
    }
    // Through the final level and polished: the polished score (smooth,
    // after the same refinement) chooses, not D.
    ScaledRotationFit fit;
    const bool fitted = polish && coarse == num_levels && polish_of(xs, fit);
    AlignResult::Start record;
    record.pitch_deg = starts[k];
    record.xor_final = d;
    if (fitted) record.polish_score = fit.score;
    if (fitted && kept_tree) record.face_distance = face_distance_of(xs, fit);
    const bool by_face_here = record.face_distance >= 0;
    const bool better = !fitted ? (best_d < 0 || d < best_d)
                                : !have_fit || (by_face_here ? record.face_distance < out.starts[out.chosen].face_distance
                                                             : fit.score < best_fit.score);
    if (fitted && better) best_fit = fit, have_fit = true;
    if (better) best_d = d, best_x = xs, best_levels = std::move(levels), out.chosen = static_cast<int>(k);
    out.starts.push_back(record);
  }
  x = best_x;
  out.levels = std::move(best_levels);
  if (coarse > 0 && coarse < num_levels) {
    AlignLevel level;
    st = run_level(coarse, 1.0 - span, span, x, level);
    if (!st) return st;
    out.levels.push_back(std::move(level));
  }

  // The final level's masks are still in cloud_masks: D before and after.
  const double zero[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
  render_mesh(zero, frame.window);
  views_xor(mesh_masks, cloud_masks, out.xor_before);
  out.xor_after = out.levels.back().xor_after;

  for (int i = 0; i < 9; ++i) out.parameters[i] = x[i];
  model.transform_of(x.data(), out.linear, out.translation);
  if (polish && !have_fit) have_fit = polish_of(x, best_fit);
  if (have_fit) {
    const ScaledRotationFit& fit = best_fit;
    out.polished = true;
    out.polish_scale = std::cbrt(fit.scales.prod());
    out.polish_turn_deg =
        std::acos(std::clamp(0.5 * (fit.rotation.trace() - 1), -1.0, 1.0)) * 180.0 / kPi;
    out.polish_rms = fit.rms;
    out.polish_iterations = fit.iterations;
    out.linear = fit.linear * out.linear;
    out.translation = fit.linear * out.translation + fit.translation;
    for (size_t i = 0; i < moved.size(); ++i) moved[i] = out.linear * generic.positions[i] + out.translation;
    rasterize_mesh_silhouettes(moved, generic.triangles, frame.window, frame.clips, mesh_masks,
                               options.cull_back_faces);
    views_xor(mesh_masks, cloud_masks, out.xor_polished);
  }
  out.aligned = generic;
  transform(out.aligned, out.linear, out.translation);
  return Status::success();
}

Status align_difference_images(const TriMesh& generic, const Mat3& linear, const Vec3& translation,
                               const PointCloud& cloud, const AlignFrame& frame,
                               const AlignOptions& options, std::array<Image, kSilhouetteViews>& out) {
  const int n = frame.window.resolution;
  if (n < kMinResolution || n > kMaxResolution)
    return Status::error(ErrorCode::InvalidInput, "align_difference_images: the frame has no valid window (run align_initial first)");
  std::string why;
  if (!is_valid(generic, &why)) return Status::error(ErrorCode::InvalidInput, "align_difference_images: " + why);
  std::array<SilhouetteMask, kSilhouetteViews> cloud_masks, mesh_masks;
  rasterize_point_silhouettes(cloud.positions, frame.window, frame.clips, options.splat, cloud_masks);
  std::vector<Vec3> moved(generic.positions.size());
  for (size_t i = 0; i < moved.size(); ++i) moved[i] = linear * generic.positions[i] + translation;
  rasterize_mesh_silhouettes(moved, generic.triangles, frame.window, frame.clips, mesh_masks,
                             options.cull_back_faces);
  for (int v = 0; v < kSilhouetteViews; ++v) {
    Image im = Image::make(n, n, 3, 0);
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        const bool a = mesh_masks[v].get(x, y), b = cloud_masks[v].get(x, y);
        const std::uint8_t value = (a != b) ? 255 : (a ? 64 : 0);
        std::uint8_t* px = im.at(x, y);
        px[0] = px[1] = px[2] = value;
      }
    out[v] = std::move(im);
  }
  return Status::success();
}

Image concat_views(const std::array<Image, kSilhouetteViews>& views) {
  constexpr int kGap = 2;
  int width = 0, height = 0;
  for (const Image& v : views) {
    width += v.width;
    height = std::max(height, v.height);
  }
  width += kGap * (kSilhouetteViews - 1);
  Image out = Image::make(std::max(width, 0), height, 3, 128);
  int x0 = 0;
  for (const Image& v : views) {
    for (int y = 0; y < v.height; ++y)
      for (int x = 0; x < v.width; ++x)
        for (int c = 0; c < 3; ++c) out.at(x0 + x, y)[c] = v.at(x, y)[std::min(c, v.channels - 1)];
    x0 += v.width + kGap;
  }
  return out;
}

}  // namespace lk
