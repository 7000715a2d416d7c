// likeness photos: landmark files of several photos -> cameras and the
// person's head (issue 37, fua1998; core/photos/photos_job.h).
// likeness synth-photos: a synthetic photo session with its truth, to try it.
#include "command.h"
#include "photos_fit_options.h"
#include "photos_pulls_report.h"

#include "head/generic_head.h"
#include "head/head_creases.h"
#include "head/skin_detail.h"
#include "head/surface_quality.h"
#include "image/image.h"
#include "io/exif.h"
#include "io/io.h"
#include "photos/added_folds.h"
#include "photos/landmark_learning.h"
#include "photos/photos_job.h"
#include "photos_texture.h"
#include "synthetic_session_images.h"
#include "photos/synthetic_outlines.h"
#include "photos/synthetic_views.h"
#include "project/eye_from_views.h"
#include "project/photos_project.h"
#include "project/project_file.h"
#include "synth/skin_field.h"
#include "synth/synth_head.h"
#include "texture/synthetic_photo.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <deque>
#include <cmath>
#include <cstdio>
#include <sys/stat.h>

namespace lk::cli {
namespace {

using Json = nlohmann::json;

Json camera_json(const Camera& c) {
  Json R = Json::array();
  for (int i = 0; i < 3; ++i) R.push_back({c.R(i, 0), c.R(i, 1), c.R(i, 2)});
  return {{"width", c.width}, {"height", c.height}, {"fx", c.fx}, {"fy", c.fy}, {"cx", c.cx}, {"cy", c.cy},
          {"R", R}, {"t", {c.t.x(), c.t.y(), c.t.z()}}};
}

bool make_dir(const std::string& dir) {
  ::mkdir(dir.c_str(), 0755);
  struct stat st;
  return ::stat(dir.c_str(), &st) == 0 && S_ISDIR(st.st_mode);
}

std::string base_name(const std::string& path) {
  const size_t k = path.find_last_of('/');
  return k == std::string::npos ? path : path.substr(k + 1);
}

// A check image of the silhouettes in one photo: the photo (or grey), each
// outline point red (no rim matched at the fit) or green (matched), the
// matched rim edges as the generic head projects them (yellow) and as the
// fitted head does (cyan).
void draw_segment(Image& im, Vec2 a, Vec2 b, const std::uint8_t* rgb) {
  const int n = int(std::ceil((b - a).norm())) + 1;
  for (int i = 0; i <= n; ++i) {
    const Vec2 p = a + (b - a) * (double(i) / n);
    const int x = int(std::floor(p.x())), y = int(std::floor(p.y()));
    if (x >= 0 && y >= 0 && x < im.width && y < im.height)
      for (int k = 0; k < 3; ++k) im.at(x, y)[k] = rgb[k];
  }
}

Status write_silhouette_check(const std::string& path, const std::string& photo_path, const PhotoOutline& outline,
                              const Camera& camera, int cam_index, const SilhouetteSet& at_generic,
                              const std::vector<Vec3>& generic_positions, const SilhouetteSet& at_fit,
                              const std::vector<Vec3>& fit_positions) {
  Image im;
  if (photo_path.empty() || !load_image_file(photo_path, im, 3)) im = Image::make(outline.width, outline.height, 3, 96);
  for (auto& v : im.pixels) v = std::uint8_t(v / 2);
  static const std::uint8_t red[3] = {255, 40, 40}, green[3] = {40, 255, 40}, yellow[3] = {255, 220, 0},
                            cyan[3] = {0, 220, 255};
  auto edges = [&](const SilhouetteSet& set, const std::vector<Vec3>& P, const std::uint8_t* rgb) {
    for (const auto& m : set.matches()) {
      if (m.camera != cam_index) continue;
      Vec2 a, b;
      if (camera.project(P[size_t(m.a)], a) && camera.project(P[size_t(m.b)], b)) draw_segment(im, a, b, rgb);
    }
  };
  edges(at_generic, generic_positions, yellow);
  edges(at_fit, fit_positions, cyan);
  std::vector<char> matched(outline.points.size(), 0);
  for (const auto& m : at_fit.matches())
    if (m.camera == cam_index) matched[size_t(m.point)] = 1;
  for (size_t k = 0; k < outline.points.size(); ++k) {
    const Vec2 p = outline.points[k].pixel;
    for (int dy = -2; dy <= 2; ++dy)
      for (int dx = -2; dx <= 2; ++dx) {
        const int x = int(p.x()) + dx, y = int(p.y()) + dy;
        if (x >= 0 && y >= 0 && x < im.width && y < im.height)
          for (int c = 0; c < 3; ++c) im.at(x, y)[c] = (matched[k] ? green : red)[c];
      }
  }
  // At most about 1000 px wide or high (box filter), so a check of a
  // 12-megapixel photo stays small.
  const int k = std::max(1, (std::max(im.width, im.height) + 999) / 1000);
  if (k > 1) {
    Image small = Image::make(im.width / k, im.height / k, 3);
    for (int y = 0; y < small.height; ++y)
      for (int x = 0; x < small.width; ++x)
        for (int c = 0; c < 3; ++c) {
          int sum = 0;
          for (int dy = 0; dy < k; ++dy)
            for (int dx = 0; dx < k; ++dx) sum += im.at(k * x + dx, k * y + dy)[c];
          small.at(x, y)[c] = std::uint8_t(sum / (k * k));
        }
    im = small;
  }
  return write_file(path, write_png(im));
}

// Mean of the finite values (NaN when none).
double finite_mean(const std::vector<double>& v) {
  double sum = 0;
  int n = 0;
  for (double x : v)
    if (std::isfinite(x)) sum += x, ++n;
  return n ? sum / n : std::nan("");
}

// The face outline against the rim, per used photo: mean signed mm (+ =
// the photo's outline outside the head's rim) on each side of the face, in
// three heights (loop positions 2-6 temple, 7-12 cheek, 13-17 jaw), and
// the jaw's width at the mouth corners' height (interpolated between the
// loop's points on each side): the photo's minus the head's.
void print_contour_report(const std::vector<LandmarkPhoto>& photos, const SelfCalibResult& calib,
                          const std::vector<ContourDistance>& at_generic, const std::vector<ContourDistance>& at_fit,
                          Json& rep) {
  std::printf("  face outline to the rim, mean mm (+ = the photo's outline outside the head), generic -> fit:\n");
  auto band = [](int k) {  // 0 temple, 1 cheek, 2 jaw, -1 other; side 0 / 1
    const int j = k <= 18 ? k : 36 - k;
    return j >= 2 && j <= 6 ? 0 : j >= 7 && j <= 12 ? 1 : j >= 13 && j <= 17 ? 2 : -1;
  };
  static const char* bands[3] = {"temple", "cheek", "jaw"};
  for (size_t i = 0; i < photos.size(); ++i) {
    if (!calib.photos[i].used) continue;
    std::string line;
    Json jp;
    for (int side = 0; side < 2; ++side)
      for (int b = 0; b < 3; ++b) {
        double m[2];
        for (int w = 0; w < 2; ++w) {
          std::vector<double> v;
          for (const ContourDistance& c : w ? at_fit : at_generic)
            if (c.photo == int(i) && band(c.loop_index) == b && (c.loop_index > 18) == (side == 1)) v.push_back(c.mm);
          m[w] = finite_mean(v);
        }
        char buf[96];
        std::snprintf(buf, sizeof buf, " %s %s %+.1f -> %+.1f", side ? "R" : "L", bands[b], m[0], m[1]);
        line += buf;
        jp[std::string(side ? "right_" : "left_") + bands[b] + "_mm"] = {m[0], m[1]};
      }
    // The jaw's width at the mouth corners' height (landmarks 61, 291).
    const LandmarkPhoto& ph = photos[i];
    if (ph.points.size() > 291 && ph.present[61] && ph.present[291]) {
      const double y = 0.5 * (ph.points[61].y() + ph.points[291].y());
      double x[2] = {0, 0}, d[2][2] = {{0, 0}, {0, 0}};  // per side: the photo's x; generic, fit px at y
      // Interpolated at height y along one side's points (all: the photo's
      // x; finite only: the distance to the rim); false outside their span.
      auto at_height = [&](const std::vector<ContourDistance>& list, int side, bool finite_only, bool want_px,
                           double& out) {
        std::vector<const ContourDistance*> seq;
        for (const ContourDistance& c : list)
          if (c.photo == int(i) && band(c.loop_index) >= 1 && (c.loop_index > 18) == (side == 1) &&
              (!finite_only || std::isfinite(c.px)))
            seq.push_back(&c);
        std::sort(seq.begin(), seq.end(), [](auto p, auto q) { return p->pixel.y() < q->pixel.y(); });
        for (size_t k = 0; k + 1 < seq.size(); ++k) {
          const ContourDistance &a = *seq[k], &b = *seq[k + 1];
          if (!(a.pixel.y() <= y && y <= b.pixel.y()) || b.pixel.y() - a.pixel.y() < 1e-9) continue;
          const double t = (y - a.pixel.y()) / (b.pixel.y() - a.pixel.y());
          out = want_px ? (1 - t) * a.px + t * b.px : a.pixel.x() + t * (b.pixel.x() - a.pixel.x());
          return true;
        }
        return false;
      };
      bool ok = true;
      for (int side = 0; side < 2 && ok; ++side)
        ok = at_height(at_generic, side, false, false, x[side]) && at_height(at_generic, side, true, true, d[side][0]) &&
             at_height(at_fit, side, true, true, d[side][1]);
      // The head's width: the photo's less what its outline lies outside the rim on both sides.
      double width[3] = {std::abs(x[1] - x[0]), 0, 0};
      width[1] = width[0] - d[0][0] - d[1][0];
      width[2] = width[0] - d[0][1] - d[1][1];
      if (ok) {
        const double mm_per_px = [&] {
          std::vector<double> v;
          for (const ContourDistance& c : at_fit)
            if (c.photo == int(i) && std::isfinite(c.px) && std::abs(c.px) > 1e-6) v.push_back(c.mm / c.px);
          return v.empty() ? std::nan("") : finite_mean(v);
        }();
        char buf[160];
        std::snprintf(buf, sizeof buf, "; jaw at the mouth %.0f px wide in the photo, generic %+.0f px (%+.1f mm), fit %+.0f px (%+.1f mm)",
                      width[0], width[1] - width[0], (width[1] - width[0]) * mm_per_px, width[2] - width[0],
                      (width[2] - width[0]) * mm_per_px);
        line += buf;
        jp["jaw_width_at_mouth_px"] = {width[0], width[1], width[2]};
      }
    }
    std::printf("    %s:%s\n", ph.name.c_str(), line.c_str());
    rep["face_outline"][ph.name] = jp;
  }
}

// The face outline's landmarks on the photo (or grey): each loop landmark
// green where it is a contour point with a rim at the fit (a line to the
// rim's crossing of its normal), orange without, the fit's rim (cyan).
Status write_contour_check(const std::string& path, const std::string& photo_path, const LandmarkPhoto& photo,
                           const Camera& camera, const TriMesh& generic, const std::vector<Vec3>& fit_positions,
                           int photo_index, const std::vector<ContourDistance>& at_fit) {
  Image im;
  if (photo_path.empty() || !load_image_file(photo_path, im, 3)) im = Image::make(photo.width, photo.height, 3, 96);
  for (auto& v : im.pixels) v = std::uint8_t(v / 2);
  static const std::uint8_t cyan[3] = {0, 220, 255}, green[3] = {40, 255, 40}, orange[3] = {255, 140, 0},
                            white[3] = {255, 255, 255};
  for (const RimEdge& e : find_rim_edges(fit_positions, generic.triangles, mesh_edge_list(generic.triangles), camera, false))
    draw_segment(im, e.pa, e.pb, cyan);
  const auto normals = outline_normals(photo.points, photo.present, mediapipe_face_oval());
  for (const ContourDistance& c : at_fit) {
    if (c.photo != photo_index) continue;
    const bool has = std::isfinite(c.px);
    if (has)
      for (const auto& [m, n] : normals)
        if (m == c.landmark) draw_segment(im, c.pixel, c.pixel - c.px * n, white);
    for (int dy = -3; dy <= 3; ++dy)
      for (int dx = -3; dx <= 3; ++dx) {
        const int x = int(c.pixel.x()) + dx, y = int(c.pixel.y()) + dy;
        if (x >= 0 && y >= 0 && x < im.width && y < im.height)
          for (int k = 0; k < 3; ++k) im.at(x, y)[k] = (has ? green : orange)[k];
      }
  }
  return write_file(path, write_png(im));
}

int run_photos(const Args& args) {
  const std::string cmd = "photos";
  if (!only_known_options(cmd, args, {"points", "photos", "masks", "masks-from-photos", "no-outlines", "silhouette-check", "map", "out",
                                      "levels", "focal-px", "texture-size", "no-texture", "register-texture", "label-texture", "stereo", "no-stereo", "coarse",
                                      "schedule", "follow", "folds", "depth-scale", "depth-0", "depth-yaw2", "contours",
                                      "contour-check", "contour-lambda", "focal-sigma", "no-slide", "lids", "iris-photo", "pulls", "pulls-by-photo", "pulls-by-landmark", "focal-jackknife", "symmetry", "no-skin-detail"}))
    return 2;
  const std::vector<std::string> points_paths = args.get_all("points"), photo_paths = args.get_all("photos"),
                                 mask_paths = args.get_all("masks");
  const std::string map_path = args.get("map"), out_dir = args.get("out");
  if (points_paths.empty() || out_dir.empty()) return fail(cmd, "needs --points P1.json P2.json ... and --out DIR");
  if (!photo_paths.empty() && photo_paths.size() != points_paths.size())
    return fail(cmd, std::to_string(photo_paths.size()) + " photos for " + std::to_string(points_paths.size()) +
                         " points files: give one points file per photo, in the same order");
  if (!mask_paths.empty() && mask_paths.size() != points_paths.size())
    return fail(cmd, std::to_string(mask_paths.size()) + " masks for " + std::to_string(points_paths.size()) +
                         " points files: give one mask per photo, in the same order");
  // With --photos and no --masks, each photo's outline is found on its
  // background where that is plain, as the page does (--no-outlines: none);
  // --masks-from-photos, the old name of that default, is still accepted.
  if (args.has("masks-from-photos") && (photo_paths.empty() || !mask_paths.empty()))
    return fail(cmd, "--masks-from-photos needs --photos (and no --masks): it finds each outline on a plain background");
  const bool plain_masks = !photo_paths.empty() && mask_paths.empty() && !args.has("no-outlines");
  const bool with_outlines = plain_masks || !mask_paths.empty();
  int levels = 3, texture_size = 2048;
  double focal_px = 0;
  double depth_scale = 0, depth_0 = 1, depth_yaw2 = 0;
  double contour_lambda = 0, focal_sigma = 0;
  if (!args.get_double("contour-lambda", PhotosJobOptions{}.contour_lambda_scale, contour_lambda, 0, 100) ||
      !args.get_double("focal-sigma", SelfCalibOptions{}.focal_prior_sigma, focal_sigma, 1e-4, 10))
    return 2;
  if (!args.get_int("levels", 3, levels, 0, 4) || !args.get_double("focal-px", 0, focal_px, 0, 1e6) ||
      !args.get_double("depth-scale", 0, depth_scale, 0, 10) || !args.get_double("depth-yaw2", 0, depth_yaw2, -10, 10) ||
      !args.get_double("depth-0", 1, depth_0, 0.1, 10) ||
      !args.get_int("texture-size", 2048, texture_size, 16, 4096))
    return 2;
  const auto t0 = std::chrono::steady_clock::now();

  GenericHead generic;
  Status s = load_generic_head(generic);
  if (!s) return fail(cmd, s.message);
  // The map: --map FILE (e.g. synth-photos' own), else the MediaPipe map
  // that ships with the head.
  std::string map_text;
  if (!map_path.empty()) {
    Bytes bytes;
    s = read_file(map_path, bytes, kMaxLandmarkFileBytes);
    if (!s) return fail(cmd, s.message);
    map_text.assign(bytes.begin(), bytes.end());
  } else {
    map_text = mediapipe_landmark_map_text();
  }
  LandmarkMap map;
  s = parse_landmark_map_json(map_text, map);
  if (!s) return fail(cmd, (map_path.empty() ? std::string("the embedded MediaPipe map") : map_path) + ": " + s.message);

  // Each photo's points; a file that cannot be used is named and left out.
  std::vector<LandmarkPhoto> photos;
  std::vector<std::string> image_paths;  // #photos: each kept photo's image ("" without --photos)
  std::vector<std::string> points_texts; // #photos: each kept photo's points file, as read
  std::vector<Image> images;             // #photos with --photos (for stereo), else empty
  // Stereo is asked for (--stereo): on Kira's real photos its patches dent
  // the face (docs/design/photos.md, Stereo); --no-stereo is kept as the default.
  const bool stereo = !photo_paths.empty() && args.has("stereo") && !args.has("no-stereo");
  std::vector<std::string> notes;
  std::vector<double> exif_focals;
  std::vector<PhotoOutline> outlines;  // #photos with --masks: each kept photo's outline (empty: its mask refused)
  for (size_t i = 0; i < points_paths.size(); ++i) {
    LandmarkPhoto ph;
    Bytes bytes;
    s = read_file(points_paths[i], bytes, kMaxLandmarkFileBytes);
    if (s) s = with_context(parse_landmarks_json(std::string(bytes.begin(), bytes.end()), ph), points_paths[i]);
    if (s && !photo_paths.empty()) {
      Bytes img;
      s = read_file(photo_paths[i], img, kMaxImageBytes);
      ImageInfo info;
      if (s) s = with_context(inspect_image(img.data(), img.size(), info), photo_paths[i]);
      if (s && (info.width != ph.width || info.height != ph.height))
        s = Status::error(ErrorCode::InvalidInput, photo_paths[i] + " is " + std::to_string(info.width) + "x" +
                                                       std::to_string(info.height) + ", its points file says " +
                                                       std::to_string(ph.width) + "x" + std::to_string(ph.height));
      Image decoded;
      if (s && stereo) s = with_context(read_image(img.data(), img.size(), decoded, 3), photo_paths[i]);
      if (s && stereo) images.push_back(std::move(decoded));
      ExifInfo exif;
      if (s && std::string(info.format) == "JPEG" && read_jpeg_exif(img.data(), img.size(), exif) && exif.present) {
        const double f = exif_focal_pixels(exif, ph.width, ph.height);
        if (f > 0) exif_focals.push_back(f);
      }
      ph.name = base_name(photo_paths[i]);
    }
    if (ph.name.empty()) ph.name = base_name(points_paths[i]);
    if (!s) {
      notes.push_back(s.message + " (left out)");
      continue;
    }
    if (with_outlines) {
      // A bad mask costs that photo its outline, not the photo.
      const std::string& source = plain_masks ? photo_paths[i] : mask_paths[i];
      Image image;
      PhotoOutline outline;
      Status ms = load_image_file(source, image, plain_masks ? 3 : 0);
      if (ms && plain_masks) {
        ms = outline_from_plain_photo(image, ph.width, ph.height, kPlainOutlineMaxSide, PlainBackgroundOptions{}, OutlineOptions{}, outline);
      } else if (ms) {
        ms = outline_from_mask_image(image, ph.width, ph.height, OutlineOptions{}, outline);
      }
      if (!ms) {
        // (load_image_file's messages already start with the path)
        notes.push_back((ms.message.rfind(source, 0) == 0 ? ms.message : source + ": " + ms.message) +
                        " (its outline not used)");
        outline = {};
      }
      outlines.push_back(outline);
    }
    photos.push_back(ph);
    image_paths.push_back(photo_paths.empty() ? "" : photo_paths[i]);
    points_texts.emplace_back(bytes.begin(), bytes.end());
  }
  // --iris-photo names none of the photos: said before the half-minute fit,
  // not after it (a photo given but left out by the fit is refused below).
  const std::string iris_photo = args.get("iris-photo");
  if (args.has("iris-photo")) {
    std::vector<std::string> names;
    for (const LandmarkPhoto& ph : photos) names.push_back(ph.name);
    if (photo_paths.empty() || args.has("no-texture") || levels == 0)
      return fail(cmd, "--iris-photo looks for the iris in one of the photos: it needs --photos and a textured head");
    if (iris_photo.empty()) return fail(cmd, "--iris-photo needs a photo's name (e.g. 0003 or 0003.jpg)");
    if (find_photo_name(names, iris_photo) < 0)
      return fail(cmd, "--iris-photo " + iris_photo + ": no photo of that name among the " +
                           std::to_string(names.size()) + " given (e.g. " + (names.empty() ? "" : names[0]) + ")");
  }
  PhotosJobOptions opt;
  opt.stereo = stereo;
  opt.lids_on_rim = args.has("lids");  // photos/eye_lids.h: off by default (docs/design/photos.md, "Lids that follow the photos")
  {
    std::string why;
    if (!parse_fit_levels(args.get("coarse"), args.get("schedule"), args.get("follow"), opt.fit, why)) return fail(cmd, why);
  }
  if (!args.get_double("symmetry", opt.fit.symmetry_weight, opt.fit.symmetry_weight, 0, 1e6))
    return fail(cmd, "--symmetry W: a weight >= 0");
  opt.calib.focal_prior_px = focal_px;
  opt.calib.focal_prior_sigma = focal_sigma;
  opt.calib.focal_from_jackknife = args.has("focal-jackknife");
  opt.contour_landmarks = args.has("contours");
  opt.use_slide = !args.has("no-slide");
  opt.contour_lambda_scale = contour_lambda;
  opt.calib.depth_scale_sigma = depth_scale;
  opt.calib.depth_scale_0 = depth_0;
  opt.calib.depth_scale_yaw2 = depth_yaw2;
  if (focal_px == 0 && !exif_focals.empty()) {
    std::sort(exif_focals.begin(), exif_focals.end());
    opt.calib.focal_prior_px = exif_focals[exif_focals.size() / 2];
    notes.push_back("focal prior from EXIF: " + std::to_string(int(std::lround(opt.calib.focal_prior_px))) + " px");
  }
  PhotosJobResult r;
  s = run_photos_job(generic, map, photos, opt, r, with_outlines ? &outlines : nullptr, images);
  for (const std::string& n : r.notes) notes.push_back(n);
  for (const std::string& n : notes) std::printf("  note: %s\n", n.c_str());
  if (!s) return fail(cmd, s.message);
  if (!make_dir(out_dir)) return fail(cmd, "cannot create the output folder '" + out_dir + "'");

  // The control mesh and its Butterfly levels (no scan: the generic head's
  // skin detail as their displacements, unless --no-skin-detail), as the
  // head project holds them (`likeness export --head DIR`, `likeness
  // project`, the page's Open project).
  s = write_file(out_dir + "/control.obj", write_obj(r.fit.mesh));
  HeadProject project;
  std::vector<std::vector<double>> skin_detail;
  const bool with_detail = levels > 0 && !args.has("no-skin-detail");
  if (s && with_detail) s = generic_skin_detail(generic, levels, SkinDetailOptions{}, skin_detail);
  if (s && levels > 0) s = project_from_photos(generic, r, levels, project, with_detail ? &skin_detail : nullptr);
  for (int l = 1; s && l <= levels; ++l) {
    TriMesh m = project.fit.level_meshes[size_t(l - 1)];
    m.normals.clear();  // positions and triangles, as before the project was kept
    s = write_file(out_dir + "/level" + std::to_string(l) + ".obj", write_obj(m));
  }
  if (!s) return fail(cmd, s.message);

  // The skin from the recovered cameras, when the photos are given.
  const bool textured = !photo_paths.empty() && levels > 0 && !args.has("no-texture");
  if (textured) {
    std::vector<std::string> used_paths, used_names;
    std::vector<Camera> cameras;
    for (size_t i = 0; i < photos.size(); ++i)
      if (r.calib.photos[i].used) {
        used_paths.push_back(image_paths[i]);
        used_names.push_back(photos[i].name);
        cameras.push_back(r.calib.photos[i].camera);
      }
    std::vector<Image> decoded;
    s = write_photos_texture(r.fit.mesh, project.fit.multires.levels, project.fit.level_meshes.back().positions,
                             used_paths, used_names, cameras, texture_size, out_dir, &project.texture.uvs,
                             &project.texture.skin, &decoded, args.has("register-texture"),
                             args.has("label-texture"));
    if (!s) return fail(cmd, s.message);
    // The iris from the same photos (the generic one when none is found).
    std::vector<const Image*> image_ptrs;
    for (const Image& im : decoded) image_ptrs.push_back(&im);
    EyeFromViewsResult eye;
    // --iris-photo: the iris looked for in that photo only (the page's photo
    // set to "Eye (iris)"); else the most frontal eye of all.
    EyeFromViewsOptions eye_options;
    if (!iris_photo.empty()) {
      eye_options.only_photo = find_photo_name(used_names, iris_photo);
      if (eye_options.only_photo < 0)
        return fail(cmd, "--iris-photo " + iris_photo + ": not one of the photos the head was made from");
    }
    const Status eye_status = find_project_iris(project, generic, image_ptrs, cameras, used_names, eye, eye_options);
    if (eye_status) {
      s = save_png_file(out_dir + "/eye.png", eye.texture);
      if (!s) return fail(cmd, s.message);
      std::printf("  eyes: the iris from %s's %s eye (%.0f deg from the front, iris radius %.0f px, %.1f deg on the eyeball): eye.png\n",
                  used_names[size_t(eye.photo)].c_str(), eye.eye == 0 ? "left" : "right", eye.view_angle_deg,
                  eye.circle.radius, eye.iris_angle_deg);
    } else {
      std::printf("  eyes: %s\n", eye_status.message.c_str());
    }
  }
  if (levels > 0) {
    // The project keeps the photos' files and points files as given, so
    // `likeness project info --extract-photos` and the page's Open project
    // get them back (project file version 3).
    for (size_t i = 0; i < photos.size() && !photo_paths.empty(); ++i) {
      ProjectPhoto kept{photos[i].name, "face", {}, points_texts[i]};
      s = read_file(image_paths[i], kept.bytes, kMaxImageBytes);
      if (!s) return fail(cmd, s.message);
      project.inputs.photos.push_back(std::move(kept));
    }
    Bytes bytes;
    s = save_project(project, bytes);
    if (s) s = write_file(out_dir + "/head.likeness.glb", bytes);
    if (!s) return fail(cmd, s.message);
  }

  Json cams = {{"format", "likeness-cameras"}, {"version", 1}, {"focal_px", r.calib.focal}, {"photos", Json::array()}};
  for (size_t i = 0; i < photos.size(); ++i) {
    const PhotoCalibration& pc = r.calib.photos[i];
    Json p = {{"name", photos[i].name}, {"used", pc.used}};
    if (pc.used) {
      p["camera"] = camera_json(pc.camera);
      p["rms_px"] = pc.rms_px;
      p["median_px"] = pc.median_px;
      double yaw, pitch;
      view_angles(pc.camera, yaw, pitch);
      p["yaw_deg"] = yaw;
      p["pitch_deg"] = pitch;
      p["landmarks_turned_away"] = pc.num_hidden;
    } else {
      p["refusal"] = pc.refusal;
    }
    cams["photos"].push_back(p);
  }
  // The stereo patches as points (normals; green = kept by the fit's last
  // reweighting, within ~3 median distances, red = dropped), to look at.
  if (stereo && !r.stereo.patches.empty()) {
    PointCloud pc;
    for (size_t i = 0; i < r.stereo.patches.size(); ++i) {
      pc.positions.push_back(r.stereo.patches[i].centre);
      pc.normals.push_back(r.stereo.patches[i].normal);
      const bool kept = i < r.stereo_fit.weights.size() && r.stereo_fit.weights[i] >= std::exp(-3.0);
      pc.colors.push_back(kept ? Vec3(0.1, 0.8, 0.2) : Vec3(0.9, 0.1, 0.1));
    }
    s = write_file(out_dir + "/stereo_patches.ply", write_ply(pc));
    if (!s) return fail(cmd, s.message);
  }
  s = write_file(out_dir + "/cameras.json", cams.dump(2) + "\n");
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  Json rep = {{"photos_used", r.calib.num_used()}, {"photos_given", points_paths.size()},
              {"focal_px", r.calib.focal},
              {"focal_landmarks_px", {r.calib.focal_landmarks_raw, r.calib.focal_landmarks, r.calib.focal_landmarks_sigma}},
              {"focal_prior_px", {r.calib.focal_prior, r.calib.focal_prior_sigma}},
              {"calibration_rms_px", {r.calib.initial_rms_px, r.calib.final_rms_px}},
              {"shape_fit_rms_px", {r.fit.initial_rms_px, r.fit.final_rms_px}}, {"notes", notes},
              {"seconds", seconds}, {"stages", Json::array()}};
  for (const ShapeFitStage& st : r.fit.stages)
    rep["stages"].push_back({{"nodes", st.nodes}, {"stiffness", st.stiffness}, {"cost", {st.initial_cost, st.final_cost}},
                             {"lm_iterations", st.lm_iterations}});
  if (with_outlines) {
    // The rim against the masks' outlines, at the generic head and at the fit.
    const auto sil = make_silhouette_set(generic, generic.mesh, r.calib, outlines, opt.silhouettes);
    if (sil) {
      const SilhouetteStats a = sil->stats(generic.mesh.positions), b = sil->stats(r.fit.mesh.positions);
      rep["silhouettes"] = {{"outline_points", a.points}, {"matched", {a.matched, b.matched}},
                            {"rim_to_outline_mean_px", {a.mean_px, b.mean_px}},
                            {"rim_to_outline_p95_px", {a.p95_px, b.p95_px}}};
      std::printf("  silhouettes: %d outline points; rim to outline %.2f px (%d matched, generic head) -> %.2f px (%d, fit)\n",
                  a.points, a.mean_px, a.matched, b.mean_px, b.matched);
      if (args.has("silhouette-check")) {
        const auto at_fit = make_silhouette_set(generic, r.fit.mesh, r.calib, outlines, opt.silhouettes);
        int cam = 0;
        for (size_t i = 0; s && i < photos.size(); ++i) {
          if (!r.calib.photos[i].used) continue;
          if (!outlines[i].points.empty())
            s = write_silhouette_check(out_dir + "/silhouettes_" + std::to_string(i + 1) + ".png", image_paths[i],
                                       outlines[i], r.calib.photos[i].camera, cam, *sil, generic.mesh.positions,
                                       *at_fit, r.fit.mesh.positions);
          ++cam;
        }
      }
    }
  }
  // The face outline's landmarks against the head's rim in each photo
  // (contour_obs.h), generic head and fit: per side and height, and the
  // jaw's width at the mouth corners' height.
  {
    std::vector<SurfacePoint> lms;
    if (attach_landmark_map(map, generic.mesh, opt.map_max_distance_m, lms)) {
      const auto at_generic = contour_distances(generic.mesh, lms, photos, r.calib, generic.mesh.positions, opt.contours);
      const auto at_fit = contour_distances(generic.mesh, lms, photos, r.calib, r.fit.mesh.positions, opt.contours);
      print_contour_report(photos, r.calib, at_generic, at_fit, rep);
      if (args.has("contour-check"))
        for (size_t i = 0; s && i < photos.size(); ++i)
          if (r.calib.photos[i].used)
            s = write_contour_check(out_dir + "/contours_" + std::to_string(i + 1) + ".png",
                                    image_paths.empty() ? std::string() : image_paths[i], photos[i],
                                    r.calib.photos[i].camera, generic.mesh, r.fit.mesh.positions, int(i), at_fit);
    }
  }
  // --pulls: which observation groups move the cheeks and the jaw outward
  // (photos/fit_pulls.h): the first step's split, the fitted displacement's
  // split, the forces at the end.
  if (args.has("pulls") || args.has("pulls-by-photo") || args.has("pulls-by-landmark")) {
    std::vector<SurfacePoint> lms;
    PhotosFitPulls pulls;
    const LandmarkSlide* slide = opt.use_slide && (map.slide.has_slide() || map.slide.has_sigma()) ? &map.slide : nullptr;
    Status ps = attach_landmark_map(map, generic.mesh, opt.map_max_distance_m, lms);
    if (ps)
      ps = measure_photos_fit_pulls(generic, lms, photos, r.calib, opt, r.fit.mesh.positions, pulls,
                                    with_outlines ? &outlines : nullptr, &r.stereo, slide,
                                    args.has("pulls-by-photo")      ? PullGrouping::Photos
                                    : args.has("pulls-by-landmark") ? PullGrouping::EachLandmark
                                                                    : PullGrouping::Landmarks);
    if (ps) {
      std::printf("%s", fit_pulls_table(pulls, "  ", args.has("pulls-by-landmark") ? 15 : 0).c_str());
      rep["fit_pulls"] = fit_pulls_json(pulls);
    } else {
      std::printf("  pulls: %s\n", ps.message.c_str());
    }
  }
  // --folds: how much the fit grew the smooth level 3's dihedral angles over
  // the generic head's, per region (photos/added_folds.h), and the
  // self-crossing pairs of levels 0..3, the generic head's beside the fit's
  // (1-2 s of CPU, so asked for).
  if (args.has("folds")) {
    std::vector<AddedFolds> added;
    if (measure_added_folds(generic, r.fit.mesh.positions, 3, 15.0, added)) {
      std::string line;
      for (const AddedFolds& g : added) {
        rep["folds"]["added"][g.region] = {{"p95_deg", g.p95_deg}, {"max_deg", g.max_deg}, {"edges_over_15_deg", g.creased},
                                           {"level3_crossings", {g.generic_crossings, g.crossings}}};
        char buf[128];
        std::snprintf(buf, sizeof buf, " %s %.1f / %.1f / %d (crossings %d -> %d)", g.region.c_str(), g.p95_deg,
                      g.max_deg, g.creased, g.generic_crossings, g.crossings);
        line += buf;
      }
      int crossings[2] = {0, 0};
      const ButterflyCreases creases = head_creases(generic.mesh, generic.annotations);
      for (int which = 0; which < 2; ++which) {
        GenericHead h = generic;
        if (which) h.mesh.positions = r.fit.mesh.positions;
        HeadSurfaceQuality q;
        if (measure_head_surface(h, creases, 3, q))
          for (int c : q.crossing_pairs) crossings[which] += c;
      }
      rep["folds"]["crossing_pairs"] = {crossings[0], crossings[1]};
      std::printf("  folds the fit added to level 3, p95 / max deg / edges grown > 15 deg:%s; crossing pairs %d "
                  "(generic head) -> %d (fit)\n",
                  line.c_str(), crossings[0], crossings[1]);
    }
  }
  Json pairs = Json::array();
  for (const StereoPairReport& p : r.stereo.pairs) {
    Json jp = {{"photos", {photos[size_t(p.a)].name, photos[size_t(p.b)].name}}, {"angle_deg", p.angle_deg},
               {"rectified", {p.width, p.height}}, {"pixels_searched", p.disparity.searched},
               {"disparities", p.disparity.valid}, {"low_texture", p.disparity.low_texture},
               {"low_score", p.disparity.low_score}, {"at_range_end", p.disparity.at_range_end},
               {"left_right_rejected", p.disparity.lr_rejected}, {"disparity_range", {p.d_min, p.d_max}},
               {"patches", p.patches}};
    if (!p.refusal.empty()) jp["refusal"] = p.refusal;
    pairs.push_back(jp);
  }
  rep["stereo"] = {{"used", stereo}, {"pairs", pairs}, {"patches", r.stereo.patches.size()},
                   {"inliers", r.stereo_fit.inliers},
                   {"median_patch_to_surface_mm", {1000 * r.stereo_fit.median_start_m, 1000 * r.stereo_fit.median_fit_m}},
                   {"p95_patch_to_fit_mm", 1000 * r.stereo_fit.p95_fit_m}};
  if (s) s = write_file(out_dir + "/report.json", rep.dump(2) + "\n");
  if (!s) return fail(cmd, s.message);
  std::printf("likeness photos: %d of %zu photos used, focal %.1f px\n", r.calib.num_used(), points_paths.size(),
              r.calib.focal);
  if (r.calib.focal_landmarks > 0)
    std::printf("  focal: the landmarks' %.0f px, over the detector's ratio %.0f +- %.0f px (spread over the photos), "
                "with the prior %.0f +- %.0f px (%s)\n",
                r.calib.focal_landmarks_raw, r.calib.focal_landmarks, r.calib.focal_landmarks_sigma, r.calib.focal_prior,
                r.calib.focal_prior_sigma, opt.calib.focal_prior_px > 0 ? "given or EXIF" : "a phone's 26 mm, no EXIF");
  std::printf("  landmark error: calibration %.2f -> %.2f px, shape fit %.2f -> %.2f px (%.2f s)\n",
              r.calib.initial_rms_px, r.calib.final_rms_px, r.fit.initial_rms_px, r.fit.final_rms_px, seconds);
  if (r.mouth_bag.pairs_before > 0)
    std::printf("  mouth bag (photos/lips.h): %d crossing pairs over it as fitted (levels %d..%d) -> %d, its corners drawn "
                "%.1f %% of the way to its centroid\n",
                r.mouth_bag.pairs_before, opt.mouth_bag.all_levels ? 0 : opt.mouth_bag.level, opt.mouth_bag.level,
                r.mouth_bag.pairs_after, 100 * r.mouth_bag.share);
  if (r.untangle.pairs_before > 0)
    std::printf("  untangle (pipeline/untangle.h, level %d against the generic head): %d new crossing pairs -> %d, "
                "%d control vertices restored\n",
                opt.untangle.level, r.untangle.pairs_before, r.untangle.pairs_after, r.untangle.restored_vertices);
  if (r.lids.observations > 0)
    std::printf("  lids (photos/eye_lids.h) turned to %d lid columns: upper %+.2f %+.2f, lower %+.2f %+.2f (left, right; "
                "+ closes), their gaps' error %.2f -> %.2f px\n",
                r.lids.observations, r.lids.upper[0], r.lids.upper[1], r.lids.lower[0], r.lids.lower[1],
                r.lids.rms_before_px, r.lids.rms_after_px);
  if (stereo) {
    int pairs_used = 0;
    for (const StereoPairReport& p : r.stereo.pairs) pairs_used += p.patches > 0;
    std::printf("  stereo: %d of %zu pairs, %zu patches (%d inliers); patch to surface median %.2f mm (generic) -> "
                "%.2f mm (fit), p95 %.2f mm\n",
                pairs_used, r.stereo.pairs.size(), r.stereo.patches.size(), r.stereo_fit.inliers,
                1000 * r.stereo_fit.median_start_m, 1000 * r.stereo_fit.median_fit_m, 1000 * r.stereo_fit.p95_fit_m);
  }
  for (size_t i = 0; i < photos.size(); ++i) {
    const PhotoCalibration& pc = r.calib.photos[i];
    if (!pc.used) {
      std::printf("  %s: not used\n", photos[i].name.c_str());
      continue;
    }
    double yaw, pitch;
    view_angles(pc.camera, yaw, pitch);
    std::printf("  %s: seen from yaw %+.0f deg (+ = the head's left), pitch %+.0f deg (+ = above); "
                "%d landmarks, %d turned away; median error %.1f px; depth scale %.3f\n",
                photos[i].name.c_str(), yaw, pitch, pc.num_landmarks - pc.num_hidden, pc.num_hidden, pc.median_px,
                pc.depth_scale);
  }
  const std::string level_files = levels > 0 ? ", level1..level" + std::to_string(levels) + ".obj" : "";
  std::printf("  wrote %s/control.obj%s, cameras.json, report.json%s%s%s\n", out_dir.c_str(), level_files.c_str(),
              textured ? ", textured.obj, textured.mtl, skin.png" : "",
              stereo && !r.stereo.patches.empty() ? ", stereo_patches.ply" : "",
              levels > 0 ? ", head.likeness.glb (the head project: likeness export --head DIR)" : "");
  return 0;
}

int run_synth_photos(const Args& args) {
  const std::string cmd = "synth-photos";
  if (!only_known_options(cmd, args, {"seed", "out", "cameras", "noise-px", "no-render"})) return 2;
  int seed = 1;
  SyntheticViewsOptions vo;
  if (!args.get_int("seed", 1, seed, 0, INT_MAX) || !args.get_int("cameras", 10, vo.num_cameras, 1, 64) ||
      !args.get_double("noise-px", 2.0, vo.noise_px, 0, 100))
    return 2;
  const std::string out_dir = args.get("out");
  if (out_dir.empty()) return fail(cmd, "needs --out DIR");
  if (!make_dir(out_dir)) return fail(cmd, "cannot create the output folder '" + out_dir + "'");
  GenericHead generic, person;
  Status s = load_generic_head(generic);
  if (s) s = synthesize_head(generic, std::uint32_t(seed), SynthHeadOptions{}, person);
  LandmarkMap map;
  if (s) s = placeholder_landmark_map(generic, 468, map);
  std::vector<SurfacePoint> landmarks;
  if (s) s = attach_landmark_map(map, generic.mesh, 1e-3, landmarks);
  SyntheticSession session;
  if (s) s = make_synthetic_views(person, landmarks, std::uint32_t(seed), vo, session);
  if (s) s = write_file(out_dir + "/map.json", landmark_map_to_json(map));
  if (s) s = write_file(out_dir + "/person.obj", write_obj(person.mesh));
  SkinField skin;
  SyntheticEyes eyes;
  if (s && !args.has("no-render")) s = make_skin_field(person, std::uint32_t(seed), {}, skin);
  if (s && !args.has("no-render")) s = make_synthetic_eyes(person, generic, std::uint32_t(seed), {}, eyes);
  Json truth = {{"seed", seed}, {"focal_px", vo.focal_px}, {"cameras", Json::array()}};
  for (size_t c = 0; s && c < session.photos.size(); ++c) {
    const std::string stem = out_dir + "/" + session.photos[c].name.substr(0, session.photos[c].name.size() - 4);
    s = write_file(stem + ".json", landmarks_to_json(session.photos[c]));
    truth["cameras"].push_back(camera_json(session.cameras[c]));
    if (!s || args.has("no-render")) continue;
    Image photo;
    s = render_session_image(person, skin, eyes, session.cameras[c], photo);
    if (s) s = write_file(stem + ".png", write_png(photo));
    // The exact mask a perfect segmentation would give (likeness photos --masks).
    Image mask;
    if (s) s = synthetic_mask(person.mesh, session.cameras[c], mask);
    // mask_XX.png, not view_XX_mask.png: a glob view_*.png stays the photos alone.
    if (s) s = write_file(out_dir + "/mask_" + session.photos[c].name.substr(5), write_png(mask));
  }
  if (s) s = write_file(out_dir + "/truth.json", truth.dump(2) + "\n");
  if (!s) return fail(cmd, s.message);
  std::printf("synth-photos: seed %d, %zu views -> %s (view_XX.json%s, map.json, person.obj, truth.json)\n", seed,
              session.photos.size(), out_dir.c_str(), args.has("no-render") ? "" : ", view_XX.png, mask_XX.png");
  return 0;
}

// likeness learn-landmark-map: the MediaPipe map re-made from the real
// detector's points on synthetic sessions (tests/browser/detect_synth_photos.mjs
// writes DIR: session.json and seedN/view_XX.json); the truth re-made from
// each seed as synth-photos makes it.
int run_learn_landmark_map(const Args& args) {
  const std::string cmd = "learn-landmark-map";
  if (!only_known_options(cmd, args, {"detected", "out", "map", "slide"})) return 2;
  const std::string dirs = args.get("detected"), out_path = args.get("out"), map_path = args.get("map");
  if (dirs.empty() || out_path.empty()) return fail(cmd, "needs --detected DIR[,DIR...] and --out MAP.json");
  GenericHead generic;
  Status s = load_generic_head(generic);
  if (!s) return fail(cmd, s.message);
  Bytes bytes;
  std::string map_text = mediapipe_landmark_map_text();
  if (!map_path.empty()) {
    s = read_file(map_path, bytes, kMaxLandmarkFileBytes);
    if (!s) return fail(cmd, s.message);
    map_text.assign(bytes.begin(), bytes.end());
  }
  LandmarkMap start, ph_map;
  s = parse_landmark_map_json(map_text, start);
  std::vector<SurfacePoint> ph_lms;
  if (s) s = placeholder_landmark_map(generic, 468, ph_map);
  if (s) s = attach_landmark_map(ph_map, generic.mesh, 1e-3, ph_lms);
  if (!s) return fail(cmd, s.message);
  std::deque<GenericHead> people;
  std::vector<DetectedSessionView> sessions;
  size_t a = 0;
  while (a < dirs.size()) {
    const size_t b = std::min(dirs.find(',', a), dirs.size());
    const std::string dir = dirs.substr(a, b - a);
    a = b + 1;
    if (dir.empty()) continue;
    s = read_file(dir + "/session.json", bytes, 1 << 20);
    if (!s) return fail(cmd, s.message + " (make DIR with tests/browser/detect_synth_photos.mjs)");
    Json session = Json::parse(std::string(bytes.begin(), bytes.end()), nullptr, false);
    if (session.is_discarded() || !session.contains("cameras") || !session["cameras"].is_number_integer() ||
        !session.contains("seeds") || !session["seeds"].is_array())
      return fail(cmd, dir + "/session.json: needs {\"cameras\": C, \"seeds\": [...]}");
    const int cameras = session["cameras"].get<int>();
    if (cameras < 2 || cameras > 64) return fail(cmd, dir + "/session.json: cameras must be 2..64");
    for (const Json& js : session["seeds"]) {
      if (!js.is_number_integer() || js.get<int>() < 0) return fail(cmd, dir + "/session.json: seeds must be integers");
      const int seed = js.get<int>();
      people.emplace_back();
      SyntheticViewsOptions vo;
      vo.num_cameras = cameras;
      SyntheticSession truth;
      s = synthesize_head(generic, std::uint32_t(seed), SynthHeadOptions{}, people.back());
      if (s) s = make_synthetic_views(people.back(), ph_lms, std::uint32_t(seed), vo, truth);
      if (!s) return fail(cmd, s.message);
      DetectedSessionView v;
      v.person = &people.back().mesh;
      for (int c = 0; c < cameras; ++c) {
        char name[32];
        std::snprintf(name, sizeof name, "/view_%02d.json", c);
        const std::string path = dir + "/seed" + std::to_string(seed) + name;
        if (!read_file(path, bytes, kMaxLandmarkFileBytes)) continue;  // no face found on that view
        LandmarkPhoto ph;
        s = parse_landmarks_json(std::string(bytes.begin(), bytes.end()), ph);
        if (!s) return fail(cmd, path + ": " + s.message);
        if (ph.detector != start.detector)
          return fail(cmd, path + ": points of '" + ph.detector + "', the map is for '" + start.detector + "'");
        v.cameras.push_back(truth.cameras[size_t(c)]);
        v.photos.push_back(ph);
      }
      sessions.push_back(std::move(v));
    }
  }
  LandmarkMap learned;
  if (args.has("slide")) {
    LearnSlideReport rep;
    s = learn_landmark_slide(generic.mesh, start, sessions, LearnSlideOptions{}, learned, &rep);
    if (s) s = write_file(out_path, landmark_map_to_json(learned));
    if (!s) return fail(cmd, s.message);
    std::printf("learn-landmark-map --slide: %d landmarks from %zu sessions, %d with a slide (views within yaw "
                "+-%.1f, pitch +-%.1f deg); training scatter %.2f mm with a fixed point, %.2f mm with the slide "
                "(per coordinate, at the landmark) -> %s\n",
                rep.learned, sessions.size(), rep.sliding, rep.yaw_range_deg, rep.pitch_range_deg,
                1000 * rep.rms_fixed_m, 1000 * rep.rms_slide_m, out_path.c_str());
    return 0;
  }
  LearnMapReport rep;
  s = learn_landmark_map(generic.mesh, start, sessions, LearnMapOptions{}, learned, &rep);
  if (s) s = write_file(out_path, landmark_map_to_json(learned));
  if (!s) return fail(cmd, s.message);
  std::printf("learn-landmark-map: %d landmarks re-made from %zu sessions (median move %.2f mm) -> %s\n", rep.learned,
              sessions.size(), 1000 * rep.median_move_m, out_path.c_str());
  return 0;
}

Registrar photos_reg({"photos",
                      "likeness photos --points P1.json P2.json ... --out DIR [--map MAP.json] [--photos P1.jpg ...] [--masks M1.png ... | --no-outlines] [--silhouette-check] "
                      "[--focal-px F] [--levels L] [--texture-size N] [--no-texture] [--register-texture] [--label-texture] [--stereo] [--folds] [--coarse N:S,...|none] [--schedule S,...|none] [--follow K[:W]] [--symmetry W] [--no-skin-detail] [--depth-scale SIGMA [--depth-0 K0] [--depth-yaw2 C]] [--focal-sigma S] [--focal-jackknife] [--no-slide] [--contours [--contour-lambda K]] [--contour-check] [--lids] [--iris-photo NAME] [--pulls | --pulls-by-photo | --pulls-by-landmark]",
                      "a head from several photos' landmarks (fua1998): self-calibrated cameras, fitted control "
                      "mesh, levels, cameras.json, report.json; with --photos the skin from those cameras "
                      "(textured.obj, skin.png, sources.png; --label-texture: one photo per texture region, texture/labeling.h; "
                      "--register-texture: the photos re-registered on the head first, "
                      "texture/register.h) and the iris found in them (eye.png; --iris-photo NAME: in that photo only, "
                      "else the most frontal eye); head.likeness.glb, the head project; with --masks (white or opaque = the person) the head's outline "
                      "in each photo as silhouettes, the face's rim matched to it (with --photos and no --masks, by default, from the "
                      "photos where their background is plain, as the page does; --no-outlines: none; "
                      "--silhouette-check: silhouettes_N.png, outline and rims drawn on each photo); with --photos "
                      "and --stereo, stereo between pairs of them joins the landmarks (off by default: on real "
                      "photos it dents the face, docs/design/photos.md); --coarse: the shape fit first over coarse control "
                      "triangulations of N nodes at stiffness S (fua1998 Sec. 2.1), --schedule: the control mesh's own "
                      "stiffness stages after them; --follow K[:W]: the stiffness on the displacement less a fitted similarity, "
                      "plus K x stiffness ||displacement - similarity||^2 where no observation is (W x that where one is; "
                      "default 0): unobserved parts follow the head, not the nearest pull; --symmetry W: the shape fit asks each "
                      "displacement, mirrored, of the other side (weight W, default 0.3; 0: off); --no-skin-detail: the levels without the generic head's skin detail (the furrows of its smooth levels left in); --depth-scale: a per-photo depth scale in the bundle adjustment "
                      "(prior sigma SIGMA, mean K0 + C (yaw/60 deg)^2) for the detector's error shared by a photo's points; "
                      "--focal-sigma: the focal prior's relative sigma (with --focal-px); --focal-jackknife: the landmarks' focal weighed by the photos' disagreement, over the detector's ratio, with EXIF or a phone's 26 mm prior (not the default); --no-slide: the map's "
                      "view-dependent slide left out; --contours: the face outline's jaw and chin landmarks as "
                      "contour observations, not fixed surface points (--contour-lambda: their weight, x the "
                      "features'); the report and --contour-check: contours_N.png, the face outline's landmarks, their distance to "
                      "the fit's rim and the rims drawn on each photo; --pulls: which observation groups move the cheeks and the "
                      "jaw outward (the first step's and the fitted displacement's split, the forces at the end; report.json's fit_pulls; "
                      "--pulls-by-photo: the features split by photo instead of by landmark group, --pulls-by-landmark: by landmark, "
                      "the 15 widening the cheeks most and the 3 narrowing them most printed)",
                      run_photos, nullptr});
Registrar synth_photos_reg({"synth-photos",
                            "likeness synth-photos --out DIR [--seed N] [--cameras C] [--noise-px S] [--no-render]",
                            "a synthetic photo session with its truth: landmark files, map, rendered views, cameras",
                            run_synth_photos, nullptr});

Registrar learn_map_reg({"learn-landmark-map", "likeness learn-landmark-map --detected DIR[,DIR...] --out MAP.json [--map START.json] [--slide]",
                         "the MediaPipe landmark map re-made from the real detector's points on synthetic sessions with "
                         "their truth (tests/browser/detect_synth_photos.mjs writes DIR); --slide: with the detector's "
                         "view-dependent slide and scatter per landmark (map version 2, photos/landmark_slide.h)",
                         run_learn_landmark_map, nullptr});
}  // namespace
}  // namespace lk::cli
