// Writes the fuzzers' seed corpus: tiny valid files of every format, made by
// our own writers (write_ply, write_obj, write_xyz, write_png,
// format_correspondences) and, for the formats we only read (VTK) or whose
// encoder is not ours (JPEG, BMP, TGA), by the smallest text we can write by
// hand or Debian's stb_image_write. Usage: make_seeds OUT_DIR; files go to
// OUT_DIR/<target>/.
#include "../io/exif_builder.h"
#include "io/io.h"
#include "mesh/primitives.h"
#include "photos/landmarks.h"
#include "texture/correspondences.h"

#include <sys/stat.h>

#include <cstdio>
#include <string>
#include <utility>

#define STB_IMAGE_WRITE_STATIC
#define STB_IMAGE_WRITE_IMPLEMENTATION
#if defined(__clang__)
#pragma clang diagnostic push
#pragma clang diagnostic ignored "-Wunused-function"
#pragma clang diagnostic ignored "-Wmissing-field-initializers"
#endif
#include <stb/stb_image_write.h>
#if defined(__clang__)
#pragma clang diagnostic pop
#endif

using namespace lk;

namespace {

std::string g_out;
int g_failures = 0;

void put(const std::string& target, const std::string& name, const void* data, size_t size) {
  const std::string dir = g_out + "/" + target;
  ::mkdir(g_out.c_str(), 0755);
  ::mkdir(dir.c_str(), 0755);
  if (!write_file(dir + "/" + name, data, size)) ++g_failures;
}
void put(const std::string& target, const std::string& name, const std::string& s) {
  put(target, name, s.data(), s.size());
}
void put(const std::string& target, const std::string& name, const Bytes& b) { put(target, name, b.data(), b.size()); }

void append(void* context, void* data, int size) {
  Bytes* out = static_cast<Bytes*>(context);
  out->insert(out->end(), static_cast<std::uint8_t*>(data), static_cast<std::uint8_t*>(data) + size);
}

// A 3x3-vertex grid with normals, colors and uvs (and a per-corner variant).
TriMesh small_grid(bool corner_uvs) {
  TriMesh m = make_regular_grid(3, 3);
  for (Vec3& p : m.positions) {
    p.z() = 0.25 * p.x() * p.y();
    m.normals.push_back(Vec3(0, 0, 1));
    m.colors.push_back(Vec3(p.x() / 2, p.y() / 2, 0.5));
    m.uvs.push_back(Vec2(p.x() / 2, p.y() / 2));
  }
  if (corner_uvs) {
    std::vector<Vec2> corners;
    for (const Tri& t : m.triangles)
      for (int k = 0; k < 3; ++k) corners.push_back(m.uvs[t[k]]);
    m.uvs = corners;
    m.uv_per_corner = true;
  }
  return m;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: make_seeds OUT_DIR\n");
    return 2;
  }
  g_out = argv[1];
  const TriMesh grid = small_grid(false), corner = small_grid(true);
  TriMesh bare = make_regular_grid(2, 2);
  const PointCloud cloud = to_point_cloud(grid);
  PointCloud bare_cloud;
  bare_cloud.positions = cloud.positions;

  {  // outline: a head-like white ellipse on black (a mask), and on a plain grey backdrop (a photo)
    Image mask = Image::make(64, 80, 1, 0), photo = Image::make(64, 80, 3, 90);
    for (int y = 0; y < 80; ++y)
      for (int x = 0; x < 64; ++x) {
        const double u = (x - 32) / 20.0, v = (y - 36) / 28.0;
        if (u * u + v * v > 1) continue;
        mask.pixels[static_cast<size_t>(y) * 64 + x] = 255;
        for (int c = 0; c < 3; ++c) photo.pixels[(static_cast<size_t>(y) * 64 + x) * 3 + c] = static_cast<std::uint8_t>(200 - 40 * c);
      }
    put("outline", "mask.png", write_png(mask));
    put("outline", "photo.png", write_png(photo));
  }
  put("ply", "grid_binary.ply", write_ply(grid));
  put("ply", "grid_ascii.ply", write_ply(grid, true));
  put("ply", "corner_uvs.ply", write_ply(corner));
  put("ply", "bare_ascii.ply", write_ply(bare, true));
  put("ply", "cloud.ply", write_ply(cloud));
  // fuzz_ply_stream: a chunk-pattern byte, then the file.
  for (const auto& [name, file] : {std::pair<const char*, Bytes>{"grid_binary", write_ply(grid)},
                                   {"grid_ascii", write_ply(grid, true)},
                                   {"corner_uvs", write_ply(corner)}}) {
    for (std::uint8_t pattern : {0, 3, 7, 11}) {
      Bytes seed{pattern};
      seed.insert(seed.end(), file.begin(), file.end());
      put("ply_stream", std::string(name) + "_" + std::to_string(pattern) + ".ply", seed);
    }
  }

