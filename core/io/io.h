// Readers and writers for meshes, point clouds and images. Parsing works on
// bytes in memory (the web app hands us the bytes of a dropped file); the
// *_file helpers are thin wrappers for the native harness. A scan can also
// be read from chunks pushed one after another (scan_stream.h).
//
// Every reader validates what it reads and fails with a Status whose message
// names the problem (truncated data, wrong counts, NaN/inf, unsupported
// property, empty input, declared sizes beyond the bytes given). No reader
// allocates more than the input can justify, so a huge declared count in a
// small file cannot exhaust memory or hang.
#pragma once
#include "common/status.h"
#include "image/image.h"
#include "mesh/tri_mesh.h"

#include <climits>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace lk {

using Bytes = std::vector<std::uint8_t>;

// The largest input of each kind, one constant per kind used on every path:
// read_file refuses a bigger file from its size (stat) before reading a byte,
// and the readers refuse bigger buffers (bytes from the page) before parsing.
// 2 GiB - 1 because line numbers and stb_image's lengths are ints.
constexpr size_t kMaxGeometryBytes = size_t(INT_MAX);
constexpr size_t kMaxImageBytes = size_t(INT_MAX);
constexpr size_t kMaxMaterialBytes = size_t(1) << 20;  // an OBJ's MTL

// Which kind of geometry a file held.
enum class GeometryKind { Mesh, PointCloud };

// PLY: ascii, binary_little_endian, binary_big_endian. Vertex properties
// x y z (float/double/int types), optional nx ny nz, red green blue (uchar or
// float); faces as "vertex_indices"/"vertex_index" lists (polygons are
// fan-triangulated). A PLY without faces is a point cloud.
Status read_ply(const std::uint8_t* data, size_t size, TriMesh& mesh, GeometryKind& kind);
// Writes binary little-endian PLY (ascii when ascii is true). Faces are
// written when the mesh has triangles; normals and colors when present.
Bytes write_ply(const TriMesh& mesh, bool ascii = false);
Bytes write_ply(const PointCloud& cloud, bool ascii = false);

// OBJ: v, vn, vt, f (polygons fan-triangulated, negative indices allowed),
// mtllib/usemtl recorded (texture_name from the MTL's map_Kd when given).
// Per-corner uvs (3 * #F) unless every vertex uses a single uv throughout;
// vn normals are made unit length, then averaged per vertex. Unknown
// statements made of lowercase letters are skipped; any other line start is
// rejected as "not OBJ".
Status read_obj(const std::uint8_t* data, size_t size, TriMesh& mesh, GeometryKind& kind,
                const std::string& mtl_text = "");
// The file name after "mtllib" (empty if none), so a caller can fetch the MTL.
std::string obj_mtllib(const std::uint8_t* data, size_t size);
// OBJ text; with a material name, writes "mtllib <mtl_file>" and "usemtl".
std::string write_obj(const TriMesh& mesh, const std::string& mtl_file = "");
// MTL text with one material whose map_Kd is texture_file.
std::string write_mtl(const std::string& texture_file);

// XYZ: one point per line, "x y z" optionally followed by "nx ny nz" (and/or
// "r g b"); '#' and '//' comments; space, tab or comma separated. Also Leica
// .pts: a point-count line, then "x y z intensity [r g b]".
// Six columns are normals if every extra triple has unit length, else colors
// (0..255 if any exceeds 1); with nine, the unit-length triple is the normal.
Status read_xyz(const std::uint8_t* data, size_t size, PointCloud& cloud);
// "x y z [nx ny nz] [r g b]" with colors as 0..255 integers.
std::string write_xyz(const PointCloud& cloud);

// Legacy VTK, ASCII DATASET POLYDATA only (e.g. Cyberware scans in VTKData):
// POINTS, POLYGONS (fan-triangulated), TRIANGLE_STRIPS, and point NORMALS,
// TEXTURE_COORDINATES (per-vertex uvs) and COLOR_SCALARS; other sections are
// skipped by their declared sizes. Versions up to 4.2 and 5.1 (OFFSETS /
// CONNECTIVITY) cell layouts.
Status read_vtk(const std::uint8_t* data, size_t size, TriMesh& mesh, GeometryKind& kind);

