#include "photos/photos_job.h"

#include "photos/eye_lids.h"
#include "photos/stereo_obs.h"
#include "mesh/geometry.h"
#include "head/head_creases.h"
#include "mesh/topology.h"

#include <algorithm>
#include <cmath>
#include <memory>

namespace lk {

Status run_photos_stereo(const GenericHead& generic, const std::vector<LandmarkPhoto>& photos,
                         const SelfCalibResult& calib, const std::vector<Image>& images, const StereoOptions& options,
                         StereoResult& stereo) {
  stereo = {};
  if (images.size() != photos.size() || calib.photos.size() != photos.size())
    return Status::error(ErrorCode::InvalidInput, "stereo: one image per photo needed");
  std::vector<StereoView> views;
  for (size_t i = 0; i < photos.size(); ++i) {
    if (!calib.photos[i].used || images[i].empty()) continue;
    StereoView v;
    v.image = &images[i];
    v.camera = calib.photos[i].camera;
    v.name = photos[i].name;
    for (size_t m = 0; m < photos[i].points.size(); ++m)
      if (photos[i].present[m]) v.region.push_back(photos[i].points[m]);
    views.push_back(v);
  }
  Status s = run_stereo(views, generic.mesh, options, stereo);
  // Report pairs by photo index, not by index among the views.
  std::vector<int> photo_of;
  for (size_t i = 0; i < photos.size(); ++i)
    if (calib.photos[i].used && !images[i].empty()) photo_of.push_back(int(i));
  for (StereoPairReport& p : stereo.pairs) {
    p.a = photo_of[size_t(p.a)];
    p.b = photo_of[size_t(p.b)];
  }
  return s;
}

namespace {

// The symmetry term (shape_fit.h) pairs the generic head's mirror vertices
// once; a head that is not mirror-symmetric is fitted without the term
// (false: the caller says so).
bool pair_mirror_vertices(const GenericHead& generic, ShapeFitOptions& fit) {
  if (!(fit.symmetry_weight > 0) || !fit.mirror_pairs.empty()) return true;
  fit.mirror_pairs = mirror_vertex_pairs(generic.mesh);
  if (!fit.mirror_pairs.empty()) return true;
  fit.symmetry_weight = 0;
  return false;
}

}  // namespace

Status make_photos_observations(const GenericHead& generic, const std::vector<SurfacePoint>& landmarks,
                                const std::vector<LandmarkPhoto>& photos, const SelfCalibResult& calib,
                                const PhotosJobOptions& options, const std::vector<PhotoOutline>* outlines,
                                const StereoResult* stereo, const LandmarkSlide* slide, PhotosObservations& out) {
  out = {};
  if (slide && !slide->has_slide() && !slide->has_sigma()) slide = nullptr;
  if (calib.photos.size() != photos.size())
    return Status::error(ErrorCode::InvalidInput, "shape fit: the calibration is for other photos");
  std::vector<SurfacePoint>& lid_points = out.lid_points;  // valid where a landmark is a lid contour point seen on the rim
  if (options.lids_on_rim && std::any_of(photos.begin(), photos.end(), [](const LandmarkPhoto& p) {
        return p.detector == kMediaPipeDetector;
      }))
    if (Status s = lid_margin_points(generic, landmarks, lid_points); !s) return with_context(s, "shape fit");
  std::vector<Camera> cameras;
  std::vector<FeatureObservation> obs;
  std::vector<ContourObservation> contour_obs;
  double sigma_weight_sum = 0;  // sum of (pixel_sigma / the slide's scatter)^2 over the observations
  for (size_t i = 0; i < photos.size(); ++i) {
    const PhotoCalibration& pc = calib.photos[i];
    if (!pc.used) continue;
    const int cam = int(cameras.size());
    cameras.push_back(pc.camera);
    const SlideView view = slide ? slide_view(*slide, pc.camera.center()) : SlideView{};
    std::vector<char> is_contour(photos[i].points.size(), 0);
    if (options.contour_landmarks && photos[i].detector == kMediaPipeDetector) {
      std::vector<ContourObservation> c = contour_observations(generic.mesh, landmarks, photos[i].points,
                                                               photos[i].present, pc.camera, cam, options.contours,
                                                               is_contour);
      contour_obs.insert(contour_obs.end(), c.begin(), c.end());
    }
    for (size_t m = 0; m < landmarks.size() && m < photos[i].points.size(); ++m) {
      if (is_contour[m]) continue;
      const bool on_rim = m < lid_points.size() && lid_points[m].valid();
      if (!photos[i].present[m] || !landmarks[m].valid()) continue;
      if (on_rim ? !camera_sees_lids(generic, lid_contour_eye(int(m)), pc.camera) : !(pc.weights[m] > 0)) continue;
      FeatureObservation o;
      o.camera = cam;
      o.landmark = int(m);
      o.point = on_rim ? lid_points[m] : landmarks[m];
      o.pixel = photos[i].points[m];
      // On the rim: the calibration's weight was earned at the map's point,
      // not there; the fit's own Huber reweighting still drops outliers.
      o.prior_weight = o.weight = on_rim ? 1.0 : pc.weights[m];
      if (slide && !on_rim) {
        // The cameras are fixed here: the shift is a constant offset per observation.
        o.point.offset += landmark_shift(*slide, int(m), view);
        if (slide->has_sigma() && options.calib.use_slide_sigma) {
          const double sp = slide_sigma_px(*slide, int(m), pc.camera, surface_position(generic.mesh, o.point),
                                           options.calib.min_sigma_px, options.calib.pixel_sigma);
          o.prior_weight = o.weight = pc.weights[m] * std::pow(options.calib.pixel_sigma / sp, 2);
          sigma_weight_sum += std::pow(options.calib.pixel_sigma / sp, 2);
        } else {
          sigma_weight_sum += 1;
        }
      } else {
        sigma_weight_sum += 1;
      }
      obs.push_back(o);
    }
  }
  // eq. 7 scales the features to an RMS gradient of lambda whatever their
  // weights; landmarks noisier than pixel_sigma (the slide's scatter)
  // should pull less against the stiffness: lambda times the RMS of
  // pixel_sigma / scatter (1 without a scatter).
  const double noise_factor = obs.empty() ? 1.0 : std::sqrt(sigma_weight_sum / double(obs.size()));
  std::vector<std::unique_ptr<ObservationSet>>& sets = out.sets;
  sets.push_back(std::make_unique<FeatureSet>(generic.mesh, cameras, std::move(obs), 2 * options.calib.pixel_sigma));
  std::vector<double>& lambdas = out.lambdas;
  lambdas = {options.fit.lambda_features * noise_factor};
  if (!contour_obs.empty()) {
    sets.push_back(std::make_unique<ContourSet>(generic.mesh, cameras, std::move(contour_obs), options.contours));
    lambdas.push_back(options.fit.lambda_features * noise_factor * options.contour_lambda_scale);
  }
  if (outlines) {
    if (outlines->size() != photos.size())
      return Status::error(ErrorCode::InvalidInput, "shape fit: one outline per photo needed");
    if (auto sil = make_silhouette_set(generic, generic.mesh, calib, *outlines, options.silhouettes)) {
      sets.push_back(std::move(sil));
      lambdas.push_back(options.lambda_silhouettes);
    }
  }
  if (options.stereo && stereo && !stereo->patches.empty()) {
    auto set = std::make_unique<StereoAttractorSet>(generic.mesh, stereo->patches, generic.mesh.positions);
    out.attractors = set.get();
    sets.push_back(std::move(set));
    lambdas.push_back(options.lambda_stereo);
  }
  out.fit = options.fit;
  pair_mirror_vertices(generic, out.fit);
  if (options.bind_lips) {
    const std::vector<std::array<int, 2>> lips = lip_binding_edges(generic);
    out.fit.binding_edges.insert(out.fit.binding_edges.end(), lips.begin(), lips.end());
  }
  return Status::success();
}

namespace {

// The scan fit's untangle (pipeline/untangle.h) on a photos head: the
// generic head is the reference (the fit stays in its frame), its
// bounding-box diagonal the erosion's scale, no vertex pinned.
Status untangle_photos_head(const GenericHead& generic, const UntangleOptions& options, TriMesh& control,
                            UntangleResult& result) {
  MeshTopology topology;
  Status s = build_topology(generic.mesh, topology);
  if (!s) return with_context(s, "untangle");
  const ButterflyCreases creases = head_creases(generic.mesh, topology, generic.annotations);
  const double diagonal = bounding_box(generic.mesh.positions).diagonal();
  return with_context(untangle_smooth_surface(generic.mesh.positions, creases, diagonal, topology, {}, options,
                                              control, result),
                      "untangle");
}

}  // namespace

Status fit_photos_shape(const GenericHead& generic, const std::vector<SurfacePoint>& landmarks,
                        const std::vector<LandmarkPhoto>& photos, const SelfCalibResult& calib,
                        const PhotosJobOptions& options, ShapeFitResult& fit,
                        const std::vector<PhotoOutline>* outlines, const StereoResult* stereo,
                        PhotosStereoFit* stereo_fit, const LandmarkSlide* slide, MouthBagResult* mouth_bag,
                        LidPoseResult* lids, UntangleResult* untangled) {
  PhotosObservations obs;
  if (Status s = make_photos_observations(generic, landmarks, photos, calib, options, outlines, stereo, slide, obs); !s)
    return s;
  const StereoAttractorSet* attractors = obs.attractors;
  const std::vector<SurfacePoint>& lid_points = obs.lid_points;
  const std::vector<double> start = attractors ? attractors->surface_distances(generic.mesh.positions)
                                               : std::vector<double>();
  Status s = fit_shape(generic.mesh, obs.sets, obs.lambdas, obs.fit, fit);
  if (s && options.keep_mouth_bag) {
    MouthBagResult bag;
    s = keep_mouth_bag_inside(generic, options.mouth_bag, fit.mesh, bag);
    if (mouth_bag) *mouth_bag = bag;
  }
  if (s && options.untangle.level > 0) {
    UntangleResult u;
    s = untangle_photos_head(generic, options.untangle, fit.mesh, u);
    if (untangled) *untangled = u;
  }
  if (s && options.fit_lids && !lid_points.empty()) {
    LidPoseResult pose;
    s = fit_lid_pose(generic, lid_points, photos, calib, fit.mesh, pose);
    if (lids) *lids = pose;
  }
  if (s && attractors && stereo_fit) {
    auto median_of = [](std::vector<double> v) {
      std::nth_element(v.begin(), v.begin() + long(v.size() / 2), v.end());
      return v[v.size() / 2];
    };
    std::vector<double> d = attractors->surface_distances(fit.mesh.positions);
    PhotosStereoFit& r = *stereo_fit;
    r = {};
    r.attractors = int(d.size());
    for (const StereoAttractor& a : attractors->attractors()) {
      r.inliers += a.weight >= std::exp(-3.0);
      r.weights.push_back(a.weight);
    }
    r.median_start_m = median_of(start);
    r.median_fit_m = median_of(d);
    std::sort(d.begin(), d.end());
    r.p95_fit_m = d[d.size() * 95 / 100];
    r.distances_fit_m = std::move(d);
  }
  return s;
}

std::unique_ptr<SilhouetteSet> make_silhouette_set(const GenericHead& generic, const TriMesh& start,
                                                   const SelfCalibResult& calib,
                                                   const std::vector<PhotoOutline>& outlines,
                                                   const SilhouetteOptions& options) {
  std::vector<Camera> cameras;
  std::vector<PhotoOutline> used;
  bool any = false;
  for (size_t i = 0; i < calib.photos.size() && i < outlines.size(); ++i) {
    if (!calib.photos[i].used) continue;
    cameras.push_back(calib.photos[i].camera);
    used.push_back(outlines[i]);
    any = any || !outlines[i].points.empty();
  }
  if (!any) return nullptr;
  std::vector<char> excluded(size_t(generic.mesh.num_vertices()), 0);
  for (const std::string& name : options.excluded_regions) {
    auto region = generic.annotations.regions.find(name);
    if (region == generic.annotations.regions.end()) continue;
    for (int v : region->second)
      if (v >= 0 && v < generic.mesh.num_vertices()) excluded[size_t(v)] = 1;
  }
  ChinLine chin;
  auto ch = generic.annotations.regions.find("chin");
  if (ch != generic.annotations.regions.end()) chin.vertices = ch->second;
  chin.up = generic.annotations.up;
  TriMesh m = generic.mesh;
  m.positions = start.positions;
  return std::make_unique<SilhouetteSet>(m, std::move(cameras), std::move(used), std::move(excluded), std::move(chin),
                                         options);
}

Status run_photos_job(const GenericHead& generic, const LandmarkMap& map, const std::vector<LandmarkPhoto>& photos,
                      const PhotosJobOptions& options, PhotosJobResult& result,
                      const std::vector<PhotoOutline>* outlines, const std::vector<Image>& images) {
  result = {};
  auto photo_name = [&](size_t i) {
    return photos[i].name.empty() ? "photo " + std::to_string(i + 1) : photos[i].name;
  };
  if (photos.empty()) return Status::error(ErrorCode::Empty, "photos: no photo given");
  if (photos.size() == 1)
    result.notes.push_back(photo_name(0) + " is the only photo: the head follows its landmarks across the image, "
                           "but its depth stays the generic head's (add photos from the sides)");
  for (size_t i = 0; i < photos.size(); ++i)
    if (photos[i].detector != map.detector)
      return Status::error(ErrorCode::InvalidInput, photo_name(i) + ": landmarks from detector '" + photos[i].detector +
                                                        "', the map is for '" + map.detector + "'");
  if (outlines) {
    if (outlines->size() != photos.size())
      return Status::error(ErrorCode::InvalidInput, "photos: " + std::to_string(outlines->size()) + " masks for " +
                                                        std::to_string(photos.size()) + " photos");
    for (size_t i = 0; i < photos.size(); ++i) {
      const PhotoOutline& o = (*outlines)[i];
      if (!o.points.empty() && (o.width != photos[i].width || o.height != photos[i].height))
        return Status::error(ErrorCode::InvalidInput, photo_name(i) + ": its mask is " + std::to_string(o.width) + "x" +
                                                          std::to_string(o.height) + ", the photo " +
                                                          std::to_string(photos[i].width) + "x" +
                                                          std::to_string(photos[i].height));
    }
  }
  std::vector<SurfacePoint> landmarks;
  Status s = attach_landmark_map(map, generic.mesh, options.map_max_distance_m, landmarks);
  if (!s) return s;

  const LandmarkSlide* slide = options.use_slide && (map.slide.has_slide() || map.slide.has_sigma()) ? &map.slide : nullptr;
  SelfCalibOptions calib = options.calib;
  if (slide && map.detector == kMediaPipeDetector) calib.slide_focal_ratio = options.mediapipe_focal_ratio;
  s = self_calibrate(photos, generic.mesh, landmarks, calib, result.calib, slide);
  for (size_t i = 0; i < result.calib.photos.size(); ++i)
    if (!result.calib.photos[i].refusal.empty())
      result.notes.push_back(photo_name(i) + " dropped: " + result.calib.photos[i].refusal);
  if (!s) return s;

  if (options.stereo && !images.empty()) {
    s = run_photos_stereo(generic, photos, result.calib, images, options.stereo_options, result.stereo);
    if (!s) return with_context(s, "photos");
    for (const StereoPairReport& p : result.stereo.pairs)
      if (!p.refusal.empty())
        result.notes.push_back("stereo " + photo_name(size_t(p.a)) + " + " + photo_name(size_t(p.b)) + ": " + p.refusal);
    if (result.stereo.pairs.empty())
      result.notes.push_back("stereo: no two used photos see the head from " +
                             std::to_string(int(options.stereo_options.min_angle_deg)) + "-" +
                             std::to_string(int(options.stereo_options.max_angle_deg)) +
                             " deg apart; landmarks only");
  }
  PhotosJobOptions fit_options = options;
  if (!pair_mirror_vertices(generic, fit_options.fit))
    result.notes.push_back("the generic head is not mirror-symmetric: the shape fit does without its symmetry term");
  s = fit_photos_shape(generic, landmarks, photos, result.calib, fit_options, result.fit, outlines, &result.stereo,
                       &result.stereo_fit, slide, &result.mouth_bag, &result.lids, &result.untangle);
  return with_context(s, "photos");
}

}  // namespace lk
