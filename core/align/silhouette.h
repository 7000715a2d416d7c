// Silhouette masks for the initial alignment of jeong2002 Sec. 4.1, on the
// CPU: the paper renders the generic head G and the point cloud P into an
// OpenGL frame buffer for the three axis views, XORs them and counts white
// pixels with glGetHistogram. Here each view is an N x N bit mask (one bit per
// pixel, 64 pixels per word), triangles are scan-line filled, and the XOR
// count is a popcount over 64-bit words.
//
// Views share one world-fixed cubic window (the paper's fixed projection):
//   Front: looks along -z at the face: column <- +x, row <- -y (top row = top of head)
//   Side:  looks along +x:              column <- +z, row <- -y (face to the right)
//   Top:   looks along -y:              column <- +x, row <- +z (face at the bottom)
// Pixel (i, j) has its centre at (i + 0.5, j + 0.5) in pixel coordinates.
//
// Point clouds are drawn once per view (the paper's texture trick, end of
// Sec. 4.1). Sparse clouds leave holes (the paper's footnote 1 raises
// glPointSize); we close the splatted mask morphologically with a disk just
// large enough to bridge the gaps between points, which fills the holes
// without growing the outline as a larger point size would.
#pragma once
#include "common/types.h"
#include "head/head_model.h"
#include "mesh/topology.h"

#include <array>
#include <cstdint>
#include <vector>

namespace lk {

enum class SilhouetteView { Front = 0, Side = 1, Top = 2 };
constexpr int kSilhouetteViews = 3;
const char* to_string(SilhouetteView view);

// A square bit mask, N x N pixels; row-major, top row first.
struct SilhouetteMask {
  int size = 0;                       // N
  int words_per_row = 0;              // ceil(N / 64)
  std::vector<std::uint64_t> bits;    // N * words_per_row; bits past column N stay 0

  static SilhouetteMask make(int n);
  bool get(int x, int y) const {
    return (bits[static_cast<size_t>(y) * words_per_row + (x >> 6)] >> (x & 63)) & 1u;
  }
  void set(int x, int y) {
    bits[static_cast<size_t>(y) * words_per_row + (x >> 6)] |= std::uint64_t(1) << (x & 63);
  }
  // Sets columns [x0, x1) of row y (clamped to the mask).
  void set_span(int y, int x0, int x1);
  void clear();
  int count() const;  // covered pixels
};

// Pixels covered by exactly one of a and b (sizes must match).
int xor_count(const SilhouetteMask& a, const SilhouetteMask& b);
// Pixels covered by exactly one of (a1 or a2) and b: the XOR count of a mesh
// drawn in two parts into a1 and a2 (sizes must match).
int union_xor_count(const SilhouetteMask& a1, const SilhouetteMask& a2, const SilhouetteMask& b);

// The shared world-fixed projection: a cube of side 2 * half_size around
// center, seen at resolution x resolution pixels in each view.
struct ViewWindow {
  Vec3 center = Vec3::Zero();
  double half_size = 1.0;
  int resolution = 256;