// Picks the reader from the file name's extension (.ply .obj .xyz .vtk;
// .txt .pts .asc as XYZ) or, when unknown, from the first bytes. Both mesh
// and cloud receive the vertices (with normals/colors); mesh also the faces.
Status read_geometry(const std::string& name, const std::uint8_t* data, size_t size,
                     TriMesh& mesh, PointCloud& cloud, GeometryKind& kind);

// Images: JPEG (baseline, progressive) and PNG only, decoded by stb_image
// behind our own checks (image_io.cpp). Other formats are refused by name
// from their magic bytes ("this is a PGM image; Likeness reads JPEG and
// PNG", Unsupported). Before decoding, the segments / chunks are walked with
// every length checked, and the declared size is refused over max_pixels
// (TooLarge) or over what the bytes can hold (a JPEG needs a bit per 8x8
// block, deflate inflates at most 1032:1: InvalidInput). A JPEG whose data
// ends before its end-of-image marker, or a PNG before IEND, is Truncated.
// JPEG EXIF orientation is applied (width and height swap for 5-8).
// want_channels 0 keeps the file's channels (gray+alpha becomes RGBA).
Status read_image(const std::uint8_t* data, size_t size, Image& image,
                  int want_channels = 0, size_t max_pixels = 64u << 20);

// What read_image checks before decoding, without decoding: the format, the
// structure, the limits and the EXIF orientation. The page runs it before
// handing the bytes to the browser's own decoder.
struct ImageInfo {
  const char* format = "";                 // "JPEG" or "PNG"
  int stored_width = 0, stored_height = 0;  // as the file stores the pixels
  int orientation = 1;                      // EXIF orientation 1..8 (1: upright)
  int width = 0, height = 0;                // as shown: swapped for orientations 5..8
};
Status inspect_image(const std::uint8_t* data, size_t size, ImageInfo& info, size_t max_pixels = 64u << 20);

// For a JPEG that inspect_image accepts: a copy with one-bits after each
// scan's data. A whole JPEG decodes to the same pixels as its probe; one
// whose scan data ends early (cut, with an end-of-image marker after) does
// not, since decoders silently fill its missing blocks. read_image compares
// the two itself; the page does it with the browser's decoder. Empty for a
// PNG (a cut deflate stream already fails in the decoder).
Status jpeg_truncation_probe(const std::uint8_t* data, size_t size, Bytes& probe);
// Empty when the image is empty or its pixel count disagrees with its size.
Bytes write_png(const Image& image);

// File helpers (native only). Files larger than max_bytes are refused with
// TooLarge from their size, before being read; load_geometry_file and
// load_image_file use the constants above. Every message starts with the
// path ("scan.ply: truncated: ..."). For an OBJ, load_geometry_file also
// reads the MTL named by mtllib (next to the OBJ) and sets texture_name to
// the map_Kd path resolved against the MTL's folder.
Status read_file(const std::string& path, Bytes& out, size_t max_bytes = kMaxGeometryBytes);
Status write_file(const std::string& path, const void* data, size_t size);
Status write_file(const std::string& path, const std::string& text);
Status write_file(const std::string& path, const Bytes& bytes);
Status load_geometry_file(const std::string& path, TriMesh& mesh, PointCloud& cloud, GeometryKind& kind);
Status load_mesh_file(const std::string& path, TriMesh& mesh);         // fails if not a mesh
Status load_point_cloud_file(const std::string& path, PointCloud& cloud);  // any geometry's vertices
Status load_image_file(const std::string& path, Image& image, int want_channels = 0);
Status save_png_file(const std::string& path, const Image& image);

PointCloud to_point_cloud(const TriMesh& mesh);

}  // namespace lk
