// likeness eye: eyeball texture from one eye photo (core/iris, Tarini et al.
// 2002 Sec. 4.1). Optional --debug-dir writes the polar input with removed
// pixels in black, the reference sector and the synthesized polar iris.
#include "command.h"

#include "io/io.h"
#include "iris/iris.h"

#include <cerrno>
#include <chrono>
#include <climits>
#include <cstdlib>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <sstream>

namespace lk::cli {
namespace {

// "x,y" in pixels.
bool parse_point(const std::string& s, Vec2& p) {
  double x, y;
  char comma, extra;
  std::istringstream in(s);
  if (!(in >> x >> comma >> y) || comma != ',' || (in >> extra) || !std::isfinite(x) || !std::isfinite(y)) return false;
  p = Vec2(x, y);
  return true;
}

Image polar_to_image(const PolarIris& p, bool show_invalid, int sector_begin = -1, int sector_rows = 0) {
  // Angles run down the image, radii across (pupil on the left).
  Image im = Image::make(p.radii, p.angles, 3);
  for (int a = 0; a < p.angles; ++a)
    for (int r = 0; r < p.radii; ++r) {
      const float* c = p.at(a, r);
      const bool ok = !show_invalid || p.valid[static_cast<size_t>(a) * p.radii + r];
      for (int k = 0; k < 3; ++k)
        im.at(r, a)[k] = ok ? static_cast<std::uint8_t>(std::lround(std::clamp(c[k], 0.f, 1.f) * 255)) : 0;
      const int rel = ((a - sector_begin) % p.angles + p.angles) % p.angles;
      if (sector_begin >= 0 && rel < sector_rows && (r == 0 || r == p.radii - 1)) {
        im.at(r, a)[0] = 255; im.at(r, a)[1] = 255; im.at(r, a)[2] = 255;
      }
    }
  return im;
}

int run_eye(const Args& args) {
  const char* cmd = "eye";
  if (!only_known_options(cmd, args, {"photo", "out", "guess", "size", "debug-dir"})) return 2;
  if (!args.has("photo") || !args.has("out")) {
    fail(cmd, "needs --photo FILE and --out FILE.png");
    return 2;
  }
  Vec2 guess;
  const bool has_guess = args.has("guess");
  if (has_guess && !parse_point(args.get("guess"), guess)) {
    fail(cmd, "--guess expects x,y in pixels, got '" + args.get("guess") + "'");
    return 2;
  }
  int size = 512;
  if (!args.get_int("size", 512, size, 16, 4096)) return 2;
  Image photo;
  if (Status s = load_image_file(args.get("photo"), photo, 3); !s) return fail(cmd, s.message);
  EyeballTextureOptions topt;
  topt.size = size;
  IrisResult res;
  const auto t0 = std::chrono::steady_clock::now();
  if (Status s = iris_texture_from_photo(photo, has_guess ? &guess : nullptr, res, topt); !s)
    return fail(cmd, args.get("photo") + ": " + s.message);
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (Status s = save_png_file(args.get("out"), res.texture); !s) return fail(cmd, s.message);
  std::printf("iris centre (%.2f, %.2f) px, radius %.2f px, pupil %.2f px\n", res.circle.center.x(),
              res.circle.center.y(), res.circle.radius, res.circle.pupil_radius);
  std::printf("valid iris samples %d of %d; %s, reference sector %.1f deg; %.2f s\n",
              res.report.valid_pixels, res.input_polar.angles * res.input_polar.radii,
              res.report.used_2d ? "2-D synthesis" : "1-D Markov chain of rows", res.report.sector_deg, secs);
  std::printf("wrote %s (%dx%d)\n", args.get("out").c_str(), res.texture.width, res.texture.height);
  if (args.has("debug-dir")) {
    const std::string d = args.get("debug-dir") + "/";
    // The photo with the found circles drawn in.
    Image marked = photo;
    for (double rad : {res.circle.radius, res.circle.pupil_radius})
      for (int i = 0; i < 2000; ++i) {
        const double t = 2 * 3.14159265358979 * i / 2000;
        const int x = static_cast<int>(std::lround(res.circle.center.x() + rad * std::cos(t)));
        const int y = static_cast<int>(std::lround(res.circle.center.y() + rad * std::sin(t)));
        if (x >= 0 && y >= 0 && x < marked.width && y < marked.height) {
          marked.at(x, y)[0] = 0; marked.at(x, y)[1] = 255; marked.at(x, y)[2] = 0;
        }
      }
    Status s = save_png_file(d + "iris_found.png", marked);
    if (s) s = save_png_file(d + "iris_polar_valid.png",
                             polar_to_image(res.input_polar, true, res.report.used_2d ? -1 : res.report.sector_begin,
                                            res.report.sector_rows));
    if (s) s = save_png_file(d + "iris_polar_synth.png", polar_to_image(res.synthesized, false));
    if (!s) return fail(cmd, s.message);
    std::printf("wrote %siris_found.png, iris_polar_valid.png, iris_polar_synth.png\n", d.c_str());
  }
  return 0;
}

Registrar reg_eye({"eye", "likeness eye --photo F --out iris.png [--guess x,y] [--size 512] [--debug-dir DIR]",
                   "eyeball texture (frontal hemisphere) from one eye photo: iris found, cleaned, synthesized",
                   run_eye});

}  // namespace
}  // namespace lk::cli

