// The worker's photos job (issue 37): each photo's face landmarks (the
// likeness-landmarks JSON the page's detector writes) -> cameras and the
// person's head, by core/project/photos_project.h (run_photos_job, the core
// job `likeness photos` runs), kept as the head project so Animate, Export
// and Save work on it as on a fitted head.
#include "worker_common.h"

#include "photos/landmarks.h"
#include "head/skin_detail.h"
#include "project/photos_project.h"

#include <memory>

namespace lk_worker {
namespace {

// The MediaPipe map that ships with the head, parsed once per worker.
const lk::LandmarkMap* mediapipe_map(lk::Status& status) {
  static lk::LandmarkMap map;
  static bool have = false;
  status = lk::Status::success();
  if (!have) {
    status = lk::parse_landmark_map_json(lk::mediapipe_landmark_map_text(), map);
    if (!status.ok()) return nullptr;
    have = true;
  }
  return &map;
}

// The generic head's skin detail for `levels` (head/skin_detail.h), made
// once per worker and level count.
const std::vector<std::vector<double>>* skin_detail(const lk::GenericHead& generic, int levels, lk::Status& status) {
  static std::vector<std::vector<double>> detail[5];
  static bool have[5] = {};
  status = lk::Status::success();
  if (levels < 0 || levels > 4) {
    status = lk::Status::error(lk::ErrorCode::InvalidInput, "levels must be 0..4");
    return nullptr;
  }
  if (!have[levels]) {
    status = lk::generic_skin_detail(generic, levels, lk::SkinDetailOptions{}, detail[levels]);
    if (!status.ok()) return nullptr;
    have[levels] = true;
  }
  return &detail[levels];
}

// A dropped photo's outline on a plain background (photos/outline.h:
// outline_from_plain_photo, as `likeness photos --photos` finds it), for the
// head's silhouettes. The pixels (decoded: see decode_image) are the photo's
// or the smaller copy the page's face detector gets; width x height is the
// photo's own size. -> {ok, points: Float64Array of x y nx ny
// per outline point, in the photo's pixels} or {ok: false, message} (the
// background is not plain, no outline in it: the photo keeps its landmarks).
val plain_outline(const std::string& name, std::uintptr_t data, std::size_t size, val decoded, int width, int height) {
  lk::Image image;
  lk::Status status = decode_image(name, data, size, decoded, image, 3);
  lk::PhotoOutline outline;
  if (width <= 0 || height <= 0) {  // (the stb path of the 'outline' job: the photo's own size)
    width = image.width;
    height = image.height;
  }
  if (status.ok())
    status = lk::outline_from_plain_photo(image, width, height, lk::kPlainOutlineMaxSide, lk::PlainBackgroundOptions{},
                                          lk::OutlineOptions{}, outline);
  if (!status.ok()) return error_result(status);
  std::vector<double> flat;
  flat.reserve(4 * outline.points.size());
  for (const lk::OutlinePoint& q : outline.points)
    flat.insert(flat.end(), {q.pixel.x(), q.pixel.y(), q.normal.x(), q.normal.y()});
  val r = ok_result();
  r.set("points", typed_array("Float64Array", flat));
  return r;
}

// The outline a photo row carries ({outline: Float64Array x y nx ny ...},
// from plain_outline) for a photo of width x height; none: no points.
lk::PhotoOutline outline_of(const val& p, int width, int height) {
  lk::PhotoOutline o;
  o.width = width;
  o.height = height;
  if (!has(p, "outline") || p["outline"].isNull()) return o;
  const std::vector<double> flat = emscripten::convertJSArrayToNumberVector<double>(p["outline"]);
  for (size_t i = 0; i + 3 < flat.size(); i += 4) {
    const lk::Vec2 q(flat[i], flat[i + 1]), n(flat[i + 2], flat[i + 3]);
    if (q.allFinite() && n.allFinite() && n.norm() > 0.5 && q.x() >= 0 && q.y() >= 0 && q.x() <= width && q.y() <= height)
      o.points.push_back({q, n.normalized()});
  }
  return o;
}

// photos: [{name, text, outline?}] (text: the photo's likeness-landmarks
// JSON; outline: its plain_outline points, the silhouettes);
// options: {levels (1..4, default 3), focalPx (a focal prior in pixels, 0:
// none)}. Returns what fit_head_job does (head_result: meshes with the
// generic head as "aligned", the fitted control mesh as "local" and
// "control", the levels; notes; components) plus
//   photos [{name, used, refusal, rmsPx, landmarks, outliers, outlinePoints}] in the order given
//   focalPx, calibrationRmsPx [before, after], shapeFitRmsPx [before, after],
//   silhouettes {photos, points, matched [generic, fit], rimToOutlinePx
//   [generic, fit]} (only when some photo had an outline),
//   calibrationIterations, shapeFitStages [{stiffness, iterations}], photosMs.
// A photo whose file is refused (format, size) is named with its reason and
// left out, as the CLI does. On an error (fewer than 2 usable photos, ...)
// the kept head is unchanged and the error result carries photos too.
val photos_head_job(val photos, val options) {
  int levels = 3;
  double focal_px = 0;
  if (has(options, "levels")) levels = options["levels"].as<int>();
  if (has(options, "focalPx")) focal_px = options["focalPx"].as<double>();
  if (levels < 1 || levels > 4) return error_result(lk::ErrorCode::InvalidInput, "levels must be 1..4");
  if (!(focal_px >= 0 && focal_px < 1e6)) return error_result(lk::ErrorCode::InvalidInput, "focalPx must be 0..1e6");
  lk::Status status;
  const lk::GenericHead* generic = generic_head(status);
  if (!generic) return error_result(lk::with_context(status, "generic head"));
  const lk::LandmarkMap* map = mediapipe_map(status);
  if (!map) return error_result(lk::with_context(status, "the embedded MediaPipe map"));

  const int n = photos.isUndefined() || photos.isNull() ? 0 : photos["length"].as<int>();
  std::vector<lk::LandmarkPhoto> parsed;
  std::vector<int> parsed_index(static_cast<size_t>(n), -1);  // photo k -> its index in parsed, -1: refused
  std::vector<std::string> names(static_cast<size_t>(n)), refusals(static_cast<size_t>(n));
  std::vector<lk::PhotoOutline> outlines;  // #parsed
  bool with_outlines = false;
  for (int k = 0; k < n; ++k) {
    const val p = photos[k];
    names[size_t(k)] = has(p, "name") ? p["name"].as<std::string>() : "photo " + std::to_string(k + 1);
    const std::string text = has(p, "text") ? p["text"].as<std::string>() : std::string();
    lk::LandmarkPhoto ph;
    const lk::Status s = text.size() > lk::kMaxLandmarkFileBytes
                             ? lk::Status::error(lk::ErrorCode::TooLarge, "landmarks larger than 4 MB")
                             : lk::parse_landmarks_json(text, ph);
    if (!s.ok()) {
      refusals[size_t(k)] = s.message;
      continue;
    }
    ph.name = names[size_t(k)];
    parsed_index[size_t(k)] = static_cast<int>(parsed.size());
    outlines.push_back(outline_of(p, ph.width, ph.height));
    with_outlines = with_outlines || !outlines.back().points.empty();
    parsed.push_back(std::move(ph));
  }

  lk::PhotosJobOptions opt;
  opt.calib.focal_prior_px = focal_px;
  auto project = std::make_unique<lk::HeadProject>();
  lk::PhotosJobResult job;
  const double t0 = now_ms();
  // (the first job of a worker makes the skin detail: counted in its time)
  const std::vector<std::vector<double>>* detail = skin_detail(*generic, levels, status);
  if (!detail) return error_result(lk::with_context(status, "the generic head's skin detail"));
  status = lk::photos_project(*generic, *map, parsed, opt, levels, *project, job, detail,
                              with_outlines ? &outlines : nullptr);
  const double photos_ms = now_ms() - t0;

  val rows = val::array();
  for (int k = 0; k < n; ++k) {
    val o = val::object();
    o.set("name", names[size_t(k)]);
    const int i = parsed_index[size_t(k)];
    const bool calibrated = i >= 0 && static_cast<size_t>(i) < job.calib.photos.size();
    const lk::PhotoCalibration* pc = calibrated ? &job.calib.photos[size_t(i)] : nullptr;
    o.set("used", status.ok() && pc && pc->used);
    o.set("refusal", i < 0 ? refusals[size_t(k)] : pc ? pc->refusal : std::string());
    o.set("rmsPx", pc ? pc->rms_px : 0.0);
    o.set("landmarks", pc ? pc->num_landmarks : 0);
    o.set("outliers", pc ? pc->num_outliers : 0);
    o.set("outlinePoints", i >= 0 ? int(outlines[size_t(i)].points.size()) : 0);
    rows.call<void>("push", o);
  }
  if (!status.ok()) {
    val e = error_result(status);
    e.set("photos", rows);
    e.set("photosMs", photos_ms);
    return e;
  }
  val r = head_result(*project, *generic);
  // The CLI's notes: photos left out (with why), one photo only, ...
  val notes = val::array();
  for (int k = 0; k < n; ++k)
    if (parsed_index[size_t(k)] < 0) notes.call<void>("push", names[size_t(k)] + ": " + refusals[size_t(k)] + " (left out)");
  for (const std::string& note : job.notes) notes.call<void>("push", note);
  r.set("notes", notes);
  r.set("name", std::string("photos"));
  r.set("photos", rows);
  r.set("focalPx", job.calib.focal);
  val calib_rms = val::array(), fit_rms = val::array();
  calib_rms.call<void>("push", job.calib.initial_rms_px);
  calib_rms.call<void>("push", job.calib.final_rms_px);
  fit_rms.call<void>("push", job.fit.initial_rms_px);
  fit_rms.call<void>("push", job.fit.final_rms_px);
  r.set("calibrationRmsPx", calib_rms);
  r.set("shapeFitRmsPx", fit_rms);
  r.set("calibrationIterations", job.calib.lm_iterations);
  val stages = val::array();
  for (const lk::ShapeFitStage& st : job.fit.stages) {
    val o = val::object();
    o.set("stiffness", st.stiffness);
    o.set("iterations", st.lm_iterations);
    stages.call<void>("push", o);
  }
  r.set("shapeFitStages", stages);
  // The head's rim against the photos' outlines (fua1998 Sec. 3.2), at the
  // generic head and at the fit, as `likeness photos` reports them.
  if (with_outlines) {
    const auto sil = lk::make_silhouette_set(*generic, generic->mesh, job.calib, outlines, opt.silhouettes);
    if (sil) {
      const lk::SilhouetteStats a = sil->stats(generic->mesh.positions), b = sil->stats(job.fit.mesh.positions);
      val o = val::object(), mean = val::array(), matched = val::array();
      mean.call<void>("push", a.mean_px);
      mean.call<void>("push", b.mean_px);
      matched.call<void>("push", a.matched);
      matched.call<void>("push", b.matched);
      o.set("points", a.points);
      o.set("matched", matched);
      o.set("rimToOutlinePx", mean);
      int photos_with = 0;
      for (size_t i = 0; i < outlines.size() && i < job.calib.photos.size(); ++i)
        photos_with += job.calib.photos[i].used && !outlines[i].points.empty();
      o.set("photos", photos_with);
      r.set("silhouettes", o);
    }
  }
  r.set("stages", val::array());  // no scan: no distance figures per stage
  r.set("photosMs", photos_ms);
  r.set("fitMs", photos_ms);
  kept_project() = std::move(project);
  PhotoCameras& cams = kept_photo_cameras();
  cams = PhotoCameras{};
  cams.project = kept_project().get();
  for (int k = 0; k < n; ++k) {
    const int i = parsed_index[size_t(k)];
    if (i < 0 || static_cast<size_t>(i) >= job.calib.photos.size() || !job.calib.photos[size_t(i)].used) continue;
    cams.names.push_back(names[size_t(k)]);
    cams.cameras.push_back(job.calib.photos[size_t(i)].camera);
  }
  return r;
}

}  // namespace

PhotoCameras& kept_photo_cameras() {
  static PhotoCameras cameras;
  return cameras;
}

const lk::Camera* PhotoCameras::find(const lk::HeadProject* of, const std::string& name) const {
  if (!of || of != project) return nullptr;
  for (size_t i = 0; i < names.size(); ++i)
    if (names[i] == name) return &cameras[i];
  return nullptr;
}
}  // namespace lk_worker

EMSCRIPTEN_BINDINGS(likeness_worker_photos) {
  using namespace lk_worker;
  emscripten::function("photos_head_job", &photos_head_job);
  emscripten::function("plain_outline", &plain_outline);
  // The longer side plain_outline shrinks a photo to (worker.js: when the
  // detector's copy of that size serves instead).
  emscripten::constant("PLAIN_OUTLINE_MAX_SIDE", lk::kPlainOutlineMaxSide);
}