  put("obj", "grid.obj", write_obj(grid));
  put("obj", "corner_uvs.obj", write_obj(corner));
  put("obj", "bare.obj", write_obj(bare));
  put("obj", "with_mtl.obj", write_obj(corner, "m.mtl") + "\n#mtl\n" + write_mtl("skin.png"));

  put("xyz", "points.xyz", write_xyz(bare_cloud));
  put("xyz", "normals.xyz", write_xyz(PointCloud{cloud.positions, cloud.normals, {}, {}}));
  put("xyz", "colors.xyz", write_xyz(PointCloud{cloud.positions, {}, cloud.colors, {}}));
  put("xyz", "both.xyz", write_xyz(cloud));
  put("xyz", "leica.pts", "3\n0 0 0 10\n1 0 0 20\n0 1 0 30\n");

  // Legacy VTK: we have no writer, so the smallest files of each section.
  put("vtk", "polygons.vtk",
      "# vtk DataFile Version 3.0\nt\nASCII\nDATASET POLYDATA\nPOINTS 5 float\n0 0 0 1 0 0 1 1 0 0 1 0 2 0 0\n"
      "POLYGONS 1 5\n4 0 1 2 3\nTRIANGLE_STRIPS 1 4\n3 1 4 2\nPOINT_DATA 5\nSCALARS s float 1\n"
      "LOOKUP_TABLE default\n1 2 3 4 5\nTEXTURE_COORDINATES t 2 float\n0 0 1 0 1 1 0 1 0.5 0.5\n");
  put("vtk", "attributes.vtk",
      "# vtk DataFile Version 4.2\nt\nASCII\nDATASET POLYDATA\nPOINTS 3 double\n0 0 0 1 0 0 0 1 0\n"
      "POLYGONS 1 4\n3 0 1 2\nCELL_DATA 1\nCOLOR_SCALARS c 3\n1 0 0\nPOINT_DATA 3\n"
      "NORMALS n float\n0 0 1 0 0 1 0 0 1\nCOLOR_SCALARS c 4\n1 0 0 1 0 1 0 1 0 0 1 1\n"
      "FIELD f 1\na 2 3 float\n1 2 3 4 5 6\n");
  put("vtk", "offsets.vtk",
      "# vtk DataFile Version 5.1\nt\nASCII\nDATASET POLYDATA\nPOINTS 4 float\n0 0 0 1 0 0 1 1 0 0 1 0\n"
      "POLYGONS 2 6\nOFFSETS vtktypeint64\n0 3 6\nCONNECTIVITY vtktypeint64\n0 1 2 0 2 3\n");

  // fuzz_scan_stream: a name byte (0 .ply, 1 .obj, 2 .xyz, 3 .pts, 4 .vtk,
  // 5 none), a cut-count byte, the cuts (two bytes each), then the file.
  {
    const std::string grid_obj = write_obj(corner), grid_xyz = write_xyz(cloud);
    const std::string vtk = "# vtk DataFile Version 3.0\nt\nASCII\nDATASET POLYDATA\nPOINTS 4 float\n"
                            "0 0 0 1 0 0 1 1 0 0 1 0\nPOLYGONS 1 5\n4 0 1 2 3\n";
    const Bytes ply = write_ply(grid), ply_ascii = write_ply(grid, true);
    const struct {
      std::uint8_t name;
      const char* label;
      Bytes file;
    } files[] = {{0, "ply", ply}, {5, "ply_ascii", ply_ascii}, {1, "obj", Bytes(grid_obj.begin(), grid_obj.end())},
                 {5, "obj", Bytes(grid_obj.begin(), grid_obj.end())}, {2, "xyz", Bytes(grid_xyz.begin(), grid_xyz.end())},
                 {3, "pts", Bytes{'2', '\n', '0', ' ', '0', ' ', '0', ' ', '9', '\n', '1', ' ', '0', ' ', '0', ' ', '9', '\n'}},
                 {4, "vtk", Bytes(vtk.begin(), vtk.end())}};
    for (const auto& f : files)
      for (int cuts : {0, 1, 5}) {
        Bytes seed{f.name, static_cast<std::uint8_t>(cuts)};
        for (int k = 0; k < cuts; ++k) {
          const size_t at = f.file.size() * (k + 1) / (cuts + 1) + k;  // inside lines and numbers
          seed.push_back(static_cast<std::uint8_t>(at >> 8));
          seed.push_back(static_cast<std::uint8_t>(at & 255));
        }
        seed.insert(seed.end(), f.file.begin(), f.file.end());
        put("scan_stream", std::string(f.label) + "_" + std::to_string(f.name) + "_" + std::to_string(cuts), seed);
      }
  }