// likeness teeth: RGBA teeth texture (voids transparent) from one photo
// (core/teeth, Tarini et al. 2002 Sec. 4.2), or from the synthetic smile
// with lips hiding parts of the teeth (--synthetic-smile).
#include "project/parts.h"
#include "teeth/synthetic_smile.h"

namespace lk::cli {
namespace {

int run_teeth(const Args& args) {
  const char* cmd = "teeth";
  if (!only_known_options(cmd, args,
                          {"photo", "out", "generic-out", "synthetic-smile", "upper-dip", "lower-rise",
                           "no-reconstruct", "input-out", "crop"}))
    return 2;
  if ((!args.has("photo") && !args.has("synthetic-smile")) || !args.has("out")) {
    fail(cmd, "needs --photo FILE (or --synthetic-smile) and --out FILE.png");
    return 2;
  }
  Image photo;
  std::string input = args.get("photo");
  if (args.has("synthetic-smile")) {
    SyntheticSmileOptions so;
    so.width = 640;
    so.height = 320;
    // Rows at 320x160 (the smile is 160 rows tall).
    if (!args.get_double("upper-dip", 40, so.upper_dip, 0, 160) || !args.get_double("lower-rise", 34, so.lower_rise, 0, 160))
      return 2;
    photo = make_synthetic_smile(so).image;
    input = "synthetic smile";
    if (args.has("input-out"))
      if (Status s = save_png_file(args.get("input-out"), photo); !s) return fail(cmd, s.message);
  } else if (Status s = load_image_file(args.get("photo"), photo, 3); !s) {
    return fail(cmd, s.message);
  }
  if (args.has("crop")) {  // X,Y,W,H: the front teeth's part of a larger photo
    // Four integers, each parsed with its range (no sscanf %d overflow).
    long long v[4] = {-1, -1, -1, -1};
    const std::string crop = args.get("crop");
    const char* p = crop.c_str();
    bool parsed = true;
    for (int k = 0; k < 4 && parsed; ++k) {
      char* end = nullptr;
      errno = 0;
      v[k] = std::strtoll(p, &end, 10);
      parsed = end != p && errno == 0 && v[k] >= 0 && v[k] <= INT_MAX && *end == (k < 3 ? ',' : '\0');
      p = end + (k < 3 ? 1 : 0);
    }
    const long long cx = v[0], cy = v[1], cw = v[2], ch = v[3];
    if (!parsed || cw < 8 || ch < 8 || cx + cw > photo.width || cy + ch > photo.height)
      return fail(cmd, "--crop takes X,Y,W,H inside the " + std::to_string(photo.width) + "x" +
                           std::to_string(photo.height) + " photo (W, H >= 8)");
    Image cropped = Image::make(int(cw), int(ch), photo.channels);
    for (int y = 0; y < ch; ++y)
      for (int x = 0; x < cw; ++x)
        for (int k = 0; k < photo.channels; ++k) cropped.at(x, y)[k] = photo.at(int(cx) + x, int(cy) + y)[k];
    photo = std::move(cropped);
    if (args.has("input-out"))
      if (Status s = save_png_file(args.get("input-out"), photo); !s) return fail(cmd, s.message);
  }
  TeethOptions options;
  options.reconstruct_hidden = !args.has("no-reconstruct");
  TeethResult r;
  Image composite;  // with --generic-out: composited into the generic teeth texture
  const auto t0 = std::chrono::steady_clock::now();
  if (Status s = teeth_photo_texture(photo, options, r, nullptr, args.has("generic-out") ? &composite : nullptr); !s)
    return fail(cmd, input + ": " + s.message);
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (Status s = save_png_file(args.get("out"), r.texture); !s) return fail(cmd, s.message);
  size_t voids = 0, gums = 0;
  for (auto c : r.classes) { voids += c == TeethClass::Void; gums += c == TeethClass::Gum; }
  std::printf("thresholds: void %.3f, gum %.3f (colour distance); teeth %d px, gums %zu px, voids %zu px; %.2f s\n",
              r.void_threshold, r.gum_threshold, r.teeth_pixels, gums, voids, secs);
  std::printf("bite row %d; %d hidden pixels reconstructed\n", r.bite_row, r.reconstructed_pixels);
  std::printf("teeth target colour (%.3f, %.3f, %.3f); wrote %s\n", r.target_color[0], r.target_color[1],
              r.target_color[2], args.get("out").c_str());
  if (args.has("generic-out")) {
    if (Status s = save_png_file(args.get("generic-out"), composite); !s) return fail(cmd, s.message);
    std::printf("wrote %s (composited into the generic teeth texture)\n", args.get("generic-out").c_str());
  }
  return 0;
}

Registrar reg_teeth({"teeth", "likeness teeth --photo F [--crop X,Y,W,H] | --synthetic-smile [--upper-dip R --lower-rise R] [--input-out in.png] --out teeth.png [--generic-out arch.png] [--no-reconstruct]",
                     "RGBA teeth texture from one photo: voids transparent, gums recoloured, colour equalized",
                     run_teeth});

}  // namespace
}  // namespace lk::cli

