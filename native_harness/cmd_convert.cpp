// likeness convert: reads any geometry the io module knows (PLY, OBJ+MTL,
// XYZ, legacy VTK) or any image, and writes it in the format named by the
// output's extension (.ply, .obj, .xyz; .png for images). Shows what a
// reader made of a file, and turns scanner data into something viewers open.
#include "command.h"

#include "io/io.h"

#include <cstdio>
#include <string>

namespace lk::cli {
namespace {

std::string extension(const std::string& path) {
  const size_t dot = path.find_last_of('.');
  const size_t slash = path.find_last_of('/');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  std::string e = path.substr(dot + 1);
  for (char& c : e) c = static_cast<char>(c >= 'A' && c <= 'Z' ? c - 'A' + 'a' : c);
  return e;
}

std::string file_name(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

int run_convert(const Args& args) {
  if (!only_known_options("convert", args, {"in", "out", "ascii"})) return 2;
  const std::string in = args.get("in"), out = args.get("out");
  if (in.empty() || out.empty()) return fail("convert", "needs --in FILE and --out FILE");
  const std::string in_ext = extension(in), out_ext = extension(out);
  const bool image_in = in_ext == "png" || in_ext == "jpg" || in_ext == "jpeg" || in_ext == "bmp" || in_ext == "tga";
  if (image_in || out_ext == "png") {
    if (out_ext != "png") return fail("convert", "images can only be written as .png");
    Image im;
    if (Status s = load_image_file(in, im); !s) return fail("convert", s.message);
    if (Status s = save_png_file(out, im); !s) return fail("convert", s.message);
    std::printf("%s: %dx%d, %d channels -> %s\n", in.c_str(), im.width, im.height, im.channels, out.c_str());
    return 0;
  }
  TriMesh mesh;
  PointCloud cloud;
  GeometryKind kind;
  if (Status s = load_geometry_file(in, mesh, cloud, kind); !s) return fail("convert", s.message);
  std::printf("%s: %s, %d vertices, %d triangles%s%s%s%s\n", in.c_str(),
              kind == GeometryKind::Mesh ? "mesh" : "point cloud", mesh.num_vertices(), mesh.num_triangles(),
              mesh.normals.empty() ? "" : ", normals", mesh.colors.empty() ? "" : ", colors",
              mesh.uvs.empty() ? "" : (mesh.uv_per_corner ? ", per-corner uvs" : ", per-vertex uvs"),
              mesh.texture_name.empty() ? "" : (", texture " + mesh.texture_name).c_str());
  Status s;
  if (out_ext == "ply") {
    s = kind == GeometryKind::Mesh ? write_file(out, write_ply(mesh, args.has("ascii")))
                                   : write_file(out, write_ply(cloud, args.has("ascii")));
  } else if (out_ext == "obj") {
    // The texture, when known, is referenced through an MTL beside the OBJ.
    if (!mesh.texture_name.empty()) {
      const std::string mtl = out.substr(0, out.size() - 4) + ".mtl";
      s = write_file(mtl, write_mtl(mesh.texture_name));
      if (s) s = write_file(out, write_obj(mesh, file_name(mtl)));
    } else {
      s = write_file(out, write_obj(mesh));
    }
  } else if (out_ext == "xyz") {
    s = write_file(out, write_xyz(cloud));
  } else {
    return fail("convert", "unknown output format '." + out_ext + "' (use .ply, .obj, .xyz or .png)");
  }
  if (!s) return fail("convert", s.message);
  std::printf("wrote %s\n", out.c_str());
  return 0;
}

Registrar reg({"convert", "likeness convert --in FILE --out FILE.{ply,obj,xyz,png} [--ascii]",
               "reads a scan/mesh/point cloud/image and writes it in another format", run_convert});

}  // namespace
}  // namespace lk::cli