  // Images: ours (PNG) and stb_image_write's (JPEG, BMP, TGA), 6x4 pixels.
  for (int channels : {1, 3, 4}) {
    Image im = Image::make(6, 4, channels);
    for (size_t i = 0; i < im.pixels.size(); ++i) im.pixels[i] = static_cast<std::uint8_t>(i * 37);
    const std::string c = std::to_string(channels);
    put("image", "c" + c + ".png", write_png(im));
    Bytes jpg, bmp, tga;
    stbi_write_jpg_to_func(append, &jpg, im.width, im.height, channels, im.pixels.data(), 90);
    stbi_write_bmp_to_func(append, &bmp, im.width, im.height, channels, im.pixels.data());
    stbi_write_tga_to_func(append, &tga, im.width, im.height, channels, im.pixels.data());
    put("image", "c" + c + ".jpg", jpg);
    if (channels == 3) {  // EXIF: a camera's focal tags, in both byte orders, on stb's picture
      for (bool big : {false, true}) {
        exif_test::TiffBuilder tags = exif_test::camera_tags(big);
        tags.ifd0.back() = tags.shrt(0x0112, 6);  // orientation: turned 90 degrees, which read_image undoes
        Bytes tagged = exif_test::jpeg_with(tags.build());
        tagged.resize(tagged.size() - 14);  // the hand-made JPEG's stub tables, scan and end: stb's file follows
        tagged.insert(tagged.end(), jpg.begin() + 2, jpg.end());
        put("exif", std::string(big ? "big" : "little") + ".jpg", tagged);
        put("image", std::string("exif_") + (big ? "big" : "little") + ".jpg", tagged);
      }
      put("exif", "plain.jpg", jpg);
    }
    put("image", "c" + c + ".bmp", bmp);
    put("image", "c" + c + ".tga", tga);
  }

  // Points files: what the page writes after the user clicks.
  std::vector<Correspondence> points;
  for (int i = 0; i < 6; ++i) {
    Correspondence c;
    c.pixel = Vec2(10.5 * i, 7.25 * i + 3);
    c.point = Vec3(0.1 * i, -0.2 * i, 1.0 + 0.05 * i);
    points.push_back(c);
  }
  put("points", "six.txt", format_correspondences(points));
  put("points", "commented.txt", "# u v X Y Z\n\n12 34 0.5 0.25 -1 # nose tip\n1,2,3,4,5\n");

  // Landmark files and a landmark map, as likeness synth-photos writes them.
  LandmarkPhoto photo;
  photo.name = "view_00.png";
  photo.width = 120;
  photo.height = 160;
  photo.detector = "mediapipe-face-mesh";
  LandmarkMap map;
  map.detector = photo.detector;
  for (int i = 0; i < 8; ++i) {
    photo.points.push_back(Vec2(10 + 12.5 * i, 150 - 17.25 * i));
    photo.present.push_back(i % 3 != 1);
    map.points.push_back(Vec3(0.01 * i, -0.02 * i, 0.1 + 0.005 * i));
    map.present.push_back(i % 4 != 2);
  }
  put("landmarks", "view_00.json", landmarks_to_json(photo));
  put("landmarks", "map.json", landmark_map_to_json(map));

  // A speech document as scripts/say writes it ("Hello, nice to meet you.").
  put("speech", "hello.json",
      R"({"format":"likeness-speech","version":1,"lipsync":"@met4citizen/talkinghead 1.7.0 lipsync-en",)"
      R"("text":"Hello, nice to meet you.","visemes":["I","E","nn","O","sil","nn","aa","SS","DD","U","PP","I","DD","I","U"],)"
      R"("times":[0,0.92,1.82,2.7,3.66,6.16,7.04,7.99,10.22,11.27,13.22,14.3,15.22,17.27,18.19],)"
      R"("durations":[0.92,0.9,0.88,0.96,2.5,0.88,0.95,1.23,1.05,0.95,1.08,0.92,1.05,0.92,0.95]})");

  if (g_failures) {
    std::fprintf(stderr, "make_seeds: %d files could not be written under %s\n", g_failures, g_out.c_str());
    return 1;
  }
  return 0;
}