// likeness components: generic eyes, teeth arch and tongue placed into a
// head that shares the generic head's topology (core/components).
#include "components/components.h"
#include "head/generic_head.h"
#include "mesh/geometry.h"
#include "render/camera.h"
#include "render/offscreen.h"

namespace lk::cli {
namespace {

int run_components(const Args& args) {
  const char* cmd = "components";
  if (!only_known_options(cmd, args,
                          {"head", "out", "render", "eye-texture", "teeth-texture", "view", "no-head"}))
    return 2;
  if (!args.has("out")) {
    fail(cmd, "needs --out DIR (and --head FILE.obj, default: the generic head)");
    return 2;
  }
  GenericHead generic;
  if (Status s = load_generic_head(generic); !s) return fail(cmd, s.message);
  TriMesh fitted = generic.mesh;
  if (args.has("head"))
    if (Status s = load_mesh_file(args.get("head"), fitted); !s) return fail(cmd, s.message);
  HeadParts placed;
  if (Status s = place_head_parts(fitted, generic, placed); !s) return fail(cmd, s.message);
  const ComponentPlacement& p = placed.placement;
  const PlacedComponents& c = placed.placed;
  const std::string d = args.get("out") + "/";
  const std::pair<const char*, const TriMesh*> files[] = {
      {"eye_left.obj", &c.eye[0]}, {"eye_right.obj", &c.eye[1]}, {"teeth.obj", &c.teeth}, {"tongue.obj", &c.tongue}};
  for (const auto& [name, mesh] : files)
    if (Status s = write_file(d + name, write_obj(*mesh)); !s) return fail(cmd, s.message);
  std::printf("eyes at (%.4f %.4f %.4f) r %.4f and (%.4f %.4f %.4f) r %.4f; mouth (%.4f %.4f %.4f) width %.4f\n",
              p.eye_center[0].x(), p.eye_center[0].y(), p.eye_center[0].z(), p.eye_radius[0], p.eye_center[1].x(),
              p.eye_center[1].y(), p.eye_center[1].z(), p.eye_radius[1], p.mouth_center.x(), p.mouth_center.y(),
              p.mouth_center.z(), p.mouth_width);
  std::printf("wrote %seye_left.obj eye_right.obj teeth.obj (%zu triangles) tongue.obj\n", d.c_str(),
              c.teeth.triangles.size());
  if (!args.has("render")) return 0;
  // The head (half transparent would need blending; drawn opaque, the eyes show
  // through the eye openings) with the textured components.
  Image eye_tex, teeth_tex;
  if (args.has("eye-texture"))
    if (Status s = load_image_file(args.get("eye-texture"), eye_tex, 3); !s) return fail(cmd, s.message);
  if (args.has("teeth-texture"))
    if (Status s = load_image_file(args.get("teeth-texture"), teeth_tex, 4); !s) return fail(cmd, s.message);
  CanonicalView view = CanonicalView::Front;
  if (Status s = parse_canonical_view(args.get("view", "front"), view); !s) return fail(cmd, s.message);
  TriMesh head = fitted;
  if (head.normals.empty()) head.normals = vertex_normals(head);
  TriMesh parts[4] = {c.eye[0], c.eye[1], c.teeth, c.tongue};
  parts[2].normals = vertex_normals(parts[2]);
  parts[3].normals = vertex_normals(parts[3]);
  auto setup = [&](Renderer& r) -> Status {
    DrawableHandle h;
    if (!args.has("no-head"))
      if (Status st = r.upload_mesh(head, h); !st) return st;
    for (int i = 0; i < 4; ++i) {
      DrawableHandle ph;
      if (Status st = r.upload_mesh(parts[i], ph); !st) return st;
      const Image& tex = i < 2 ? eye_tex : i == 2 ? teeth_tex : Image{};
      if (!tex.empty()) {
        TextureHandle t;
        Status st = r.upload_texture(tex, t);
        if (st) st = r.attach_texture(ph, t);
        if (!st) return st;
      }
    }
    return Status::success();
  };
  std::vector<Vec3> framed;
  for (int e = 0; e < 2; ++e)
    for (const Vec3& q : c.eye[e].positions) framed.push_back(q);
  for (const Vec3& q : c.teeth.positions) framed.push_back(q);
  auto camera_for = [&](float aspect) { return canonical_view(view, framed, aspect).matrices(aspect); };
  OffscreenOptions options;
  options.width = options.height = 768;
  options.supersample = 2;
  Image image;
  if (Status s = render_offscreen(setup, camera_for, options, image); !s) return fail(cmd, s.message);
  if (Status s = save_png_file(args.get("render"), image); !s) return fail(cmd, s.message);
  std::printf("rendered %s\n", args.get("render").c_str());
  return 0;
}

Registrar reg_components({"components", "likeness components [--head FILE.obj] --out DIR [--render PNG [--eye-texture PNG] [--teeth-texture PNG] [--view front|...] [--no-head]]",
                          "generic eyeballs, teeth arch and tongue placed into a head from its annotated vertices",
                          run_components});

}  // namespace
}  // namespace lk::cli