  double pixel_size() const { return 2.0 * half_size / resolution; }
  // Pixel coordinates (column, row) of a world point in a view.
  Vec2 project(const Vec3& p, SilhouetteView view) const;
};

// The cube around box, enlarged by margin (a fraction of the box's largest
// side) on every side.
ViewWindow make_view_window(const BBox& box, double margin, int resolution);

// Fills the pixels whose centres lie inside the triangle (a, b, c), given in
// pixel coordinates, with a half-open rule (left and top edges in, right and
// bottom edges out) so triangles sharing an edge leave no gap. Either winding.
void rasterize_triangle(const Vec2& a, const Vec2& b, const Vec2& c, SilhouetteMask& mask);

// Rasterizes the triangles of a mesh with the given (already transformed)
// vertex positions into the three views. Parts on the cut side of any clip
// plane are removed (triangles are clipped exactly, not dropped). out is
// resized to window.resolution.
// cull_back_faces skips triangles facing away from a view (directions -z,
// +x, -y for front, side, top): a ray entering a closed, outward-oriented
// (counter-clockwise) surface first crosses a triangle facing it, so the
// outline is unchanged at half the work. A clip plane whose cut side faces
// the viewer opens the surface to view (one sees its inside through the
// cut), so culling is switched off in such views. Wrong for inward-facing
// or open meshes seen through their own holes.
// Only triangles [range.begin, range.end) are drawn when a range is given
// (two threads draw the two halves of a mesh into two sets of masks; their
// union is the whole mesh's silhouette, see union_xor_count).
struct TriangleRange {
  int begin = 0;
  int end = 1 << 30;  // (clamped to the triangles)
};
void rasterize_mesh_silhouettes(const std::vector<Vec3>& positions, const std::vector<Tri>& triangles,
                                const ViewWindow& window, const std::vector<ClipPlane>& clips,
                                std::array<SilhouetteMask, kSilhouetteViews>& out,
                                bool cull_back_faces = false, TriangleRange range = {});

struct PointSplatOptions {
  // Hole filling: candidate closing radii in pixels, in increasing order.
  // The largest radius whose step from the previous candidate adds at least
  // hole_tolerance of the covered area is used (sampling holes fill at once
  // when the radius bridges the gaps between points; true concavities of
  // the outline fill slowly). 0 means the raw one-pixel-per-point mask.
  std::vector<double> closing_radii_px = {0.0, 1.0, 1.5, 2.0, 3.0, 4.0, 6.0};
  double hole_tolerance = 0.01;
  // Use the median of the three views' radii in every view (see the .cpp).
  bool same_radius_in_all_views = true;
};

// What point splatting chose per view.
struct PointSilhouetteInfo {
  std::array<double, kSilhouetteViews> closing_radius_px{};  // radius used per view
  std::array<int, kSilhouetteViews> raw_pixels{};            // pixels hit by a point
  std::array<int, kSilhouetteViews> covered_pixels{};        // after hole filling
  int points_kept = 0;                                       // points not clipped away
};

// Draws the points kept by every clip plane into the three views (each point
// covers the pixel it falls in), then fills holes as described above.
void rasterize_point_silhouettes(const std::vector<Vec3>& points, const ViewWindow& window,
                                 const std::vector<ClipPlane>& clips, const PointSplatOptions& options,
                                 std::array<SilhouetteMask, kSilhouetteViews>& out,
                                 PointSilhouetteInfo* info = nullptr);

// Morphological closing of a mask with a Euclidean disk of the given radius
// (pixel centres within radius), via two exact distance transforms.
// Pixels outside the mask count as empty.
SilhouetteMask close_mask(const SilhouetteMask& mask, double radius_px);

// Smooth outline distance (AlignOptions::smooth_score): the XOR count is an
// integer, flat under sub-pixel moves, so Powell stops wherever its line
// searches run out of pixels. This symmetric chamfer score between the
// outlines changes continuously as the mesh moves.
//
// A fixed (scan) mask's outline: its signed distance field (about the
// pixel edges, bilinear between pixel centres) and its edge points (the
// midpoints between covered pixels and their uncovered 4-neighbours).
struct OutlineField {
  int size = 0;
  std::vector<float> signed_distance;  // size^2, row-major; < 0 inside
  std::vector<Vec2> edge_points;       // pixel coordinates
  double cap_px = 8.0;                 // reverse distances are capped here
};
OutlineField make_outline_field(const SilhouetteMask& mask, double cap_px);
// |signed distance| of the field at pixel coordinates p (bilinear, clamped).
double outline_distance_at(const OutlineField& field, const Vec2& p);

// Points on the outline of a mesh in each view, continuous in its pose:
// the ends of contour edges (between a triangle facing the view and one
// facing away, or open) and the crossings of edges with the clip planes,
// kept where they lie next to the outline of the mesh's own mask (masks,
// from rasterize_mesh_silhouettes) and on the kept side of every plane.
// edges: the mesh's (MeshTopology::edges, mesh/topology.h).
void mesh_outline_points(const std::vector<Vec3>& positions, const std::vector<Tri>& triangles,
                         const std::vector<Edge>& edges, const ViewWindow& window,
                         const std::vector<ClipPlane>& clips,
                         const std::array<SilhouetteMask, kSilhouetteViews>& masks,
                         std::array<std::vector<Vec2>, kSilhouetteViews>& out);

// Symmetric chamfer score, in pixels times the field's edge-point count:
// sum over the field's edge points of the distance to the nearest outline
// point (capped at cap_px) plus the mean |signed distance| at the outline
// points times the edge-point count. Without outline points every edge
// point counts 2 * cap_px.
double outline_chamfer(const OutlineField& field, const std::vector<Vec2>& outline_points);

}  // namespace lk
