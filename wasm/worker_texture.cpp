// The worker's photo jobs: the skin texture of the kept head (core/project/
// texture_job.h), and the iris and teeth textures from eye and smile photos.
#include "worker_common.h"

#include "project/parts.h"
#include "project/texture_job.h"

#include <algorithm>
#include <cmath>

namespace lk_worker {
namespace {

// ---- texturing (tarini2002 Sec. 3-4) ------------------------------------------

val calib_object(const lk::CalibResult& c) {
  val o = val::object();
  o.set("ok", true);
  o.set("rms", c.rms);
  o.set("inliers", c.num_inliers);
  o.set("focal", c.camera.fx);
  val errors = val::array(), outlier = val::array();
  for (size_t k = 0; k < c.errors.size(); ++k) {
    errors.call<void>("push", std::isfinite(c.errors[k]) ? c.errors[k] : -1.0);  // -1: behind the camera
    outlier.call<void>("push", k < c.outlier.size() && c.outlier[k] != 0);
  }
  o.set("errors", errors);
  o.set("outlier", outlier);
  return o;
}

// Per photo {ok, rms, inliers, focal, errors[], outlier[]} or {ok: false, message}.
val calib_array(const lk::PhotoCalibration& c) {
  val out = val::array();
  for (size_t i = 0; i < c.status.size(); ++i) {
    if (c.status[i].ok()) {
      out.call<void>("push", calib_object(c.results[i]));
    } else {
      val o = val::object();
      o.set("ok", false);
      o.set("message", c.status[i].message);
      out.call<void>("push", o);
    }
  }
  return out;
}

// Textures the kept head from photos (core/project/texture_job.h): photos
// is an array of {name, ptr, size, points} with the photo file's bytes at
// (ptr, size) and points a Float64Array of u v X Y Z per correspondence
// (pixels, top-left origin; the point on the head in the scan's frame, as
// the fit result's landmarks). options: {level (default finest), size
// (texels, default 1024), cameras (true: a head from photos, each photo's
// camera is its self-calibration's, found by name; points are not read)}.
// progress gets "texture:<step>" and the job's
// overall fraction. Returns {ok, code, message, calib: [per photo],
// uvs Float32Array #V*2, skin {width, height, channels, pixels}, steps
// [{name, ms}], level, vertexCount, chartL2, textureMs}. On a calibration
// failure calib still holds every photo's outcome (the page marks the bad
// points).
val texture_job(val photos, val options, val progress) {
  const lk::ProgressFn report = js_progress(progress);
  if (!kept_project()) return error_result(lk::ErrorCode::InvalidInput, "fit a head first: there is no head to texture");
  lk::HeadProject& project = *kept_project();
  const int levels = project.fit.multires.num_levels();
  lk::TextureJobInput input;
  input.level = has(options, "level") ? options["level"].as<int>() : levels;
  input.options.size = has(options, "size") ? options["size"].as<int>() : 1024;
  if (input.level < 0 || input.level > levels)
    return error_result(lk::ErrorCode::InvalidInput, "no level " + std::to_string(input.level));
  if (input.options.size < 16 || input.options.size > 4096)
    return error_result(lk::ErrorCode::InvalidInput, "texture size must be 16..4096 texels");
  // A head from photos: each photo's camera is the self-calibration's.
  input.cameras_given = has(options, "cameras") && options["cameras"].as<bool>();
  // And the iris from the same photos, unless the page has one from an eye
  // photo. findEyes: true: looked for even when the project holds one (the
  // page knows whose eye it shows); irisPhoto: the photo the user set to
  // "Eye (iris)", searched alone.
  lk::Status generic_status;
  if (input.cameras_given && !(has(options, "findEyes") && !options["findEyes"].as<bool>()))
    input.generic_for_eyes = generic_head(generic_status);
  input.replace_eye_texture = has(options, "findEyes") && options["findEyes"].as<bool>();
  if (has(options, "irisPhoto") && options["irisPhoto"].isString()) input.iris_photo = options["irisPhoto"].as<std::string>();
  const int count = photos.isArray() ? photos["length"].as<int>() : 0;
  if (count == 0) return error_result(lk::ErrorCode::InvalidInput, "no photo to texture from");
  if (count > lk::kMaxTexturePhotos)
    return error_result(lk::ErrorCode::InvalidInput, std::to_string(count) + " photos; at most " +
                                                         std::to_string(lk::kMaxTexturePhotos) + " are used");

  // Steps timed here from the job's observer; progress as the overall fraction.
  const int num_steps = static_cast<int>(lk::texture_job_steps().size());
  val steps = val::array();
  int step = 0;
  double t_step = now_ms();
  const double t_job = t_step;
  lk::StepObserver observer;
  observer.started = [&](const std::string& name) {
    step = std::max(0, lk::texture_job_step_index(name));
    t_step = now_ms();
  };
  observer.finished = [&](const std::string& name) {
    val o = val::object();
    o.set("name", name);
    o.set("ms", now_ms() - t_step);
    steps.call<void>("push", o);
  };
  const lk::ProgressFn overall = [&](const char* name, double fraction) {
    const double f = (step + std::min(1.0, std::max(0.0, fraction))) / num_steps;
    return lk::report(report, ("texture:" + std::string(name)).c_str(), std::min(0.999, f));
  };
  const auto cancelled = [](const std::string& where) {
    return error_result(lk::ErrorCode::Cancelled, "texturing cancelled at " + where);
  };

  // Decode the photos and read their correspondences.
  observer.started("decode");
  if (!overall("decode", 0)) return cancelled("decode");
  input.photos.resize(count);
  input.points.resize(count);
  for (int i = 0; i < count; ++i) {
    const val p = photos[i];
    const std::string name = p["name"].isString() ? p["name"].as<std::string>() : "photo " + std::to_string(i + 1);
    input.names.push_back(name);
    const std::uintptr_t ptr = p["ptr"].as<std::uintptr_t>();
    if (ptr == 0) return error_result(lk::ErrorCode::Internal, name + ": no input buffer");
    const lk::Status st = decode_image(name, ptr, p["size"].as<std::size_t>(), p["decoded"], input.photos[i].image, 3);
    if (!st.ok()) return error_result(st);
    if (input.cameras_given) {
      const lk::Camera* camera = kept_photo_cameras().find(&project, name);
      if (!camera)
        return error_result(lk::ErrorCode::InvalidInput, name + ": not one of the photos the head was made from " +
                                                             "(make the head from the photos again)");
      input.photos[i].camera = *camera;
      if (!overall("decode", (i + 1.0) / count)) return cancelled("decode");
      continue;
    }
    const std::vector<double> flat = emscripten::convertJSArrayToNumberVector<double>(p["points"]);
    if (flat.size() % 5 != 0)
      return error_result(lk::ErrorCode::InvalidInput, name + ": points need 5 numbers each (u v X Y Z)");
    for (size_t k = 0; k + 4 < flat.size(); k += 5)
      input.points[i].push_back({lk::Vec2(flat[k], flat[k + 1]), lk::Vec3(flat[k + 2], flat[k + 3], flat[k + 4])});
    if (input.points[i].size() < 6)
      return error_result(lk::ErrorCode::InvalidInput, name + ": " + std::to_string(input.points[i].size()) +
                                                           " points; calibrating a photo needs at least 6 (12-15 are best)");
    if (!overall("decode", (i + 1.0) / count)) return cancelled("decode");
  }
  observer.finished("decode");

  lk::TextureJobResult out;
  const lk::Status st = lk::texture_project(project, input, out, observer, overall);
  if (!st.ok()) {
    val r = error_result(st);
    if (!out.calibration.status.empty()) r.set("calib", calib_array(out.calibration));
    return r;
  }
  lk::report(report, "texture:done", 1.0);
  val r = ok_result();
  r.set("calib", calib_array(out.calibration));
  r.set("uvs", float32_array(project.texture.uvs));
  r.set("skin", image_object(project.texture.skin));
  r.set("steps", steps);
  r.set("level", out.level);
  r.set("vertexCount", static_cast<double>(out.head.mesh.positions.size()));
  r.set("chartL2", out.chart.l2_stretch);
  r.set("textureMs", now_ms() - t_job);
  // The iris found in the photos (eye_from_views.h), or why not.
  if (out.eye_status.ok()) {
    r.set("eyeTexture", image_object(out.eye.texture));
    r.set("eyeSource", input.names[size_t(out.eye.photo)]);
  } else if (out.eye_status.code != lk::ErrorCode::Empty) {
    r.set("eyeNote", out.eye_status.message);
  }
  return r;
}

// An eye photo (role "Eye (iris)") -> the eyeball texture (tarini2002 Sec.
// 4.1): the iris found from the darkest blob near the centre (or from
// guess [x, y] in pixels, optional), its valid part resynthesized around the
// whole circle. {ok, texture, circle: {x, y, radius, pupilRadius}, usedTwoD,
// sectorDeg, ms} or the core's error (no dark blob, the circle never stops,
// not an eye close-up). decoded: see decode_image; progress: "iris", 0..1.
val eye_photo_job(const std::string& name, std::uintptr_t data, std::size_t size, val guess, val decoded, val progress) {
  const double t0 = now_ms();
  lk::Image photo;
  lk::Status status = decode_image(name, data, size, decoded, photo);
  if (!status.ok()) return error_result(status);
  lk::Vec2 guess_px;
  const bool have_guess = !guess.isUndefined() && !guess.isNull() && guess["length"].as<int>() == 2;
  if (have_guess) guess_px = lk::Vec2(guess[0].as<double>(), guess[1].as<double>());
  lk::IrisResult iris;
  lk::EyeballTextureOptions eto;
  eto.size = 256;  // as the generic eyes
  status = lk::iris_texture_from_photo(photo, have_guess ? &guess_px : nullptr, iris, eto, js_progress(progress));
  if (!status.ok()) return error_result(lk::with_context(status, name + ": no iris found"));
  val r = ok_result();
  r.set("texture", image_object(iris.texture));
  val c = val::object();
  c.set("x", iris.circle.center.x());
  c.set("y", iris.circle.center.y());
  c.set("radius", iris.circle.radius);
  c.set("pupilRadius", iris.circle.pupil_radius);
  r.set("circle", c);
  r.set("usedTwoD", iris.report.used_2d);
  r.set("sectorDeg", iris.report.sector_deg);
  r.set("ms", now_ms() - t0);
  return r;
}

// A smile photo (role "Smile (teeth)") -> the teeth texture in the teeth
// model's uv layout (tarini2002 Sec. 4.2). {ok, texture (RGBA), ms} or the
// core's error (e.g. no teeth found).
val smile_photo_job(const std::string& name, std::uintptr_t data, std::size_t size, val decoded) {
  const double t0 = now_ms();
  lk::Image photo;
  lk::Status status = decode_image(name, data, size, decoded, photo);
  if (!status.ok()) return error_result(status);
  lk::TeethResult teeth;
  lk::Image texture;
  const lk::TeethCompositeOptions composite = teeth_composite();
  status = lk::teeth_photo_texture(photo, lk::TeethOptions{}, teeth, &composite, &texture);
  if (!status.ok()) return error_result(lk::with_context(status, name));
  val r = ok_result();
  r.set("texture", image_object(texture));
  r.set("ms", now_ms() - t0);
  return r;
}

}  // namespace
}  // namespace lk_worker

EMSCRIPTEN_BINDINGS(likeness_worker_texture) {
  using namespace lk_worker;
  emscripten::function("texture_job", &texture_job);
  emscripten::function("eye_photo_job", &eye_photo_job);
  emscripten::function("smile_photo_job", &smile_photo_job);
}