// likeness teeth-model: the paper's teeth model (billboard for the six front
// teeth, 3-D side teeth; core/components) with a teeth texture, rendered in
// front of a dark mouth-interior backdrop so transparent voids show dark.
namespace lk::cli {
namespace {

int run_teeth_model(const Args& args) {
  const char* cmd = "teeth-model";
  if (!only_known_options(cmd, args, {"out", "texture", "render", "view", "wireframe", "no-backdrop"})) return 2;
  if (!args.has("out") && !args.has("render")) {
    fail(cmd, "needs --out FILE.obj and/or --render FILE.png");
    return 2;
  }
  const TeethModel model = make_teeth_model();
  int parts[3] = {0, 0, 0};
  for (TeethPart p : model.part) ++parts[static_cast<int>(p)];
  std::printf("teeth model: %zu triangles (billboard %d, front volume %d, side teeth %d)\n",
              model.mesh.triangles.size(), parts[0], parts[1], parts[2]);
  if (args.has("out")) {
    if (Status s = write_file(args.get("out"), write_obj(model.mesh)); !s) return fail(cmd, s.message);
    std::printf("wrote %s\n", args.get("out").c_str());
  }
  if (!args.has("render")) return 0;
  Image tex;
  if (args.has("texture"))
    if (Status s = load_image_file(args.get("texture"), tex, 4); !s) return fail(cmd, s.message);
  CanonicalView view = CanonicalView::Front;
  if (Status s = parse_canonical_view(args.get("view", "front"), view); !s) return fail(cmd, s.message);
  TriMesh teeth = model.mesh;
  teeth.normals = vertex_normals(teeth);
  // The mouth's inside: a dark curved wall behind the arch.
  TriMesh backdrop;
  for (int i = 0; i <= 16; ++i) {
    const double a = -1.5 + 3.0 * i / 16;
    for (int j = 0; j < 2; ++j)
      backdrop.positions.push_back(Vec3(1.1 * std::sin(a), j ? 0.7 : -0.7, -0.1 - 0.8 * std::cos(a)));
  }
  for (int i = 0; i < 16; ++i) {
    backdrop.triangles.push_back({2 * i, 2 * i + 2, 2 * i + 3});
    backdrop.triangles.push_back({2 * i, 2 * i + 3, 2 * i + 1});
  }
  const bool with_backdrop = !args.has("no-backdrop");
  auto setup = [&](Renderer& r) -> Status {
    DrawableHandle h;
    if (Status st = r.upload_mesh(teeth, h); !st) return st;
    r.style(h)->specular = 0.25f;
    if (args.has("wireframe")) r.set_wireframe(h, true);
    if (!tex.empty()) {
      TextureHandle t;
      Status st = r.upload_texture(tex, t);
      if (st) st = r.attach_texture(h, t);
      if (!st) return st;
    } else {
      r.set_base_color(h, glm::vec3(0.92f, 0.90f, 0.84f));
    }
    if (with_backdrop) {
      DrawableHandle b;
      if (Status st = r.upload_mesh(backdrop, b); !st) return st;
      r.set_base_color(b, glm::vec3(0.22f, 0.06f, 0.07f));
      r.style(b)->specular = 0.0f;
    }
    return Status::success();
  };
  auto camera_for = [&](float aspect) { return canonical_view(view, teeth.positions, aspect).matrices(aspect); };
  OffscreenOptions options;
  options.width = options.height = 768;
  options.supersample = 2;
  Image image;
  if (Status s = render_offscreen(setup, camera_for, options, image); !s) return fail(cmd, s.message);
  if (Status s = save_png_file(args.get("render"), image); !s) return fail(cmd, s.message);
  std::printf("rendered %s (%s view%s)\n", args.get("render").c_str(), to_string(view),
              tex.empty() ? ", untextured" : "");
  return 0;
}

Registrar reg_teeth_model({"teeth-model",
                           "likeness teeth-model [--out teeth.obj] [--render PNG [--texture arch.png] [--view front|three-quarter|...] [--wireframe] [--no-backdrop]]",
                           "the paper's teeth model: billboard front teeth, 3-D side teeth, rendered with a teeth texture",
                           run_teeth_model});

}  // namespace
}  // namespace lk::cli
