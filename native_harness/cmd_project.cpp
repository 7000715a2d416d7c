// likeness project: what a saved head project (core/project/project_file.h,
// written by `likeness fit --project` or the page's "Save project") holds,
// and its levels re-exported without fitting again.
#include "command.h"

#include "io/io.h"
#include "head/generic_head.h"
#include "project/export.h"
#include "project/fit_job.h"
#include "project/glb_export.h"
#include "project/pose.h"
#include "project/project_file.h"
#include "photos/landmarks.h"
#include "scan_axes_option.h"

#include <nlohmann/json.hpp>

#include <cctype>
#include <cstdio>
#include <set>
#include <sys/stat.h>

namespace lk::cli {
namespace {

const char* kName = "project";

Status read_project_file(const std::string& path, HeadProject& project) {
  Bytes bytes;
  if (Status st = read_file(path, bytes); !st.ok()) return st;
  return with_context(load_project(bytes.data(), bytes.size(), project), path);
}

int run_info(const std::string& path) {
  HeadProject p;
  if (Status st = read_project_file(path, p); !st.ok()) return fail(kName, st.message);
  const FitHeadResult& f = p.fit;
  const MultiresMesh& mr = f.multires;
  std::printf("%s: Likeness project, version %d%s\n", path.c_str(), p.file_version,
              p.file_version < kProjectFileVersion ? " (an older file: saving it again writes this build's version)" : "");
  std::printf("  scan: %zu points%s, unit %s (bbox diagonal %.4g scan units), %d points above the neck cut%s\n",
              p.scan.positions.size(),
              p.scan.faces.empty() ? "" : (", " + std::to_string(p.scan.faces.size()) + " triangles").c_str(),
              f.unit_to_metres == 1 ? "m" : f.unit_to_metres == 0.01 ? "cm" : "mm", f.bbox_diagonal,
              f.fitted_points, f.face_only ? ", a face-only capture" : "");
  for (const std::string& note : f.notes) std::printf("  note: %s\n", note.c_str());
  for (int l = 0; l <= mr.num_levels(); ++l)
    std::printf("  level %d%s: %d vertices, %zu triangles\n", l, l == 0 ? " (control mesh)" : "", mr.num_vertices(l),
                mr.triangles(l).size());
  for (const FitStageReport& s : f.stages)
    std::printf("  %-18s scan to surface: mean %.3f %%, max %.3f %% of the diagonal\n", s.name.c_str(),
                s.distance.mean_pct, s.distance.max_pct);
  std::printf("  animation: %zu control vertices rigged, pose %.2f\n", p.rig.moved.size(), p.pose);
  if (p.texture.empty())
    std::printf("  texture: none\n");
  else
    std::printf("  texture: %dx%d skin, chart on %zu vertices\n", p.texture.skin.width, p.texture.skin.height,
                p.texture.uvs.size());
  if (!p.parts.eye_texture.empty())
    std::printf("  eyes: %dx%d texture from the photo %s\n", p.parts.eye_texture.width, p.parts.eye_texture.height,
                p.parts.eye_source.c_str());
  if (!p.parts.teeth_texture.empty())
    std::printf("  teeth: %dx%d texture from the photo %s\n", p.parts.teeth_texture.width,
                p.parts.teeth_texture.height, p.parts.teeth_source.c_str());
  const ProjectInputs& in = p.inputs;
  for (const ProjectPhoto& ph : in.photos) {
    ImageInfo image;
    LandmarkPhoto points;
    const bool decoded = inspect_image(ph.bytes.data(), ph.bytes.size(), image).ok();
    std::string about = "no face points";
    if (!ph.points.empty() && parse_landmarks_json(ph.points, points).ok()) {
      const nlohmann::json doc = nlohmann::json::parse(ph.points, nullptr, false);
      const auto c = doc.find("corrected");
      const std::size_t moved = c != doc.end() && c->is_array() ? c->size() : 0;
      about = std::to_string(points.num_present()) + " face points" +
              (moved ? " (" + std::to_string(moved) + " moved by hand)" : "");
    }
    std::printf("  photo %s: %s, %s %dx%d, %zu bytes, %s\n", ph.name.c_str(), ph.role.c_str(),
                decoded ? image.format : "?", image.width, image.height, ph.bytes.size(), about.c_str());
  }
  if (!in.page_options.empty()) std::printf("  page options: %s\n", in.page_options.c_str());
  return 0;
}

// The kept photos and their face points as files in dir (NAME and
// NAME.points.json), and the `likeness photos` line that makes the head
// again from the face photos that have points. Two photos of the same name
// (from different folders; compared without case, as some file systems do)
// would overwrite each other: a later one is written as K_NAME, K its
// place in the project, and the line says so.
int run_extract_photos(const std::string& path, const std::string& dir) {
  HeadProject p;
  if (Status st = read_project_file(path, p); !st.ok()) return fail(kName, st.message);
  if (p.inputs.photos.empty()) return fail(kName, path + " keeps no photos (made before version 3, or from a scan alone)");
  ::mkdir(dir.c_str(), 0755);
  std::string photos, points;
  std::set<std::string> taken;  // lower-case file names written so far
  const auto lower = [](std::string s) {
    for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return s;
  };
  const auto free_name = [&](const std::string& n) { return !taken.count(lower(n)) && !taken.count(lower(n + ".points.json")); };
  for (size_t k = 0; k < p.inputs.photos.size(); ++k) {
    const ProjectPhoto& ph = p.inputs.photos[k];
    std::string name = ph.name;
    for (size_t prefix = k + 1; !free_name(name); ++prefix) name = std::to_string(prefix) + "_" + ph.name;
    taken.insert(lower(name));
    taken.insert(lower(name + ".points.json"));
    const std::string file = dir + "/" + name;
    if (Status st = write_file(file, ph.bytes); !st.ok()) return fail(kName, st.message);
    if (name != ph.name)
      std::printf("wrote %s (%s; photo %zu, named %s like an earlier one: renamed, not to overwrite it)\n", file.c_str(),
                  ph.role.c_str(), k + 1, ph.name.c_str());
    else
      std::printf("wrote %s (%s)\n", file.c_str(), ph.role.c_str());
    if (ph.points.empty()) continue;
    const std::string json_file = dir + "/" + name + ".points.json";
    if (Status st = write_file(json_file, Bytes(ph.points.begin(), ph.points.end())); !st.ok()) return fail(kName, st.message);
    std::printf("wrote %s\n", json_file.c_str());
    if (ph.role == "face") {
      photos += " " + file;
      points += " " + json_file;
    }
  }
  if (!points.empty()) std::printf("make the head again: likeness photos --photos%s --points%s --out DIR\n", photos.c_str(), points.c_str());
  return 0;
}

// The eyes' and teeth's textures of an export: a file given, else the
// project's own (made by the page from an eye or smile photo), else (with a
// head folder) DIR/eye.png and DIR/teeth.png where they are (what `likeness
// eye --out` and `likeness teeth --generic-out` write), else the generic
// ones, with a note saying which.
struct PartTextures {
  std::string eye, teeth;  // files to read; empty: generic
};

Status part_textures(const PartTextures& files, const ProjectParts& kept, GlbExportOptions& o) {
  use_generic_part_textures(o);
  const std::pair<const std::string*, Image*> parts[2] = {{&files.eye, &o.eye_texture}, {&files.teeth, &o.teeth_texture}};
  const std::pair<const Image*, const std::string*> in_project[2] = {{&kept.eye_texture, &kept.eye_source},
                                                                     {&kept.teeth_texture, &kept.teeth_source}};
  const char* what[2] = {"eye", "teeth"};
  for (int k = 0; k < 2; ++k) {
    if (parts[k].first->empty() && !in_project[k].first->empty()) {
      // The project keeps the texture the page made from a photo.
      *parts[k].second = *in_project[k].first;
      std::printf("%s texture: the project's, from the photo %s (%dx%d)\n", what[k], in_project[k].second->c_str(),
                  parts[k].second->width, parts[k].second->height);
      continue;
    }
    if (parts[k].first->empty()) {
      std::printf("note: the generic %s texture\n", what[k]);
      continue;
    }
    // The eyeball's texture RGB; the teeth's RGBA (their voids transparent).
    if (Status st = load_image_file(*parts[k].first, *parts[k].second, k == 0 ? 3 : 4); !st.ok()) return st;
    std::printf("%s texture: %s (%dx%d)\n", what[k], parts[k].first->c_str(), parts[k].second->width,
                parts[k].second->height);
  }
  return Status::success();
}

// The head at level with the eyes' and teeth's textures and every shape of
// the muscle layer, at rest (avatar tools pose it), with the clips unless
// animations is false.
int write_glb(const char* cmd, HeadProject& p, int level, const std::string& out, const PartTextures& textures = {},
              bool animations = true, const Speech& say = {}) {
  GenericHead generic;
  Status st = load_generic_head(generic);
  if (!st) return fail(cmd, st.message);
  GlbExportOptions o;
  o.level = level;
  o.animations = animations;
  o.say = say;
  if (st = part_textures(textures, p.parts, o); !st) return fail(cmd, st.message);
  Bytes bytes;
  GlbExportReport r;
  st = export_glb(p, generic, o, bytes, &r);
  if (st) st = write_file(out, bytes);
  if (!st) return fail(cmd, st.message);
  std::string clips;
  for (const std::string& a : r.animations) clips += (clips.empty() ? "" : ", ") + a;
  std::printf("wrote %s: level %d (%d vertices, %d triangles)%s, %zu nodes, %zu bytes, at rest, animations: %s\n",
              out.c_str(), r.level, r.head_vertices, r.head_triangles, p.texture.empty() ? "" : ", textured",
              r.nodes.size(), bytes.size(), clips.empty() ? "none" : clips.c_str());
  return 0;
}

int run_export(const std::string& path, const Args& args) {
  const std::string out = args.get("out"), format = args.get("format", "obj");
  if (out.empty()) return fail(kName, "export needs --out FILE");
  HeadProject p;
  if (Status st = read_project_file(path, p); !st.ok()) return fail(kName, st.message);
  int level = -1;
  double pose = p.pose;
  if (!args.get_int("level", -1, level) || !args.get_double("pose", p.pose, pose)) return 2;
  if (level < 0) level = p.fit.multires.num_levels();
  if (Status st = pose_project(p, pose); !st.ok()) return fail(kName, st.message);
  const ExportFrame frame = args.has("scan-frame") ? ExportFrame::Scan : ExportFrame::Head;
  Status st;
  if (format == "obj" || format == "ply") {
    Bytes bytes;
    st = export_level(p, level, format == "obj" ? LevelFormat::Obj : LevelFormat::Ply, frame, bytes);
    if (st) st = write_file(out, bytes);
    if (!st) return fail(kName, st.message);
    std::printf("wrote %s: level %d, pose %.2f, %s frame\n", out.c_str(), level, p.pose,
                frame == ExportFrame::Scan ? "scan" : "head");
    return 0;
  }
  if (format == "glb") return write_glb(kName, p, args.has("level") ? level : 2, out);
  if (format != "textured") return fail(kName, "--format takes obj, ply, textured or glb");
  // OUT.obj with OUT.mtl and OUT.png beside it.
  const std::string stem = out.size() > 4 && out.compare(out.size() - 4, 4, ".obj") == 0 ? out.substr(0, out.size() - 4) : out;
  const std::string base = stem.substr(stem.find_last_of('/') + 1);
  TexturedFiles files;
  st = export_textured(p, level, base, frame, files);
  if (st) st = write_file(stem + ".obj", files.obj);
  if (st) st = write_file(stem + ".mtl", files.mtl);
  if (st) st = write_file(stem + ".png", files.png);
  if (!st) return fail(kName, st.message);
  std::printf("wrote %s.obj, %s.mtl, %s.png: level %d, pose %.2f, %s frame\n", stem.c_str(), stem.c_str(),
              stem.c_str(), level, p.pose, frame == ExportFrame::Scan ? "scan" : "head");
  return 0;
}

// The project's kept scan fitted again (its options; --levels, --up and
// --facing replace theirs), saved as a new project file: a head made in the page is fitted
// natively from what its project file holds.
int run_refit(const std::string& path, const Args& args) {
  const std::string out = args.get("out");
  if (out.empty()) return fail(kName, "refit needs --out FILE.likeness.glb");
  int levels = 0;
  if (!args.get_int("levels", 0, levels, 1, 4)) return 2;
  RefitChanges changes{levels, {}, {}};
  if (!get_scan_axes(kName, args, changes.up, changes.facing)) return 2;
  HeadProject p;
  if (Status st = read_project_file(path, p); !st.ok()) return fail(kName, st.message);
  GenericHead generic;
  if (Status st = load_generic_head(generic); !st.ok()) return fail(kName, st.message);
  HeadProject refitted;
  Status st = refit_project(p, generic, changes, refitted);
  if (!st) return fail(kName, with_context(st, path).message);
  for (const std::string& note : refitted.fit.notes) std::printf("note: %s\n", note.c_str());
  for (const FitStageReport& s : refitted.fit.stages)
    std::printf("%-18s scan to surface: mean %.4f %%, max %.3f %% of the diagonal\n", s.name.c_str(),
                s.distance.mean_pct, s.distance.max_pct);
  Bytes bytes;
  st = save_project(refitted, bytes);
  if (st) st = write_file(out, bytes);
  if (!st) return fail(kName, st.message);
  std::printf("wrote %s: %d levels, fitted again to the %zu scan points the project keeps\n", out.c_str(),
              refitted.fit.multires.num_levels(), refitted.scan.positions.size());
  return 0;
}

int run_project(const Args& args) {
  // Its two positional words (info|export|refit FILE) are checked below.
  if (!only_known_options(kName, args, {"level", "levels", "up", "facing", "format", "out", "pose", "scan-frame", "extract-photos"}, 2)) return 2;
  const std::string verb = args.positional.empty() ? "" : args.positional[0];
  if (args.positional.size() != 2 || (verb != "info" && verb != "export" && verb != "refit")) {
    fail(kName, "give `info FILE`, `export FILE --out PATH` or `refit FILE --out FILE` (see likeness project --help)");
    return 2;
  }
  if (verb == "info") {
    const int rc = run_info(args.positional[1]);
    return rc != 0 || !args.has("extract-photos") ? rc : run_extract_photos(args.positional[1], args.get("extract-photos"));
  }
  return verb == "export" ? run_export(args.positional[1], args) : run_refit(args.positional[1], args);
}

// likeness export: the GLB for avatar tools from a `likeness fit` or
// `likeness photos` folder (its head.likeness.glb) or a project file.
int run_export_head(const Args& args) {
  const char* cmd = "export";
  if (!only_known_options(cmd, args, {"head", "out", "level", "eye-texture", "teeth-texture", "no-animations", "say"})) return 2;
  std::string head = args.get("head");
  const std::string out = args.get("out");
  if (head.empty() || out.empty())
    return fail(cmd, "needs --head DIR (a likeness fit or likeness photos folder) or FILE.likeness.glb, and --out FILE.glb");
  struct stat info;
  const bool folder = ::stat(head.c_str(), &info) == 0 && S_ISDIR(info.st_mode);
  if (folder) head += "/head.likeness.glb";
  if (folder && ::stat(head.c_str(), &info) != 0)
    return fail(cmd, head + " not found: `likeness fit` and `likeness photos` write it into their folder (not with "
                     "--no-project); fit again, or give a project file saved by the page");
  int level = 2;
  if (!args.get_int("level", 2, level, 0, 5)) return 2;
  HeadProject p;
  if (Status st = read_project_file(head, p); !st.ok()) return fail(cmd, st.message);
  if (Status st = rest_pose(p); !st.ok()) return fail(cmd, st.message);
  PartTextures textures{args.get("eye-texture"), args.get("teeth-texture")};
  const std::string dir = head.substr(0, head.find_last_of('/') + 1);
  // The folder's files stand in only where the project keeps no texture from a photo.
  const bool kept[2] = {!p.parts.eye_texture.empty(), !p.parts.teeth_texture.empty()};
  int k = 0;
  for (auto [file, name] : {std::pair{&textures.eye, "eye.png"}, std::pair{&textures.teeth, "teeth.png"}})
    if (!kept[k++] && file->empty() && folder && ::stat((dir + name).c_str(), &info) == 0) *file = dir + name;
  // The words to say come as the page's speech document (scripts/say
  // writes it from the words with the page's own lip-sync reader).
  Speech say;
  if (args.has("say")) {
    const std::string file = args.get("say");
    Bytes bytes;
    if (file.empty()) return fail(cmd, "--say needs a speech file: scripts/say \"WORDS\" > say.json, then --say say.json");
    if (Status st = read_file(file, bytes, kMaxSpeechBytes); !st)
      return fail(cmd, st.message + " (--say takes the file scripts/say \"WORDS\" writes, not the words)");
    if (Status st = parse_speech_json(std::string(bytes.begin(), bytes.end()), say); !st) return fail(cmd, file + ": " + st.message);
  }
  return write_glb(cmd, p, level, out, textures, !args.has("no-animations"), say);
}

const Registrar export_reg({"export", "likeness export --head DIR|FILE.likeness.glb --out FILE.glb [--level L] "
                            "[--eye-texture PNG] [--teeth-texture PNG] [--no-animations] [--say SAY.json]",
                            "the head as a GLB for avatar tools and viewers (level L, default 2): its skin, eyes, teeth "
                            "and tongue, the 77 expressions, ARKit shapes and visemes as morph targets, a small "
                            "skeleton, the Talk, Blink and Gaze clips as glTF animations (and with --say the words "
                            "as a Say clip: SAY.json is what scripts/say \"WORDS\" writes, the page's reading of them); from a likeness fit or likeness "
                            "photos folder or a project file. The eyes and teeth take DIR/eye.png (likeness eye --out) "
                            "and DIR/teeth.png (likeness teeth --generic-out) where they are, else the generic textures; "
                            "a project saved by the page with eye or smile photos keeps their textures, used first",
                            run_export_head});

const Registrar reg({kName,
                     "likeness project info FILE [--extract-photos DIR] | likeness project export FILE --out PATH [--format obj|ply|textured|glb] "
                     "[--level L] [--pose A] [--scan-frame] | likeness project refit FILE --out FILE.likeness.glb [--levels L] [--up AXIS] [--facing AXIS]",
                     "what a saved head project holds (with --extract-photos its photos and their face points written into DIR, "
                     "for likeness photos); its levels re-exported without fitting again; its kept scan "
                     "fitted again (--up and --facing, as in likeness fit, say anew which way the scan is turned)", run_project});

}  // namespace
}  // namespace lk::cli
