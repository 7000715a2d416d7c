#include "head/generic_head_builder.h"

#include "head/head_shape.h"
#include "mesh/topology.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <string>

namespace lk {
namespace {

constexpr double kPi = 3.14159265358979323846;
double radians(double degrees) { return degrees * kPi / 180.0; }


// ---------------------------------------------------------------------------
// Layout of the quad grid. Rows go from under the jaw (row 0) to the crown
// patch; columns are meridians, column 0 on the face's midline, increasing
// towards +x (the head's left). Below row 0 the neck is a stack of rings
// with fewer meridians (kNeckRings), down to the mesh's boundary.

constexpr int kColumns = 40;  // the crown patch is 10 x 10, whose border has 40 vertices
constexpr int kCapSize = 10;

// The head rows cast rays from a centre inside the head at the given
// elevation (degrees).
const double kHeadRowElevation[] = {-60, -54, -48.5, -43.5, -39.5, -36.5, -33.8, -31, -27.5, -24,
                                    -20.5, -16.5, -12.5, -8, -4, 0, 5, 10, 15, 20, 26, 33, 40};
constexpr int kHeadRows = sizeof(kHeadRowElevation) / sizeof(double);
constexpr int kRows = kHeadRows;

// The neck: rings between row 0 and the neck's bottom (y = kNeckBottomY, the
// mesh's boundary), from the top down. The 40 meridians of the head are 5 mm
// apart at the throat (the face's dense columns) and 17 mm at the nape;
// continuing them down the neck in 22-26 mm rows made 5:1 slivers whose
// smooth Butterfly surface rippled in vertical columns (streaks under the
// jaw on every fitted head). The rings have fewer, more evenly spread
// meridians and are about as far apart as their meridians, so the neck's
// triangles are close to right isosceles; a strip of triangles joins rings
// of different meridian counts. depth: fraction of the way from row 0 to the
// bottom, measured along each meridian on the surface. The first strip
// (40 -> 24 meridians) is thinner, 8-10 mm, because its upper edges are
// only 5 mm long at the throat. Measured (docs/journal.md): neck edge
// ratio p90 4.5 -> 1.9, worst 6.2 -> 2.3, for 8 more vertices.
struct NeckRing {
  int meridians;           // even, so the ring is mirror-symmetric with vertices at 0 and 180 deg
  double face_density;     // meridian spacing at the front is (1 - face_density) of the mean
  double depth;            // 0 at row 0, 1 at the bottom
};
const NeckRing kNeckRings[] = {{24, 0.3, 0.10}, {24, 0.3, 0.25}, {24, 0.3, 0.40}, {24, 0.3, 0.55},
                               {24, 0.3, 0.70}, {24, 0.3, 0.85}, {24, 0.3, 1.00}};
constexpr int kNeckRingCount = sizeof(kNeckRings) / sizeof(NeckRing);
// With regular_nape the strip joining the head's 40 meridians to the neck's
// 24 is this much deeper (a fraction of the neck's length) at the back than
// at the throat: 8 mm at the throat, whose upper edges are 5 mm long, and
// 16 mm at the back, whose are 17 and 25 mm (8 mm there made 3:1 slivers, a
// wavy line where the skull meets the neck). Deeper still (0.15, 0.2) moved
// the line to the next ring down.
constexpr double kBackNeckStripExtra = 0.10;
constexpr double kNeckBottomY = -0.195;

// Rows of the features (see kHeadRowElevation).
constexpr int kSlitRow = 6;     // -33.8 deg: the lip line
constexpr int kRimLowRow = 16;  // 5 deg: lower lid of the eye opening
constexpr int kEarLowRow = 11;  // -16.5 deg .. 10 deg: ear root
constexpr int kEarHighRow = 17;
// Columns (left side; the right side mirrors c -> -c).
constexpr int kEyeCol0 = 2, kEyeCol1 = 6;     // eye opening: 4 quads wide, 1 high
constexpr int kMouthHalfWidth = 3;            // lip line spans columns -3..3
constexpr int kEarCol0 = 12, kEarCol1 = 14;   // ear root: 2 quads wide, 6 high
// The nose's underside: the quad between the columella (column 0) and
// column 1, rows 11 (subnasale, the alar base) .. 12 (under the tip). It
// faces down; with GenericHeadBuildOptions::nostrils each side's holds a
// nostril.
constexpr int kNostrilRow = 11;

// The ear's rings inside its root wall, from the helix rim inwards (section
// 8). scale: of the helix outline about kEarConchaCenter (1: the outline);
// lift: along the head's normal (m), positive lifts fade out at the lobe.
// The first ring is the rim, whose vertices are the ear landmarks.
struct EarRing {
  int count;     // vertices on the ring
  double scale;  // of the helix outline about the concha's centre
  double lift;   // out from the flap (m)
};
const EarRing kEarRings[] = {
    {20, 1.00, 0.0},      // helix rim
    {20, 0.84, 0.0025},   // helix lip, rolled outwards over the scapha
    {16, 0.60, 0.0012},   // antihelix ridge
    {8, 0.32, -0.0020},   // concha wall, sinking towards the head
};
// The concha's centre in the ear's frame (behind the root, up, out from the
// head; m): in front of and below the ear's middle, as the bowl leads to the
// ear canal. Its floor sinks kEarConchaFloorLift below the flap.
const Vec3 kEarConchaCenter(0.004, -0.005, 0.0135);
constexpr double kEarConchaFloorLift = -0.0045;
// The wall ring (3.5 mm off the root) is moved this fraction of the way
// towards the rim.
constexpr double kEarWallTowardsRim = 0.2;

const Vec3 kRayCenter(0, 0.010, -0.005);
const Vec3 kNeckAxis(0, 0, -0.016);

// Azimuth of meridian c of n, denser over the face by face_density.
double meridian_azimuth(int c, int n, double face_density) {
  const double u = 2 * kPi * c / n;
  return u - face_density * std::sin(u);
}
double column_azimuth(int c) { return meridian_azimuth(c, kColumns, 0.5); }
int wrap(int c) { return ((c % kColumns) + kColumns) % kColumns; }
Vec3 direction(double azimuth, double elevation) {
  return {std::cos(elevation) * std::sin(azimuth), std::sin(elevation),
          std::cos(elevation) * std::cos(azimuth)};
}

// Where a polyline's cumulative length table (length[0] = 0, non-decreasing)
// reaches `target`: its segment i (from point i - 1 to point i, 1 <= i <
// length.size()) and the fraction f along it.
struct ArcPosition {
  int i = 1;
  double f = 0;
};
ArcPosition arc_position(const std::vector<double>& length, double target) {
  const int last = static_cast<int>(length.size()) - 1;
  ArcPosition a;
  while (a.i < last && length[a.i] < target) ++a.i;
  a.f = (target - length[a.i - 1]) / std::max(1e-12, length[a.i] - length[a.i - 1]);
  return a;
}

// The rows' elevations suit the face: dense at the lips and chin, sparse
// above. Seen from the ray centre the nape is a concave bend, so at the back
// the same elevations put rows 22 mm apart under the skull and 5 mm apart
// at the nape's bend, against 17 mm between the meridians there: 3.5:1
// slivers whose smooth Butterfly surface ripples into a wavy crease across
// the back of every head. Behind the ears the rows are moved along their
// meridian towards even spacing by arc length (row 0 and the top row stay,
// so the neck and the crown patch join as before), fully from
// kBackRowsFull degrees of azimuth, fading out towards kBackRowsStart.
constexpr double kBackRowsStart = 110, kBackRowsFull = 160;
void even_back_rows(const HeadShape& shape, const std::vector<std::vector<int>>& grid, std::vector<Vec3>& positions) {
  const double e0 = kHeadRowElevation[0], e1 = kHeadRowElevation[kHeadRows - 1];
  constexpr int samples = 600;
  for (int c = 0; c < kColumns; ++c) {
    const double az = column_azimuth(c);
    const double a = std::abs(std::remainder(az, 2 * kPi)) * 180 / kPi;
    double w = std::clamp((a - kBackRowsStart) / (kBackRowsFull - kBackRowsStart), 0.0, 1.0);
    w = w * w * (3 - 2 * w);
    if (w <= 0) continue;
    std::vector<Vec3> curve(samples + 1);
    std::vector<double> length(samples + 1, 0.0), elevation(samples + 1);
    for (int i = 0; i <= samples; ++i) {
      elevation[i] = e0 + (e1 - e0) * i / samples;
      curve[i] = shape.cast(kRayCenter, direction(az, radians(elevation[i])));
      if (i > 0) length[i] = length[i - 1] + (curve[i] - curve[i - 1]).norm();
    }
    auto length_at = [&](double e) {  // arc length up to elevation e
      const double t = (e - e0) / (e1 - e0) * samples;
      const int i = std::clamp(int(t), 0, samples - 1);
      return length[i] + (t - i) * (length[i + 1] - length[i]);
    };
    for (int h = 1; h + 1 < kHeadRows; ++h) {
      const double target = (1 - w) * length_at(kHeadRowElevation[h]) + w * length[samples] * h / (kHeadRows - 1);
      const ArcPosition at = arc_position(length, target);
      const double e = elevation[at.i - 1] + at.f * (elevation[at.i] - elevation[at.i - 1]);
      positions[grid[h][c]] = shape.cast(kRayCenter, direction(az, radians(e)));
    }
  }
}

// Rectangular loops of the grid mapped onto ellipses would put each corner
// vertex on the ellipse between its two neighbours, leaving a quad with a
// straight angle; pushing corners out a little keeps those quads convex.
double corner_bulge(double x, double y) {
  const double a = std::atan2(std::abs(y), std::abs(x));  // 45 deg at a corner of the square
  return 1.0 + 0.16 * std::pow(std::sin(2 * a), 4);
}

enum class Part { Grid, Neck, Cap, LowerLipLine, EyePocket, MouthBag, Ear, NostrilRim, NostrilPocket };

struct VertexInfo {
  Part part = Part::Grid;
  int row = -1, col = -1;  // grid vertices (col in 0..kColumns-1); neck: row -1 - ring
  int side = 0;            // +1 left, -1 right, 0 midline / both
  int chain = 0;           // lips and mouth bag: +1 upper, -1 lower, 0 corner
};

// Behind the ears the grid's quads are close to squares, and down the neck
// the rings' quads are alike, so splitting each along its better diagonal
// picked one or the other nearly at random: vertices with 4, 5, 7 and 8
// neighbours, each an irregular Butterfly stencil that rippled the smooth
// surface (wavy lines across the nape). There every quad is split along the
// diagonal from its lower corner nearer the face's midline to its upper
// corner farther from it (a chevron, mirrored on the other side), which
// gives every vertex six neighbours, on the midlines too. Returns which of
// the quad's diagonals that is (0: poly[0] - poly[2], 1: poly[1] - poly[3]),
// or -1 for any other quad: one not made of grid vertices behind the ears
// (kBackDiagonalColumn or more columns from the face's midline on either
// side) or of neck ring vertices.
constexpr int kBackDiagonalColumn = 15;
int chevron_diagonal(const std::vector<VertexInfo>& info, const std::vector<int>& poly) {
  const Part part = info[poly[0]].part;
  const int columns = part == Part::Grid ? kColumns : part == Part::Neck ? kNeckRings[0].meridians : 0;
  auto from_midline = [&](int col) { return std::min(col, columns - col); };
  int lowest_row = 1 << 30;
  for (int v : poly) {
    const VertexInfo& vi = info[v];
    if (columns == 0 || vi.part != part) return -1;
    if (part == Part::Grid && from_midline(vi.col) < kBackDiagonalColumn) return -1;
    lowest_row = std::min(lowest_row, vi.row);
  }
  // The chevron diagonal's ends: the lower row's corner nearer the midline
  // and the upper row's corner farther from it.
  auto is_end = [&](int v) {
    const VertexInfo& vi = info[v];
    int other_col = -1;  // the other corner on the same row
    for (int w : poly)
      if (w != v && info[w].row == vi.row) other_col = info[w].col;
    if (other_col < 0) return false;
    const bool nearer = from_midline(vi.col) < from_midline(other_col);
    return vi.row == lowest_row ? nearer : !nearer;
  };
  if (is_end(poly[0]) && is_end(poly[2])) return 0;
  if (is_end(poly[1]) && is_end(poly[3])) return 1;
  return -1;
}

class Builder {
 public:
  std::vector<Vec3> positions;
  std::vector<VertexInfo> info;
  std::vector<std::vector<int>> polygons;  // quads and triangles, CCW from outside

  int add(const Vec3& p, const VertexInfo& vi) {
    positions.push_back(p);
    info.push_back(vi);
    return static_cast<int>(positions.size()) - 1;
  }

  bool has_directed_edge(int a, int b) const {
    for (const auto& poly : polygons)
      for (size_t k = 0; k < poly.size(); ++k)
        if (poly[k] == a && poly[(k + 1) % poly.size()] == b) return true;
    return false;
  }

  // Reorders a hole's loop so that the existing faces contain loop[k] -> loop[k+1].
  void orient_loop(std::vector<int>& loop) const {
    if (!has_directed_edge(loop[0], loop[1])) std::reverse(loop.begin(), loop.end());
  }

  // Adds a ring of new vertices behind an oriented hole loop and the quads
  // joining them; returns the new vertices, index for index.
  std::vector<int> extrude(const std::vector<int>& loop, const std::vector<Vec3>& new_positions,
                           const VertexInfo& vi) {
    std::vector<int> ring;
    for (size_t k = 0; k < loop.size(); ++k) {
      VertexInfo v = vi;
      v.chain = info[loop[k]].chain;
      ring.push_back(add(new_positions[k], v));
    }
    const size_t n = loop.size();
    for (size_t k = 0; k < n; ++k) {
      const size_t k1 = (k + 1) % n;
      polygons.push_back({loop[k1], loop[k], ring[k], ring[k1]});
    }
    return ring;
  }

  // Joins an inner ring to an outer one whose faces on its other side walk
  // outer[k] -> outer[k+1]; s: each vertex's place along its ring, rising
  // with the index by less than 1 in all, both rings starting near 0. Quads where the
  // counts match, otherwise a strip of triangles merging the two rings'
  // edges in the order of their mid-places (the same on a mirrored pair of
  // rings, whose places are 1 - s, as long as no two mid-places coincide).
  // Returns the edges made between the rings (outer, inner). split: rings of
  // the same count are joined by triangles whose diagonals all lean the same
  // way (outer[k] - inner[k + 1] when forward, else outer[k + 1] - inner[k];
  // a mirrored ring pair, indexed the other way round, takes the other), so
  // every ring vertex gets 2 neighbours on each side: valence 6 where both
  // sides are such strips. Without split: quads, split later by their better
  // diagonal.
  enum class Split { Quads, Forward, Backward };
  std::vector<std::array<int, 2>> join_rings(const std::vector<int>& outer, const std::vector<double>& s_outer,
                                             const std::vector<int>& inner, const std::vector<double>& s_inner,
                                             Split split = Split::Quads) {
    const int no = static_cast<int>(outer.size()), ni = static_cast<int>(inner.size());
    std::vector<std::array<int, 2>> spokes;
    if (no == ni) {
      for (int k = 0; k < no; ++k) {
        const int o0 = outer[k], o1 = outer[(k + 1) % no], i0 = inner[k], i1 = inner[(k + 1) % no];
        spokes.push_back({o0, i0});
        if (split == Split::Quads) {
          polygons.push_back({o1, o0, i0, i1});
        } else if (split == Split::Forward) {
          polygons.push_back({o1, o0, i1});
          polygons.push_back({o0, i0, i1});
          spokes.push_back({o0, i1});
        } else {
          polygons.push_back({o1, o0, i0});
          polygons.push_back({o1, i0, i1});
          spokes.push_back({o1, i0});
        }
      }
      return spokes;
    }
    auto mid = [](const std::vector<double>& s, int i) {
      const double next = i + 1 < int(s.size()) ? s[i + 1] : s[0] + 1.0;
      return 0.5 * (s[i] + next);
    };
    int i = 0, j = 0;
    spokes.push_back({outer[0], inner[0]});
    while (i < no || j < ni) {
      if (j == ni || (i < no && mid(s_outer, i) < mid(s_inner, j))) {
        polygons.push_back({outer[(i + 1) % no], outer[i], inner[j % ni]});
        ++i;
      } else {
        polygons.push_back({outer[i % no], inner[j], inner[(j + 1) % ni]});
        ++j;
      }
      spokes.push_back({outer[i % no], inner[j % ni]});
    }
    spokes.pop_back();  // the last spoke is the first again
    return spokes;
  }

  // Closes a hole whose loop is made of two chains walking from one end to
  // the other (top[k] faces bottom[k]; ends may be shared vertices).
  void close_between(const std::vector<int>& top, const std::vector<int>& bottom) {
    const bool forward = has_directed_edge(top[0], top[1]);
    for (size_t k = 0; k + 1 < top.size(); ++k) {
      std::vector<int> q = forward ? std::vector<int>{top[k + 1], top[k], bottom[k], bottom[k + 1]}
                                   : std::vector<int>{top[k], top[k + 1], bottom[k + 1], bottom[k]};
      std::vector<int> poly;
      for (int v : q)
        if (std::find(poly.begin(), poly.end(), v) == poly.end()) poly.push_back(v);
      polygons.push_back(poly);
    }
  }
};

BBox box_of(const std::vector<Vec3>& p, const std::vector<int>& ids) {
  BBox b;
  for (int v : ids) b.extend(p[v]);
  return b;
}

// Where an ear's root loop starts and which way it turns: the loop vertex
// nearest the top of the root (by its angle around `root` in the back/up
// plane, the extents scaled to a circle), and +1 when the loop runs
// counter-clockwise from there (towards the back), -1 otherwise. Both ears'
// loops turn opposite ways; their walls are matched to the helix outline
// from the top in the same direction.
struct EarLoopStart {
  int top = 0;
  double turn = 1;
};
EarLoopStart ear_loop_start(const std::vector<Vec3>& positions, const std::vector<int>& loop, const Vec3& root,
                            const Vec3& back, const Vec3& up, double half_back, double half_up) {
  const int n_loop = static_cast<int>(loop.size());
  std::vector<double> root_angle(n_loop);
  EarLoopStart s;
  for (int k = 0; k < n_loop; ++k) {
    const Vec3 d = positions[loop[k]] - root;
    root_angle[k] = std::atan2(d.dot(up) / half_up, d.dot(back) / half_back);
    if (std::cos(root_angle[k] - kPi / 2) > std::cos(root_angle[s.top] - kPi / 2)) s.top = k;
  }
  s.turn = std::sin(root_angle[(s.top + 1) % n_loop] - root_angle[s.top]) > 0 ? 1 : -1;
  return s;
}

std::vector<int> sorted_unique(std::vector<int> v) {
  std::sort(v.begin(), v.end());
  v.erase(std::unique(v.begin(), v.end()), v.end());
  return v;
}

}  // namespace

Status build_generic_head(const GenericHeadBuildOptions& options, GenericHead& out) {
  if (!(options.eyeball_radius > 0.005 && options.eyeball_radius < 0.0135))
    return Status::error(ErrorCode::InvalidInput, "eyeball_radius must be in (5 mm, 13.5 mm)");
  if (!(options.socket_clearance > 0 && options.eyeball_radius + options.socket_clearance < 0.0138))
    return Status::error(ErrorCode::InvalidInput, "socket pocket would not fit inside the lids");
  if (!(options.lip_gap > 0 && options.lip_gap < 0.001))
    return Status::error(ErrorCode::InvalidInput, "lip_gap must be in (0, 1 mm)");

  const HeadShape shape;
  Builder b;

  // --- 1. grid vertices -----------------------------------------------------
  std::vector<std::vector<int>> grid(kRows, std::vector<int>(kColumns, -1));
  for (int r = 0; r < kRows; ++r)
    for (int c = 0; c < kColumns; ++c) {
      VertexInfo vi;
      vi.row = r;
      vi.col = c;
      grid[r][c] = b.add(Vec3::Zero(), vi);
    }
  auto g = [&](int r, int c) { return grid[r][wrap(c)]; };
  for (int c = 0; c < kColumns; ++c)
    for (int h = 0; h < kHeadRows; ++h)
      b.positions[g(h, c)] = shape.cast(kRayCenter, direction(column_azimuth(c), radians(kHeadRowElevation[h])));
  if (options.even_back_rows) even_back_rows(shape, grid, b.positions);

  // --- 1b. neck rings below row 0 -------------------------------------------
  // Each ring vertex lies on the surface curve from row 0 down to the neck's
  // bottom at its azimuth, at its ring's depth along that curve's length.
  std::vector<std::vector<int>> neck_rings;
  {
    auto meridian_point = [&](double az, double depth) -> Vec3 {
      const Vec3 top = shape.cast(kRayCenter, direction(az, radians(kHeadRowElevation[0])));
      Vec3 bottom = shape.cast(Vec3(kNeckAxis.x(), kNeckBottomY, kNeckAxis.z()), {std::sin(az), 0, std::cos(az)});
      bottom.y() = kNeckBottomY;
      if (depth >= 1) return bottom;
      constexpr int samples = 64;
      std::vector<Vec3> curve(samples + 1);
      std::vector<double> length(samples + 1, 0.0);
      for (int i = 0; i <= samples; ++i) {
        const double t = double(i) / samples;
        curve[i] = i == 0 ? top : i == samples ? bottom : shape.project((1 - t) * top + t * bottom);
        if (i > 0) length[i] = length[i - 1] + (curve[i] - curve[i - 1]).norm();
      }
      const ArcPosition a = arc_position(length, depth * length[samples]);
      return shape.project((1 - a.f) * curve[a.i - 1] + a.f * curve[a.i]);
    };
    for (int k = 0; k < kNeckRingCount; ++k) {
      const NeckRing& ring = kNeckRings[k];
      std::vector<int> ids;
      for (int c = 0; c < ring.meridians; ++c) {
        VertexInfo vi;
        vi.part = Part::Neck;
        vi.row = -1 - k;
        vi.col = c;
        const double az = meridian_azimuth(c, ring.meridians, ring.face_density);
        double depth = ring.depth;
        if (options.regular_nape) {
          // The first ring lies deeper towards the back; the rings below
          // keep their places between it and the bottom.
          const double first = kNeckRings[0].depth;
          const double here = first + kBackNeckStripExtra * 0.5 * (1 - std::cos(az));
          depth = here + (1 - here) * (ring.depth - first) / (1 - first);
        }
        ids.push_back(b.add(meridian_point(az, depth), vi));
      }
      neck_rings.push_back(ids);
    }
    // Faces between each ring and the one above it: quads where both have
    // the same meridians, otherwise a strip of triangles merging the two
    // rings' edges in the order of their mid-azimuths (mirror-symmetric as
    // long as no two mid-azimuths coincide; the tests check the triangles).
    std::vector<int> upper(kColumns);
    std::vector<double> upper_az(kColumns);
    for (int c = 0; c < kColumns; ++c) upper[c] = g(0, c), upper_az[c] = column_azimuth(c);
    double upper_density = 0.5;
    for (int k = 0; k < kNeckRingCount; ++k) {
      const NeckRing& ring = kNeckRings[k];
      const std::vector<int>& lower = neck_rings[k];
      std::vector<double> lower_az(ring.meridians);
      for (int c = 0; c < ring.meridians; ++c) lower_az[c] = meridian_azimuth(c, ring.meridians, ring.face_density);
      const int nu = static_cast<int>(upper.size()), nl = ring.meridians;
      if (nu == nl && upper_density == ring.face_density) {
        for (int c = 0; c < nl; ++c)
          b.polygons.push_back({lower[c], lower[(c + 1) % nl], upper[(c + 1) % nu], upper[c]});
      } else {
        auto mid = [](const std::vector<double>& az, int i) {
          const double next = i + 1 < int(az.size()) ? az[i + 1] : 2 * kPi;
          return 0.5 * (az[i] + next);
        };
        int i = 0, j = 0;
        while (i < nu || j < nl) {
          if (j == nl || (i < nu && mid(upper_az, i) < mid(lower_az, j))) {
            b.polygons.push_back({lower[j % nl], upper[(i + 1) % nu], upper[i % nu]});
            ++i;
          } else {
            b.polygons.push_back({lower[j % nl], lower[(j + 1) % nl], upper[i % nu]});
            ++j;
          }
        }
      }
      upper = lower;
      upper_az = lower_az;
      upper_density = ring.face_density;
    }
  }

  // Casts through a point given in front of the face.
  // The plain layout before the features are warped in; relaxation keeps its
  // local spacing (denser over the face) while evening out the warps.
  std::vector<Vec3> reference = b.positions;
  auto cast_towards = [&](const Vec3& target) { return shape.cast(kRayCenter, target - kRayCenter); };

  // --- 2. eyes: concentric ellipse around a 4 x 1 opening on the lid sphere --
  const double lid_half_angle = radians(68);  // half the opening's width, seen from the eyeball
  const double upper_lid = radians(25), lower_lid = radians(17), canthus = radians(3.5);
  std::map<int, std::vector<int>> rim_top, rim_bottom;  // by side, medial -> lateral
  for (int side : {1, -1}) {
    const Vec3 eye(side * shape.eye_center.x(), shape.eye_center.y(), shape.eye_center.z());
    const Vec3 opening_center = eye + Vec3(0, 0.0008, shape.lid_radius);
    // Ring around the opening (columns 1..7, rows rim-1..rim+2). Its points
    // are cast from inside the head towards targets in a plane in front of
    // the eye; where the face turns back (lateral, and towards the nose) a
    // ray lands short of its target. With a 17 mm half-width on both sides
    // the lateral ring landed 0.5 mm medial of the opening's lateral corner
    // and the lid skin folded back over the canthus: the smooth level 3
    // crossed itself there (307 of its 397 level-3 triangle pairs, inherited by
    // every fit). Wider half-widths leave the skin room to turn into the
    // opening; 23-25 mm laterally and 18-21 mm medially all give 0 pairs.
    const double ring_half_width_lateral = 0.0240, ring_half_width_medial = 0.0195;
    for (int r = kRimLowRow - 1; r <= kRimLowRow + 2; ++r)
      for (int c = kEyeCol0 - 1; c <= kEyeCol1 + 1; ++c) {
        const bool perimeter = r == kRimLowRow - 1 || r == kRimLowRow + 2 || c == kEyeCol0 - 1 ||
                               c == kEyeCol1 + 1;
        if (!perimeter) continue;
        auto square = [&](int rr, int cc) {
          return Vec3((cc - 0.5 * (kEyeCol0 + kEyeCol1)) / (0.5 * (kEyeCol1 - kEyeCol0) + 1),
                      (rr - (kRimLowRow + 0.5)) / 1.5, 0);
        };
        const Vec3 at = square(r, c);
        const double x = at.x(), y = at.y();
        double a = std::atan2(y, x);
        const bool corner = (r == kRimLowRow - 1 || r == kRimLowRow + 2) && (c == kEyeCol0 - 1 || c == kEyeCol1 + 1);
        if (corner && options.even_eye_corners) {
          // A corner goes halfway (in angle) between its two neighbours. The
          // ring is a 6 x 3 perimeter on a 2:1 ellipse: at 45 deg of the
          // square a corner sits 11 deg from its row neighbour and 27 deg
          // from its column neighbour, 4.3-4.9 mm from the first among
          // 13-27 mm edges. Over the brow that short edge makes the fitted
          // control mesh's Butterfly surface fold on clean scans (seeds 2
          // and 4 at 0.05 mm noise, 8 at 0.2 mm; docs/journal.md
          // "Even corners of the eye rings").
          const int rn = r == kRimLowRow - 1 ? r + 1 : r - 1, cn = c == kEyeCol0 - 1 ? c + 1 : c - 1;
          const Vec3 p_row = square(r, cn), p_col = square(rn, c);
          const double a_row = std::atan2(p_row.y(), p_row.x()), a_col = std::atan2(p_col.y(), p_col.x());
          double mid = 0.5 * (a_row + a_col);
          if (std::abs(a_row - a_col) > kPi) mid += kPi;  // the two sides of +-180 deg
          a = mid;
        }
        const double dy = std::sin(a) > 0 ? 0.0120 : 0.0105;
        const double f = corner_bulge(x, y);
        const double half_width = std::cos(a) > 0 ? ring_half_width_lateral : ring_half_width_medial;
        const Vec3 target = opening_center + f * Vec3(side * half_width * std::cos(a), dy * std::sin(a), 0);
        b.positions[g(r, side * c)] = cast_towards(target);
      }
    // The opening's rim lies on the lid sphere.
    for (int k = 0; k <= kEyeCol1 - kEyeCol0; ++k) {
      const double t = 2.0 * k / (kEyeCol1 - kEyeCol0) - 1.0;  // -1 medial .. +1 lateral
      const double az = t * lid_half_angle;
      const double open = std::pow(std::max(0.0, 1 - t * t), 0.7);
      const double tilt = 0.03 * t;  // lateral corner slightly higher
      for (int top : {1, 0}) {
        const double el = tilt + (top ? canthus + upper_lid * open : -canthus - lower_lid * open);
        const Vec3 dir(side * std::sin(az) * std::cos(el), std::sin(el), std::cos(az) * std::cos(el));
        const int v = g(kRimLowRow + top, side * (kEyeCol0 + k));
        b.positions[v] = eye + shape.lid_radius * dir;
        (top ? rim_top : rim_bottom)[side].push_back(v);
      }
    }
  }

  // --- 3. mouth: lip line and two concentric ellipses -----------------------
  const double mouth_half_width = 0.0245;
  const Vec3 mouth_front(0, shape.slit_y, 0.098);  // near the lips, so rays land close to x, y
  for (int ring = 1; ring <= 2; ++ring) {
    const int hw = kMouthHalfWidth + ring;
    // Ring 1 is cast towards an ellipse 8 mm wider than the lip line; at
    // 4.5 mm its corner rays landed short where the face turns back, 1.3 mm
    // medial of the mouth corner and 0.3 mm from the mouth bag, and the
    // smooth level 3 crossed itself there (24 pairs; 7-9 mm give none).
    const double ring1 = options.wide_mouth_ring ? 0.0080 : 0.0045;
    const double ax = mouth_half_width + (ring == 1 ? ring1 : 0.0105);
    const double up = ring == 1 ? 0.0075 : 0.0120, down = ring == 1 ? 0.0095 : 0.0175;
    for (int r = kSlitRow - ring; r <= kSlitRow + ring; ++r)
      for (int c = -hw; c <= hw; ++c) {
        if (r != kSlitRow - ring && r != kSlitRow + ring && std::abs(c) != hw) continue;
        const double x = double(c) / hw, y = double(r - kSlitRow) / ring;
        const double a = std::atan2(y, x);
        const double dy = std::sin(a) * (std::sin(a) > 0 ? up : down);
        const double f = corner_bulge(x, y);
        b.positions[g(r, c)] = cast_towards(mouth_front + f * Vec3(ax * std::cos(a), dy, 0));
      }
  }
  std::vector<int> upper_line, lower_line;  // corner .. corner, from -x to +x
  for (int c = -kMouthHalfWidth; c <= kMouthHalfWidth; ++c) {
    const double t = double(c) / kMouthHalfWidth;
    const Vec3 target = mouth_front + Vec3(mouth_half_width * t, -0.0015 * t * t, 0);
    Vec3 p = cast_towards(target);
    const int v = g(kSlitRow, c);
    if (std::abs(c) == kMouthHalfWidth) {
      b.positions[v] = p;
      b.info[v].chain = 0;
      upper_line.push_back(v);
      lower_line.push_back(v);
      continue;
    }
    b.positions[v] = p + Vec3(0, 0.5 * options.lip_gap, 0);
    b.info[v].chain = 1;
    VertexInfo lower;
    lower.part = Part::LowerLipLine;
    lower.row = kSlitRow;
    lower.col = wrap(c);
    lower.chain = -1;
    upper_line.push_back(v);
    lower_line.push_back(b.add(p - Vec3(0, 0.5 * options.lip_gap, 0), lower));
    reference.push_back(reference[v]);
  }

  // --- 4. grid faces (holes left for the eyes and ears) ----------------------
  // Quad (r, c) spans columns c..c+1 and rows r..r+1.
  auto quad_is_eye = [&](int r, int c) {
    if (r != kRimLowRow) return false;
    for (int side : {1, -1}) {
      const int lo = side > 0 ? kEyeCol0 : -kEyeCol1;
      const int hi = side > 0 ? kEyeCol1 : -kEyeCol0;
      for (int k = lo; k < hi; ++k)
        if (wrap(k) == c) return true;
    }
    return false;
  };
  auto quad_is_ear = [&](int r, int c) {
    if (r < kEarLowRow || r >= kEarHighRow) return false;
    for (int k = kEarCol0; k < kEarCol1; ++k)
      if (wrap(k) == c || wrap(-k - 1) == c) return true;
    return false;
  };
  std::map<int, std::vector<std::vector<int>>> ear_patch;  // by side
  for (int r = 0; r + 1 < kRows; ++r)
    for (int c = 0; c < kColumns; ++c) {
      std::vector<int> q = {g(r, c), g(r, c + 1), g(r + 1, c + 1), g(r + 1, c)};
      if (quad_is_eye(r, c)) continue;
      if (quad_is_ear(r, c)) {
        ear_patch[c < kColumns / 2 ? 1 : -1].push_back(q);
        continue;
      }
      // Faces below the lip line use the lower lip's vertices.
      if (r + 1 == kSlitRow) {
        for (int k = 2; k < 4; ++k) {
          const int col = b.info[q[k]].col;
          const int cc = col > kColumns / 2 ? col - kColumns : col;
          if (std::abs(cc) < kMouthHalfWidth) q[k] = lower_line[cc + kMouthHalfWidth];
        }
      }
      b.polygons.push_back(q);
    }

  // --- 5. crown patch: a 10 x 10 quad grid closing the top row --------------
  {
    const int n = kCapSize;
    std::vector<std::vector<int>> cap(n + 1, std::vector<int>(n + 1, -1));
    // Border walk from the front middle towards +x, matching columns 0..39.
    int p = n / 2, q = n, dp = 1, dq = 0;
    for (int c = 0; c < kColumns; ++c) {
      cap[p][q] = g(kRows - 1, c);
      if (c + 1 == kColumns) break;
      if ((dp == 1 && p == n) || (dq == -1 && q == 0) || (dp == -1 && p == 0) || (dq == 1 && q == n)) {
        const int t = dp;
        dp = dq;
        dq = -t;
      }
      p += dp;
      q += dq;
    }
    const double top_elevation = radians(kHeadRowElevation[kHeadRows - 1]);
    for (int i = 1; i < n; ++i)
      for (int j = 1; j < n; ++j) {
        const double X = -1 + 2.0 * i / n, Z = -1 + 2.0 * j / n;
        const double dx = X * std::sqrt(1 - Z * Z / 2), dz = Z * std::sqrt(1 - X * X / 2);
        const double rho = std::sqrt(dx * dx + dz * dz);
        const double psi = std::atan2(dx, dz);
        const double az = psi - rho * rho * 0.5 * std::sin(psi);
        const double el = kPi / 2 - (kPi / 2 - top_elevation) * rho;
        VertexInfo vi;
        vi.part = Part::Cap;
        cap[i][j] = b.add(shape.cast(kRayCenter, direction(az, el)), vi);
      }
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j)
        b.polygons.push_back({cap[i][j], cap[i][j + 1], cap[i + 1][j + 1], cap[i + 1][j]});
  }

  // --- 6. eye pockets ------------------------------------------------------
  HeadAnnotations& ann = out.annotations;
  ann = HeadAnnotations{};
  const double pocket_radius = options.eyeball_radius + options.socket_clearance;
  for (int side : {1, -1}) {
    const Vec3 eye(side * shape.eye_center.x(), shape.eye_center.y(), shape.eye_center.z());
    std::vector<int> top = rim_top[side], bottom = rim_bottom[side];
    std::vector<int> loop = top;
    loop.insert(loop.end(), bottom.rbegin(), bottom.rend());
    b.orient_loop(loop);
    EyeSocket& socket = side > 0 ? ann.eye_left : ann.eye_right;
    socket.center = eye;
    socket.radius = options.eyeball_radius;
    socket.rim = loop;
    VertexInfo vi;
    vi.part = Part::EyePocket;
    vi.side = side;
    // The pocket is a sphere around the eyeball. Seen along the eye's axis,
    // each vertex has an angle chi around the axis and a polar angle psi from
    // the front. Rings go back from the lid rim (psi 20..64 deg) to a circle
    // near the back pole with evenly spaced chi, where the top and bottom
    // chains meet in a strip of quads.
    const int n_top = static_cast<int>(top.size());
    std::map<int, double> chi_even;
    for (int k = 0; k < n_top; ++k) {
      const double chi = radians(180.0 - 180.0 * (k + 0.5) / n_top);
      chi_even[top[k]] = chi;
      chi_even[bottom[k]] = -chi;
    }
    auto sphere_point = [&](double chi, double psi) -> Vec3 {
      const Vec3 d(side * std::sin(psi) * std::cos(chi), std::sin(psi) * std::sin(chi), std::cos(psi));
      return eye + pocket_radius * d;
    };
    std::vector<int> ring = loop;
    for (int step = 0; step < 3; ++step) {
      std::vector<Vec3> next;
      for (size_t k = 0; k < loop.size(); ++k) {
        const Vec3 u = (b.positions[loop[k]] - eye).normalized();  // rim direction
        const double chi = std::atan2(u.y(), side * u.x());
        const double even = chi_even[loop[k]];
        if (step == 0) {
          // The inner edge of the lid, behind the rim. At the four corner
          // vertices (the canthi, 1.7 mm apart) straight behind would make
          // the pocket's first quad at each corner a 1.5 mm sliver between
          // rings 6 mm apart, and its Butterfly refinement folded (58 level-3
          // pairs at the inner corners); a third of the way towards the
          // evenly spaced angles widens it (0.2-0.5 of the way all give 0).
          const bool corner = loop[k] == top.front() || loop[k] == top.back() ||
                              loop[k] == bottom.front() || loop[k] == bottom.back();
          if (!corner) next.push_back(eye + pocket_radius * u);
          else next.push_back(sphere_point(chi + 0.35 * (even - chi), std::acos(std::clamp(u.z(), -1.0, 1.0))));
        }
        if (step == 1) next.push_back(sphere_point(0.5 * (chi + even), radians(95)));
        if (step == 2) next.push_back(sphere_point(even, radians(140)));
      }
      std::vector<int> new_ring = b.extrude(ring, next, vi);
      std::map<int, int> to_new;
      for (size_t k = 0; k < ring.size(); ++k) to_new[ring[k]] = new_ring[k];
      for (int& v : top) v = to_new[v];
      for (int& v : bottom) v = to_new[v];
      ring = new_ring;
    }
    b.close_between(top, bottom);
  }

  // --- 7. mouth bag behind the lip line -------------------------------------
  std::vector<int> bag_vertices;
  std::vector<Vec3> old_bag;  // the bag's vertices as without options.teeth_mouth_bag (the mouth box)
  {
    std::vector<int> top = upper_line, bottom = lower_line;
    std::vector<int> loop = top;
    for (int k = int(bottom.size()) - 2; k >= 1; --k) loop.push_back(bottom[k]);
    b.orient_loop(loop);
    // Cross-section of the bag (Fig. 4 right): inner lips, then up/down behind
    // the lips towards the gums, then the back of the bag. Offsets (m) from
    // the lip line for the upper side; the lower side mirrors in y.
    const Vec3 profile[] = {{0, 0.0025, -0.0050}, {0, 0.0085, -0.0110}, {0, 0.0075, -0.0230}};
    // With options.teeth_mouth_bag the bag holds the placed teeth (core/
    // components: 0.9 of the mouth's width, their front 12.6 mm behind the
    // slit, 11.1 mm up and 10.3 mm down from the bite, 24.6 mm deep): the
    // inner lips as above; then the vestibule, 13.5 mm up/down at full height
    // across the mouth, 9.5 mm behind the lip line (3 mm in front of the
    // teeth), its corners turned in as before; then the back, flat 41 mm
    // behind the slit (3.8 mm behind the teeth), as tall, its sides at 1.5
    // times the lip columns' x and the corners' at 1.2 (beyond the molars'
    // ends). The mouth's feature box keeps the bag's extent before (local
    // fitting's box, jeong2002 Sec. 4.2), so local fitting is unchanged.
    const Vec3 slit = 0.5 * (b.positions[upper_line[kMouthHalfWidth]] + b.positions[lower_line[kMouthHalfWidth]]);
    VertexInfo vi;
    vi.part = Part::MouthBag;
    std::vector<int> ring = loop;
    for (int step = 0; step < 3; ++step) {
      const Vec3& off = profile[step];
      std::vector<Vec3> next;
      for (int v : loop) {
        const Vec3& p = b.positions[v];
        const int chain = b.info[v].chain;
        const double t = std::min(1.0, std::abs(p.x()) / mouth_half_width);
        const double taper = 1 - 0.6 * t * t;
        Vec3 o(0, chain * off.y() * taper, off.z());
        // The corners of the mouth turn inwards, narrowing the bag behind them.
        if (chain == 0) o.x() = (p.x() > 0 ? -1 : 1) * 0.3 * -off.z();
        Vec3 q = p + o;
        old_bag.push_back(q);
        if (options.teeth_mouth_bag && step == 1) q = Vec3(p.x() + o.x(), p.y() + chain * 0.0135, p.z() - 0.0095);
        if (options.teeth_mouth_bag && step == 2)
          q = Vec3(p.x() * (chain == 0 ? 1.2 : 1.5), chain == 0 ? p.y() : slit.y() + chain * 0.0135, slit.z() - 0.041);
        next.push_back(q);
      }
      std::vector<int> new_ring = b.extrude(ring, next, vi);
      std::map<int, int> to_new;
      for (size_t k = 0; k < ring.size(); ++k) to_new[ring[k]] = new_ring[k];
      for (int& v : top) v = to_new[v];
      for (int& v : bottom) v = to_new[v];
      bag_vertices.insert(bag_vertices.end(), new_ring.begin(), new_ring.end());
      ring = new_ring;
    }
    b.close_between(top, bottom);
  }

  // --- 8. ears ----------------------------------------------------------------
  // The asset's ear (options.ring_ear false): the 2 x 6 root patch extruded
  // into a plate with a rim; its bowl is a vertical strip of quads that
  // Butterfly refines into horizontal ripples (a washboard), and fits look
  // pasted flat. The ring ear (options.ring_ear, docs/journal.md "A
  // ring ear"), for jeong2002 Sec. 4's ear with enough control vertices for
  // helix, antihelix, concha and lobe: every part is a closed ring round the
  // concha, so rows run round the ear as its ridges do:
  //   root (the 16 grid vertices around the hole in the head) -> wall (16,
  //   just off the head) -> helix rim -> helix lip (rolled outwards) ->
  //   antihelix -> concha wall -> concha floor (1 vertex); counts in kEarRings.
  // Rings of different counts are joined by triangle strips (Builder::
  // join_rings), so valences stay 5-7 off the root and the floor is the only
  // extraordinary vertex (valence 8). Each ring is the helix outline scaled
  // about the concha's centre (kEarConchaCenter) with a lift along the
  // head's normal; the lobe (the outline's bottom) is a flat flap.
  std::map<int, std::vector<int>> ear_vertices, ear_rim;
  std::map<int, std::vector<std::array<int, 2>>> ear_binding;
  for (int side : {1, -1}) {
    std::vector<int> loop;
    const int c0 = side * kEarCol0, c1 = side * kEarCol1;
    const int step = side;
    for (int c = c0; c != c1; c += step) loop.push_back(g(kEarLowRow, c));
    for (int r = kEarLowRow; r < kEarHighRow; ++r) loop.push_back(g(r, c1));
    for (int c = c1; c != c0; c -= step) loop.push_back(g(kEarHighRow, c));
    for (int r = kEarHighRow; r > kEarLowRow; --r) loop.push_back(g(r, c0));
    b.orient_loop(loop);
    Vec3 root = Vec3::Zero();
    std::vector<int> patch_ids;
    for (const auto& q : ear_patch[side]) patch_ids.insert(patch_ids.end(), q.begin(), q.end());
    patch_ids = sorted_unique(patch_ids);
    for (int v : patch_ids) root += b.positions[v];
    root /= double(patch_ids.size());
    const Vec3 n = shape.gradient(root).normalized();
    const Vec3 up = (Vec3::UnitY() - Vec3::UnitY().dot(n) * n).normalized();
    const Vec3 back = up.cross(n).normalized() * side;  // -z for both ears
    double half_back = 0, half_up = 0;
    for (int v : loop) {
      const Vec3 d = b.positions[v] - root;
      half_back = std::max(half_back, std::abs(d.dot(back)));
      half_up = std::max(half_up, std::abs(d.dot(up)));
    }
    auto at = [&](double bk, double u, double outward) -> Vec3 { return root + bk * back + u * up + outward * n; };
    if (!options.ring_ear) {
      // The helix (outer rim) outline, by the angle of each loop vertex around the root.
      auto helix = [&](double w, double out_extra, double scale) -> Vec3 {
        // A superellipse: rounder than an ellipse, so the ear is not pointed.
        auto soft = [](double t) { return std::copysign(std::pow(std::abs(t), 0.7), t); };
        const double cw = soft(std::cos(w)), sw = soft(std::sin(w));
        const double lobe = std::max(0.0, -sw);  // the lobe hangs a little behind the root
        const double bk = 0.007 + scale * 0.017 * cw + 0.005 * lobe * lobe;
        const double u = -0.002 + scale * (sw > 0 ? 0.034 : 0.031) * sw;
        const double outward = 0.008 + 0.011 * (0.5 + 0.5 * cw) + 0.003 * lobe + out_extra;
        return at(bk, u, outward);
      };
      std::vector<Vec3> ring_a, ring_b, ring_c;
      // Each root vertex maps to the point of the helix outline at the same
      // fraction of the perimeter, both measured from the top in the same
      // direction: the walls between root and rim do not twist, and the
      // outline is sampled evenly (the root's angles bunch up at its short top
      // and bottom edges, which would make a pointed ear).
      const int n_loop = static_cast<int>(loop.size());
      const EarLoopStart loop_start = ear_loop_start(b.positions, loop, root, back, up, half_back, half_up);
      const int top_k = loop_start.top;
      const double turn = loop_start.turn;
      std::vector<double> root_fraction(n_loop, 0.0);
      double root_length = 0;
      for (int i = 1; i <= n_loop; ++i) {
        const int k0 = (top_k + i - 1) % n_loop, k1 = (top_k + i) % n_loop;
        root_length += (b.positions[loop[k1]] - b.positions[loop[k0]]).norm();
        if (i < n_loop) root_fraction[k1] = root_length;
      }
      // Arc length of the outline, always measured counter-clockwise from the
      // top so that both ears (whose loops turn opposite ways) sample the same points.
      const int samples = 720;
      std::vector<double> outline_length(samples + 1, 0.0);
      for (int i = 1; i <= samples; ++i)
        outline_length[i] = outline_length[i - 1] + (helix(kPi / 2 + 2 * kPi * i / samples, 0, 1.0) -
                                                     helix(kPi / 2 + 2 * kPi * (i - 1) / samples, 0, 1.0)).norm();
      std::vector<double> angle(n_loop);
      for (int k = 0; k < n_loop; ++k) {
        double f = root_fraction[k] / root_length;
        if (turn < 0 && f > 0) f = 1 - f;
        const double target = f * outline_length[samples];
        const int i = std::clamp(static_cast<int>(std::upper_bound(outline_length.begin(), outline_length.end(), target) -
                                                  outline_length.begin()), 1, samples);
        const double t = (target - outline_length[i - 1]) / (outline_length[i] - outline_length[i - 1]);
        const double w = kPi / 2 + 2 * kPi * (i - 1 + t) / samples;
        const Vec3 d = b.positions[loop[k]] - root;
        angle[k] = w;
        ring_a.push_back(at(1.04 * d.dot(back), 1.04 * d.dot(up), d.dot(n) + 0.0035));
        ring_b.push_back(helix(w, 0, 1.0));
        ring_c.push_back(helix(w, 0.0040, 0.82));
      }
      VertexInfo vi;
      vi.part = Part::Ear;
      vi.side = side;
      const std::vector<int> a_ids = b.extrude(loop, ring_a, vi);
      const std::vector<int> b_ids = b.extrude(a_ids, ring_b, vi);
      const std::vector<int> c_ids = b.extrude(b_ids, ring_c, vi);
      std::map<int, int> to_cap;
      for (size_t k = 0; k < loop.size(); ++k) to_cap[loop[k]] = c_ids[k];
      // The patch's inner vertices become the bowl (concha) and the antihelix.
      for (int v : patch_ids) {
        if (to_cap.count(v)) continue;
        const Vec3 d = b.positions[v] - root;
        const double u = d.dot(up) / half_up;  // -1 .. 1
        b.positions[v] = at(0.008, -0.001 + 0.022 * u, 0.006 + 0.005 * u * u + 0.004 * std::max(0.0, u));
        b.info[v].part = Part::Ear;
        b.info[v].side = side;
        ear_vertices[side].push_back(v);
      }
      for (auto q : ear_patch[side]) {
        for (int& v : q)
          if (to_cap.count(v)) v = to_cap[v];
        b.polygons.push_back(q);
      }
      for (int v : loop) ear_vertices[side].push_back(v);
      for (auto* ids : {&a_ids, &b_ids, &c_ids}) ear_vertices[side].insert(ear_vertices[side].end(), ids->begin(), ids->end());
      // Helix landmarks and the binding edges spanning the hollow behind the ear.
      ear_rim[side] = b_ids;
      for (size_t k = 0; k < loop.size(); ++k) {
        if (std::cos(angle[k]) <= 0.2) continue;  // back half only
        ear_binding[side].push_back({loop[k], a_ids[k]});
        ear_binding[side].push_back({a_ids[k], b_ids[k]});
        const VertexInfo& li = b.info[loop[k]];
        if (li.part == Part::Grid && li.col == wrap(c1)) {
          const int behind = g(li.row, c1 + side);
          ear_binding[side].push_back({loop[k], behind});
        }
      }
      continue;
    }
    // The helix outline (behind the root, up, out from the head) at angle w
    // around the ear: w = 90 deg at the top, 0 at the back, 180 at the front.
    auto soft = [](double t) { return std::copysign(std::pow(std::abs(t), 0.7), t); };
    auto lobe_of = [&](double w) { return std::max(0.0, -soft(std::sin(w))); };
    auto outline = [&](double w) -> Vec3 {
      // A superellipse: rounder than an ellipse, so the ear is not pointed.
      const double cw = soft(std::cos(w)), sw = soft(std::sin(w));
      const double lobe = std::max(0.0, -sw);  // the lobe hangs a little behind the root
      return {0.007 + 0.017 * cw + 0.005 * lobe * lobe, -0.002 + (sw > 0 ? 0.034 : 0.031) * sw,
              0.008 + 0.011 * (0.5 + 0.5 * cw) + 0.003 * lobe};
    };
    // A ring: the outline scaled about the concha's centre, lifted along n.
    auto ring_point = [&](double w, double scale, double lift) -> Vec3 {
      const Vec3 o = kEarConchaCenter + scale * (outline(w) - kEarConchaCenter);
      return at(o.x(), o.y(), o.z() + lift);
    };
    // Each root vertex's place along the loop (arc length from the top, in
    // the loop's order) and the outline angle at the same fraction of the
    // outline's length: the walls between root and rim do not twist, and the
    // outline is sampled evenly (the root's angles bunch up at its short top
    // and bottom edges, which would make a pointed ear).
    const int n_loop = static_cast<int>(loop.size());
    const EarLoopStart loop_start = ear_loop_start(b.positions, loop, root, back, up, half_back, half_up);
    const double turn = loop_start.turn;
    std::rotate(loop.begin(), loop.begin() + loop_start.top, loop.end());  // the top first
    std::vector<double> loop_s(n_loop, 0.0);
    double root_length = 0;
    for (int k = 1; k <= n_loop; ++k) {
      root_length += (b.positions[loop[k % n_loop]] - b.positions[loop[k - 1]]).norm();
      if (k < n_loop) loop_s[k] = root_length;
    }
    for (double& s : loop_s) s /= root_length;
    // Arc length of the outline, always measured counter-clockwise from the
    // top so that both ears (whose loops turn opposite ways) sample the same points.
    const int samples = 720;
    std::vector<double> outline_length(samples + 1, 0.0);
    for (int i = 1; i <= samples; ++i)
      outline_length[i] = outline_length[i - 1] + (outline(kPi / 2 + 2 * kPi * i / samples) -
                                                   outline(kPi / 2 + 2 * kPi * (i - 1) / samples)).norm();
    auto angle_at = [&](double s) {  // s: fraction along a ring in the loop's order
      double f = s;
      if (turn < 0 && f > 0) f = 1 - f;
      const double target = f * outline_length[samples];
      const int i = std::clamp(static_cast<int>(std::upper_bound(outline_length.begin(), outline_length.end(), target) -
                                                outline_length.begin()), 1, samples);
      const double t = (target - outline_length[i - 1]) / (outline_length[i] - outline_length[i - 1]);
      return kPi / 2 + 2 * kPi * (i - 1 + t) / samples;
    };
    VertexInfo vi;
    vi.part = Part::Ear;
    vi.side = side;
    // The root patch's inner grid vertices are reused for the concha, so no
    // index is left unused.
    std::vector<int> spare;
    for (int v : patch_ids)
      if (std::find(loop.begin(), loop.end(), v) == loop.end()) spare.push_back(v);
    auto ear_vertex = [&](const Vec3& p) {
      if (spare.empty()) return b.add(p, vi);
      const int v = spare.back();
      spare.pop_back();
      b.positions[v] = p;
      b.info[v] = vi;
      return v;
    };
    // A ring's places by the angle about the concha's centre in the ear's
    // plane, from the outline's top, in the loop's order.
    auto angle_about_concha = [&](const std::vector<int>& ring) {
      auto angle = [&](int v) {
        const Vec3 d = b.positions[v] - root;
        return std::atan2(d.dot(up) - kEarConchaCenter.y(), d.dot(back) - kEarConchaCenter.x());
      };
      const Vec3 top = outline(kPi / 2);
      const double start = std::atan2(top.y() - kEarConchaCenter.y(), top.x() - kEarConchaCenter.x());
      std::vector<double> place;
      for (int v : ring) {
        double t = turn * (angle(v) - start) / (2 * kPi);
        t -= std::floor(t);
        place.push_back(place.empty() && t > 0.5 ? t - 1 : t);
      }
      return place;
    };
    std::vector<int> wall;
    std::vector<double> wall_angle(n_loop);
    for (int k = 0; k < n_loop; ++k) {
      const Vec3 d = b.positions[loop[k]] - root;
      wall_angle[k] = angle_at(loop_s[k]);
      const Vec3 off_root = at(1.04 * d.dot(back), 1.04 * d.dot(up), d.dot(n) + 0.0035);
      wall.push_back(ear_vertex(off_root + kEarWallTowardsRim * (ring_point(wall_angle[k], 1.0, 0.0) - off_root)));
    }
    b.join_rings(loop, loop_s, wall, loop_s);
    std::vector<int> outer = wall;
    std::vector<double> outer_s = loop_s, outer_angle = wall_angle;
    std::vector<std::array<int, 2>> rim_spokes;
    for (const EarRing& spec : kEarRings) {
      std::vector<int> ring;
      std::vector<double> s(spec.count), angle(spec.count);
      for (int k = 0; k < spec.count; ++k) {
        s[k] = double(k) / spec.count;
        angle[k] = angle_at(s[k]);
        const double curl = 1 - lobe_of(angle[k]);  // the lobe is flat
        ring.push_back(ear_vertex(ring_point(angle[k], spec.scale, spec.lift * (spec.lift > 0 ? curl : 1.0))));
      }
      const bool rim = &spec == &kEarRings[0];
      // Wall to rim: the wall follows the root's rectangle, the rim the
      // outline; merged by their places along the ring, the spokes fanned
      // out across the lobe (5 deg slivers). Merged by the angle about the
      // concha's centre instead, they run out from it, as the rings do.
      const auto spokes = rim ? b.join_rings(outer, angle_about_concha(outer), ring, angle_about_concha(ring))
                              : b.join_rings(outer, outer_s, ring, s, turn > 0 ? Builder::Split::Forward : Builder::Split::Backward);
      if (rim) {
        ear_rim[side] = ring;
        // Binding edges over the hollow behind the ear: the wall's spokes
        // to the rim on the back half.
        for (const auto& e : spokes) {
          const auto ko = std::find(outer.begin(), outer.end(), e[0]) - outer.begin();
          const auto ki = std::find(ring.begin(), ring.end(), e[1]) - ring.begin();
          if (std::cos(outer_angle[ko]) > 0.2 && std::cos(angle[ki]) > 0.2) rim_spokes.push_back(e);
        }
      }
      ear_vertices[side].insert(ear_vertices[side].end(), ring.begin(), ring.end());
      outer = ring;
      outer_s = s;
      outer_angle = angle;
    }
    const int floor = ear_vertex(ring_point(kPi / 2, 0.0, kEarConchaFloorLift));
    for (size_t k = 0; k < outer.size(); ++k) b.polygons.push_back({outer[(k + 1) % outer.size()], outer[k], floor});
    ear_vertices[side].push_back(floor);
    for (int v : loop) ear_vertices[side].push_back(v);
    ear_vertices[side].insert(ear_vertices[side].end(), wall.begin(), wall.end());
    // Binding edges (Sec. 4.2) spanning the hollow behind the ear, where
    // scans have no data: root -> wall -> rim on the back half, and the root
    // to the grid vertex behind it.
    for (int k = 0; k < n_loop; ++k) {
      if (std::cos(wall_angle[k]) <= 0.2) continue;  // back half only
      ear_binding[side].push_back({loop[k], wall[k]});
      const VertexInfo& li = b.info[loop[k]];
      if (li.part == Part::Grid && li.col == wrap(c1)) ear_binding[side].push_back({loop[k], g(li.row, c1 + side)});
    }
    for (const auto& e : rim_spokes) ear_binding[side].push_back(e);
  }

  // --- 9. relaxation of the surface grid ---------------------------------------
  // Vertices on the shape (grid and crown) move towards the average of their
  // neighbours, less the average's offset in the plain layout, and are
  // projected back onto the shape. Feature lines stay where they were put.
  {
    std::set<int> pinned;
    for (int side : {1, -1}) {
      for (int v : rim_top[side]) pinned.insert(v);
      for (int v : rim_bottom[side]) pinned.insert(v);
      for (int r = kRimLowRow - 1; r <= kRimLowRow + 2; ++r)
        for (int c = kEyeCol0 - 1; c <= kEyeCol1 + 1; ++c) pinned.insert(g(r, side * c));
      for (int r = kEarLowRow; r <= kEarHighRow; ++r)
        for (int c = kEarCol0; c <= kEarCol1; ++c) pinned.insert(g(r, side * c));
    }
    for (int r = kSlitRow - 1; r <= kSlitRow + 1; ++r)
      for (int c = -kMouthHalfWidth - 1; c <= kMouthHalfWidth + 1; ++c) pinned.insert(g(r, c));
    const int n = static_cast<int>(b.positions.size());
    std::vector<std::set<int>> neighbours(n);
    for (const auto& poly : b.polygons)
      for (size_t k = 0; k < poly.size(); ++k) {
        const int a = poly[k], c = poly[(k + 1) % poly.size()];
        neighbours[a].insert(c);
        neighbours[c].insert(a);
      }
    std::vector<int> movable;
    for (int v = 0; v < n; ++v) {
      const Part part = b.info[v].part;
      if ((part == Part::Grid || part == Part::Cap) && !pinned.count(v)) movable.push_back(v);
    }
    auto average = [&](const std::vector<Vec3>& p, int v) -> Vec3 {
      Vec3 sum = Vec3::Zero();
      for (int w : neighbours[v]) sum += p[w];
      return sum / double(neighbours[v].size());
    };
    std::vector<Vec3> offset(n, Vec3::Zero());
    // The crown patch's plain layout does not follow the face's denser
    // columns, so there (and on the rows meeting it) plain smoothing is right.
    for (int v : movable)
      if (b.info[v].part == Part::Grid && b.info[v].row < kRows - 2)
        offset[v] = average(reference, v) - reference[v];
    for (int it = 0; it < options.relax_iterations; ++it) {
      std::vector<Vec3> next = b.positions;
      for (int v : movable) {
        Vec3 p = b.positions[v] + 0.5 * (average(b.positions, v) - offset[v] - b.positions[v]);
        p = shape.project(p);
        next[v] = p;
      }
      b.positions = next;
    }
  }

  // --- 9b. nostrils (options.nostrils) -----------------------------------------
  // In the quad under the nose on each side (kNostrilRow, columns 0..1) an
  // oval of 8 rim vertices, inset in the quad's bilinear parameters and
  // moved along the quad's normal onto the shape, is joined to the quad's
  // corners by a strip of triangles; the rim continues inwards (up into the
  // nose) as two rings, each narrower and deeper, closed by a strip: a
  // shallow closed pocket (3.9 mm), as the mouth bag is, so the head stays
  // a disk. Built after the relaxation, so every other vertex is
  // where it is without nostrils. Built on the left (+x) and mirrored
  // vertex for vertex and face for face onto the right.
  std::map<int, std::vector<int>> nostril_rim, nostril_pocket;  // by side
  if (options.nostrils) {
    const int p00 = g(kNostrilRow, 0), p10 = g(kNostrilRow, 1), p11 = g(kNostrilRow + 1, 1), p01 = g(kNostrilRow + 1, 0);
    auto remove_quad = [&](std::set<int> corners) {
      for (auto it = b.polygons.begin(); it != b.polygons.end(); ++it)
        if (std::set<int>(it->begin(), it->end()) == corners) {
          b.polygons.erase(it);
          return true;
        }
      return false;
    };
    if (!remove_quad({p00, p10, p11, p01}) ||
        !remove_quad({p00, g(kNostrilRow, -1), g(kNostrilRow + 1, -1), p01}))
      return Status::error(ErrorCode::Internal, "generic head: no quad under the nose for the nostrils");
    const size_t first_new_polygon = b.polygons.size();
    const int first_new_vertex = static_cast<int>(b.positions.size());
    // The quad's corners by their bilinear parameters (u across from the
    // midline, v forwards from the alar base to the tip).
    std::vector<int> loop = {p00, p10, p11, p01};
    const std::map<int, std::array<double, 2>> corner_uv = {{p00, {0, 0}}, {p10, {1, 0}}, {p11, {1, 1}}, {p01, {0, 1}}};
    b.orient_loop(loop);
    auto bilinear = [&](double u, double v) {
      return (1 - u) * (1 - v) * b.positions[p00] + u * (1 - v) * b.positions[p10] + u * v * b.positions[p11] +
             (1 - u) * v * b.positions[p01];
    };
    // The oval: 0.66 x 0.54 of the quad (10.8 x 5.1 mm), its long axis
    // leaning from under the tip (near the columella) back and out towards
    // the alar base, as a nostril does seen from below.
    const double uc = 0.53, vc = 0.50, half_long = 0.33, half_short = 0.27;
    const double axis = std::atan2(1.0, -0.35);
    const Vec3 along(std::cos(axis), std::sin(axis), 0), across(-std::sin(axis), std::cos(axis), 0);
    // The rim turns the way the loop does in (u, v), starting at the oval's front end.
    double area = 0;
    for (size_t k = 0; k < loop.size(); ++k) {
      const auto& a = corner_uv.at(loop[k]);
      const auto& c = corner_uv.at(loop[(k + 1) % loop.size()]);
      area += a[0] * c[1] - c[0] * a[1];
    }
    const double turn = area > 0 ? 1 : -1;
    constexpr int kRimCount = 8;
    std::vector<int> rim;
    std::vector<double> rim_angle;
    VertexInfo rim_info;
    rim_info.part = Part::NostrilRim;
    rim_info.side = 1;
    // One direction for the whole nostril: the quad's normal, outwards
    // (down). The rim is the oval moved along it onto the shape, and the
    // pocket goes in against it: each vertex's own normal (the nearest
    // point of the shape) bent the oval and sent the pocket out through the
    // ala where the tip's, the wings' and the bridge's volumes blend.
    Vec3 out_dir = (b.positions[p11] - b.positions[p00]).cross(b.positions[p01] - b.positions[p10]).normalized();
    if (out_dir.dot(shape.gradient(bilinear(0.5, 0.5))) < 0) out_dir = -out_dir;
    auto onto_shape = [&](const Vec3& p) {  // the shape's point nearest p along out_dir
      const double step = 0.0001;
      for (double t = 0; t < 0.01; t += step)
        for (double sign : {1.0, -1.0}) {
          const Vec3 a = p + sign * t * out_dir, c = p + sign * (t + step) * out_dir;
          if ((shape.distance(a) < 0) == (shape.distance(c) < 0)) continue;
          Vec3 lo = a, hi = c;
          for (int k = 0; k < 40; ++k) {
            const Vec3 mid = 0.5 * (lo + hi);
            ((shape.distance(mid) < 0) == (shape.distance(lo) < 0) ? lo : hi) = mid;
          }
          return Vec3(0.5 * (lo + hi));
        }
      return p;
    };
    for (int k = 0; k < kRimCount; ++k) {
      const double t = turn * 2 * kPi * k / kRimCount;
      const Vec3 uv = Vec3(uc, vc, 0) + half_long * std::cos(t) * along + half_short * std::sin(t) * across;
      rim.push_back(b.add(onto_shape(bilinear(uv.x(), uv.y())), rim_info));
      rim_angle.push_back(std::atan2(uv.y() - vc, uv.x() - uc));
    }
    // Places along the rings from the rim's first vertex, in the loop's turn.
    auto place = [&](double angle) {
      double s = turn * (angle - rim_angle[0]) / (2 * kPi);
      return s - std::floor(s);
    };
    std::vector<double> s_rim, s_loop;
    for (double a : rim_angle) s_rim.push_back(place(a));
    for (int v : loop) s_loop.push_back(place(std::atan2(corner_uv.at(v)[1] - vc, corner_uv.at(v)[0] - uc)));
    const int start = static_cast<int>(std::min_element(s_loop.begin(), s_loop.end()) - s_loop.begin());
    std::rotate(loop.begin(), loop.begin() + start, loop.end());
    std::rotate(s_loop.begin(), s_loop.begin() + start, s_loop.end());
    b.join_rings(loop, s_loop, rim, s_rim);
    // The pocket: two rings, 1.8 and 3.8 mm in (against out_dir),
    // 25 % and 55 % of the way to the rim's centre, then closed across.
    Vec3 centre = Vec3::Zero();
    for (int v : rim) centre += b.positions[v];
    centre /= double(kRimCount);
    VertexInfo pocket_info;
    pocket_info.part = Part::NostrilPocket;
    pocket_info.side = 1;
    std::vector<int> ring = rim, pocket;
    for (const auto& [depth, inward] : {std::pair<double, double>{0.0018, 0.25}, {0.0038, 0.55}}) {
      std::vector<Vec3> next;
      for (int v : rim) {
        const Vec3& p = b.positions[v];
        next.push_back(p - depth * out_dir + inward * (centre - p));
      }
      ring = b.extrude(ring, next, pocket_info);
      pocket.insert(pocket.end(), ring.begin(), ring.end());
    }
    std::vector<int> top(ring.begin(), ring.begin() + kRimCount / 2 + 1), bottom = {ring[0]};
    for (int k = kRimCount - 1; k >= kRimCount / 2; --k) bottom.push_back(ring[k]);
    b.close_between(top, bottom);
    nostril_rim[1] = rim;
    nostril_pocket[1] = pocket;
    // The right nostril: each new vertex mirrored, each face mirrored with
    // its winding reversed (the quad's corners map column c -> -c).
    std::map<int, int> to_right = {{p00, p00}, {p01, p01}, {p10, g(kNostrilRow, -1)}, {p11, g(kNostrilRow + 1, -1)}};
    const int last_new_vertex = static_cast<int>(b.positions.size());
    for (int v = first_new_vertex; v < last_new_vertex; ++v) {
      VertexInfo vi = b.info[v];
      vi.side = -1;
      const Vec3 p = b.positions[v];
      to_right[v] = b.add(Vec3(-p.x(), p.y(), p.z()), vi);
    }
    const size_t last_new_polygon = b.polygons.size();
    for (size_t f = first_new_polygon; f < last_new_polygon; ++f) {
      std::vector<int> poly = b.polygons[f];
      for (int& v : poly) v = to_right.at(v);
      std::reverse(poly.begin(), poly.end());
      b.polygons.push_back(poly);
    }
    for (int v : rim) nostril_rim[-1].push_back(to_right.at(v));
    for (int v : pocket) nostril_pocket[-1].push_back(to_right.at(v));
  }

  // --- 10. mirror symmetry: pair vertices and make the pairs exact -----------
  const int nv = static_cast<int>(b.positions.size());
  std::vector<int> mirror(nv, -1);
  for (int v = 0; v < nv; ++v) {
    if (mirror[v] >= 0) continue;
    const Vec3 m(-b.positions[v].x(), b.positions[v].y(), b.positions[v].z());
    int best = -1;
    double best_d = 1e-6;
    for (int w = 0; w < nv; ++w) {
      const double d = (b.positions[w] - m).norm();
      if (d < best_d && (mirror[w] < 0)) best = w, best_d = d;
    }
    if (best < 0)
      return Status::error(ErrorCode::Internal, "generic head: vertex " + std::to_string(v) +
                                                    " has no mirror partner");
    mirror[v] = best;
    mirror[best] = v;
  }
  for (int v = 0; v < nv; ++v) {
    if (mirror[v] == v) {
      b.positions[v].x() = 0;
    } else if (v < mirror[v]) {
      const Vec3& p = b.positions[v];
      b.positions[mirror[v]] = Vec3(-p.x(), p.y(), p.z());
    }
  }

  // --- 11. triangles: split quads along their better diagonal ---------------
  TriMesh& mesh = out.mesh;
  mesh = TriMesh{};
  mesh.positions = b.positions;
  // Whether a quad is split along poly[0] - poly[2]: the chevron where it
  // applies, else the diagonal with the larger smallest angle.
  auto split_02 = [&](const std::vector<int>& poly) {
    const int chevron = options.regular_nape ? chevron_diagonal(b.info, poly) : -1;
    if (chevron >= 0) return chevron == 0;
    auto smallest_cos = [&](int a, int c, int d) {  // cosine of the smallest angle
      const Vec3 &pa = b.positions[a], &pc = b.positions[c], &pd = b.positions[d];
      auto cos_at = [](const Vec3& o, const Vec3& u, const Vec3& v) {
        return (u - o).normalized().dot((v - o).normalized());
      };
      return std::max({cos_at(pa, pc, pd), cos_at(pc, pd, pa), cos_at(pd, pa, pc)});
    };
    const double d02 = std::max(smallest_cos(poly[0], poly[1], poly[2]), smallest_cos(poly[0], poly[2], poly[3]));
    const double d13 = std::max(smallest_cos(poly[0], poly[1], poly[3]), smallest_cos(poly[1], poly[2], poly[3]));
    return d02 <= d13;
  };
  // With mirror_diagonals a quad on the right (-x) is split as its mirror
  // image on the left is, so the triangles mirror as the vertices do. Each
  // side by its own shape, 6 quads of each eye pocket (whose two diagonals
  // tie: planar, symmetric quads) split the same way on both sides.
  auto key_of = [](std::array<int, 4> q) {
    std::sort(q.begin(), q.end());
    return q;
  };
  auto centre_x = [&](const std::vector<int>& poly) {
    double x = 0;
    for (int v : poly) x += b.positions[v].x();
    return x / double(poly.size());
  };
  std::map<std::array<int, 4>, std::array<int, 2>> left_diagonal;  // by the quad's sorted corners
  if (options.mirror_diagonals)
    for (const auto& poly : b.polygons)
      if (poly.size() == 4 && centre_x(poly) >= -1e-9) {
        const bool s02 = split_02(poly);
        left_diagonal[key_of({poly[0], poly[1], poly[2], poly[3]})] =
            s02 ? std::array<int, 2>{poly[0], poly[2]} : std::array<int, 2>{poly[1], poly[3]};
      }
  for (const auto& poly : b.polygons) {
    if (poly.size() == 3) {
      mesh.triangles.push_back({poly[0], poly[1], poly[2]});
      continue;
    }
    bool split = split_02(poly);
    if (options.mirror_diagonals && centre_x(poly) < -1e-9) {
      const auto it = left_diagonal.find(key_of({mirror[poly[0]], mirror[poly[1]], mirror[poly[2]], mirror[poly[3]]}));
      if (it != left_diagonal.end()) {
        const int d0 = mirror[it->second[0]], d1 = mirror[it->second[1]];
        split = (d0 == poly[0] && d1 == poly[2]) || (d0 == poly[2] && d1 == poly[0]);
      }
    }
    if (split) {
      mesh.triangles.push_back({poly[0], poly[1], poly[2]});
      mesh.triangles.push_back({poly[0], poly[2], poly[3]});
    } else {
      mesh.triangles.push_back({poly[0], poly[1], poly[3]});
      mesh.triangles.push_back({poly[1], poly[2], poly[3]});
    }
  }
  MeshTopology topo;
  Status st = build_topology(mesh, topo);
  if (!st.ok()) return with_context(st, "generic head construction");
  if (topo.boundary_loops.size() != 1 || euler_characteristic(topo, mesh.num_triangles()) != 1)
    return Status::error(ErrorCode::Internal, "generic head is not a disk (" +
                                                  std::to_string(topo.boundary_loops.size()) +
                                                  " boundary loops)");

  // --- 11b. fairing of the skin's control vertices on the shape ---------------
  // The shape is smooth, but its smooth Butterfly surface was furrowed over
  // the brows, under the eyes, across the cheeks and beside the nose: the
  // interpolating stencils see a grid bent round the eye and mouth rings,
  // its rows bunched and skewed there, and sag and bulge between them (the
  // same level-3 vertices projected onto the shape show no furrow).
  // Taubin passes (lambda 0.5, mu -0.53, uniform weights over the
  // triangles) even the skin's control vertices out, each pass projected
  // back onto the shape, so the shape is kept and only the sampling moves.
  // Only the face's grid moves: the eye rims, the lip lines, the ears'
  // roots, the midline (the profile: nasion, bridge, tip, lips, chin), the
  // nose (its landmarks and box stay as cast), the regular rows behind the ears, the crown, and everything off the shape
  // (pockets, mouth bag, ears, neck) stay. After the quads are split, so the
  // triangles are those of the skin as cast.
  // The skin as cast: what the alignment matches (GenericHead::
  // alignment_positions) and where the annotations below are taken, so a
  // faired head is annotated and aligned exactly as the cast one.
  const std::vector<Vec3> cast_positions = mesh.positions;
  if (options.fair_iterations > 0) {
    std::vector<char> fixed(nv, 0);
    for (int v = 0; v < nv; ++v) {
      const VertexInfo& vi = b.info[v];
      const int from_midline = std::min(vi.col, kColumns - vi.col);
      const bool nose = (from_midline == 1 && vi.row >= 9 && vi.row <= 14) ||
                        (from_midline == 2 && vi.row >= 10 && vi.row <= 13);
      fixed[v] = vi.part != Part::Grid || vi.col == 0 || nose || from_midline >= kBackDiagonalColumn;
    }
    for (int side : {1, -1})
      for (int r = kEarLowRow; r <= kEarHighRow; ++r)
        for (int c = kEarCol0; c <= kEarCol1; ++c) fixed[g(r, side * c)] = 1;
    // The eye rims and lip lines, and (fair_keep_rim_rings) that many rings
    // round them, stay as cast, so the faired grid meets the creases as the
    // cast one does.
    std::vector<int> rims(upper_line.begin(), upper_line.end());
    rims.insert(rims.end(), lower_line.begin(), lower_line.end());
    for (int side : {1, -1}) {
      rims.insert(rims.end(), rim_top[side].begin(), rim_top[side].end());
      rims.insert(rims.end(), rim_bottom[side].begin(), rim_bottom[side].end());
    }
    const std::vector<int> from_rims = ring_distances(topo, rims, options.fair_keep_rim_rings);
    for (int v = 0; v < nv; ++v) fixed[v] = fixed[v] || from_rims[v] >= 0;
    std::vector<std::vector<int>> neighbours(nv);
    for (const Tri& t : mesh.triangles)
      for (int k = 0; k < 3; ++k) {
        neighbours[t[k]].push_back(t[(k + 1) % 3]);
        neighbours[t[k]].push_back(t[(k + 2) % 3]);
      }
    for (auto& n : neighbours) n = sorted_unique(n);
    std::vector<Vec3>& P = mesh.positions;
    for (int it = 0; it < options.fair_iterations; ++it)
      for (double lambda : {0.5, -0.53}) {
        std::vector<Vec3> next = P;
        for (int v = 0; v < nv; ++v) {
          if (fixed[v]) continue;
          Vec3 avg = Vec3::Zero();
          for (int w : neighbours[v]) avg += P[w];
          next[v] += lambda * (avg / double(neighbours[v].size()) - P[v]);
          if (lambda < 0) next[v] = shape.project(next[v]);
        }
        P = next;
      }
    // The passes are symmetric up to rounding; make the pairs exact again.
    for (int v = 0; v < nv; ++v) {
      if (mirror[v] == v) {
        P[v].x() = 0;
      } else if (v < mirror[v]) {
        P[mirror[v]] = Vec3(-P[v].x(), P[v].y(), P[v].z());
      }
    }
  }

  if (options.fair_iterations > 0) out.alignment_positions = cast_positions;

  // --- 12. annotations ------------------------------------------------------
  const auto& P = cast_positions;
  auto azimuth_deg = [&](int col) {
    double a = column_azimuth(col) * 180 / kPi;
    return a > 180 ? a - 360 : a;
  };
  std::map<std::string, std::vector<int>> R;
  for (int v = 0; v < nv; ++v) {
    const VertexInfo& vi = b.info[v];
    if (vi.part == Part::Cap) {
      R["scalp"].push_back(v);
      continue;
    }
    if (vi.part == Part::EyePocket || vi.part == Part::MouthBag || vi.part == Part::LowerLipLine) {
      R["face"].push_back(v);
      continue;
    }
    if (vi.part == Part::Neck) {
      R["neck"].push_back(v);
      continue;
    }
    if (vi.part != Part::Grid) continue;
    const int r = vi.row;
    const double a = std::abs(azimuth_deg(vi.col));
    const int cc = vi.col > kColumns / 2 ? vi.col - kColumns : vi.col;
    const int h = r;  // head row index
    if (h >= 0 && h <= 21 && a <= 70) R["face"].push_back(v);
    if (h == 0 && a > 35) R["neck"].push_back(v);
    if (h >= 21 || (h >= 8 && a >= 105) || (h >= 18 && a > 70)) R["scalp"].push_back(v);
    if (h >= 0 && h <= 3 && a <= 25) R["chin"].push_back(v);
    if (h >= 0 && h <= 5 && a > 25 && a <= 110) R["jaw"].push_back(v);
    if (h >= 6 && h <= 14 && a >= 30 && a <= 75) R["cheeks"].push_back(v);
    if (h >= 18 && h <= 20 && a <= 55) R["brow"].push_back(v);
    if ((cc == 0 && h >= 9 && h <= 18) || (std::abs(cc) == 1 && h >= 9 && h <= 14) ||
        (std::abs(cc) == 2 && h >= 10 && h <= 13))
      R["nose"].push_back(v);
    if (r >= kSlitRow - 1 && r <= kSlitRow + 1 && std::abs(cc) <= kMouthHalfWidth + 1) {
      R["lips"].push_back(v);
      if (r == kSlitRow + 1 || (r == kSlitRow && vi.chain == 1)) R["upper_lip"].push_back(v);
      if (r == kSlitRow - 1) R["lower_lip"].push_back(v);
    }
  }
  for (int v : lower_line) {
    if (b.info[v].chain == 0) continue;
    R["lips"].push_back(v);
    R["lower_lip"].push_back(v);
  }
  for (int v : bag_vertices) {
    R["lips"].push_back(v);
    if (b.info[v].chain > 0) R["upper_lip"].push_back(v);
    if (b.info[v].chain < 0) R["lower_lip"].push_back(v);
  }
  // The nostrils: rim and pocket are the nose's (they move with it) and the
  // face's (as the other pockets are); the pocket behind each rim is
  // nostril_left / nostril_right.
  for (int side : {1, -1}) {
    for (const auto* ids : {&nostril_rim[side], &nostril_pocket[side]})
      for (int v : *ids) {
        R["face"].push_back(v);
        R["nose"].push_back(v);
      }
    if (!nostril_pocket[side].empty()) R[side > 0 ? "nostril_left" : "nostril_right"] = nostril_pocket[side];
  }
  R["ear_left"] = ear_vertices[1];
  R["ear_right"] = ear_vertices[-1];
  if (options.ring_ear) {  // the helix rims (the asset's plate ear does not name them)
    R["ear_rim_left"] = ear_rim[1];
    R["ear_rim_right"] = ear_rim[-1];
  }
  R["ears"] = ear_vertices[1];
  R["ears"].insert(R["ears"].end(), ear_vertices[-1].begin(), ear_vertices[-1].end());
  R["eye_rim_left"] = ann.eye_left.rim;
  R["eye_rim_right"] = ann.eye_right.rim;
  for (auto& [name, ids] : R) ids = sorted_unique(ids);

  // Feature boxes with landmarks (Sec. 4.2: 3 per ear, 4 for nose and mouth).
  auto make_box = [&](const std::string& name, const std::vector<int>& ids, double margin,
                      const std::vector<int>& landmarks) {
    FeatureBox fb;
    fb.name = name;
    const BBox bb = box_of(P, ids);
    fb.min = bb.min - Vec3::Constant(margin);
    fb.max = bb.max + Vec3::Constant(margin);
    fb.landmarks = landmarks;
    return fb;
  };
  for (int side : {1, -1}) {
    const std::vector<int>& rim = ear_rim[side];
    auto pick = [&](auto better) {
      int best = rim[0];
      for (int v : rim)
        if (better(P[v], P[best])) best = v;
      return best;
    };
    const int top = pick([](const Vec3& p, const Vec3& q) { return p.y() > q.y(); });
    const int lobe = pick([](const Vec3& p, const Vec3& q) { return p.y() < q.y(); });
    const int back = pick([](const Vec3& p, const Vec3& q) { return p.z() < q.z(); });
    ann.boxes.push_back(make_box(side > 0 ? "ear_left" : "ear_right", ear_vertices[side], 0.010,
                                 {top, back, lobe}));
  }
  {
    int tip = g(0, 0), nasion = -1;
    for (int r = 9; r <= 14; ++r)
      if (P[g(r, 0)].z() > P[tip].z()) tip = g(r, 0);
    for (int r = 16; r <= 19; ++r)
      if (nasion < 0 || P[g(r, 0)].z() < P[nasion].z()) nasion = g(r, 0);
    int ala_left = -1;
    for (int v : R["nose"])
      if (ala_left < 0 || P[v].x() > P[ala_left].x()) ala_left = v;
    ann.boxes.push_back(make_box("nose", R["nose"], 0.008, {nasion, tip, ala_left, mirror[ala_left]}));
  }
  {
    std::vector<int> mouth_ids = R["lips"];
    FeatureBox box = make_box("mouth", mouth_ids, 0.008,
                              {upper_line.front(), upper_line.back(), g(kSlitRow + 1, 0), g(kSlitRow - 1, 0)});
    if (options.teeth_mouth_bag) {  // the box of the bag before (see step 7)
      std::vector<Vec3> pts = old_bag;
      std::vector<char> in_bag(P.size(), 0);
      for (int v : bag_vertices) in_bag[static_cast<size_t>(v)] = 1;
      for (int v : mouth_ids)
        if (!in_bag[static_cast<size_t>(v)]) pts.push_back(P[v]);
      std::vector<int> all(pts.size());
      for (size_t i = 0; i < all.size(); ++i) all[i] = static_cast<int>(i);
      const BBox bb = box_of(pts, all);
      box.min = bb.min - Vec3::Constant(0.008);
      box.max = bb.max + Vec3::Constant(0.008);
    }
    ann.boxes.push_back(box);
  }
  // Binding edges: behind the ears, plus virtual upper-lower lip edges.
  for (int side : {1, -1})
    for (const auto& e : ear_binding[side]) ann.binding_edges.push_back(e);
  for (size_t k = 1; k + 1 < upper_line.size(); ++k)
    ann.binding_edges.push_back({upper_line[k], lower_line[k]});
  ann.constrained_vertices = sorted_unique(bag_vertices);

  // Clipping planes (Sec. 4.1): below the jaw, and the hair-covered back.
  double jaw_bottom = 1e9;
  for (int v : R["jaw"]) jaw_bottom = std::min(jaw_bottom, P[v].y());
  for (int v : R["chin"]) jaw_bottom = std::min(jaw_bottom, P[v].y());
  ann.neck_clip.point = Vec3(0, jaw_bottom - 0.015, 0);
  ann.neck_clip.normal = Vec3::UnitY();
  ann.back_clip.point = Vec3(0, 0, -0.045);
  ann.back_clip.normal = Vec3(0, -0.3, 1).normalized();
  ann.look = Vec3::UnitZ();
  ann.up = Vec3::UnitY();
  ann.regions = R;
  // Rims where the skin folds back into a pocket ~0.3-1.3 mm behind it: as
  // creases, the skin's Butterfly stencils no longer reach over the rim into
  // the pocket (which made the refined lips and lids cross themselves and
  // the rims ragged). The lip lines are open curves: the mouth corners,
  // where the upper and lower lines meet, are corners of both.
  ann.creases.push_back({"eye_rim_left", ann.eye_left.rim, true});
  ann.creases.push_back({"eye_rim_right", ann.eye_right.rim, true});
  ann.creases.push_back({"upper_lip_line", upper_line, false});
  ann.creases.push_back({"lower_lip_line", lower_line, false});
  if (options.nostrils) {
    ann.creases.push_back({"nostril_rim_left", nostril_rim[1], true});
    ann.creases.push_back({"nostril_rim_right", nostril_rim[-1], true});
  }
  const Vec3 slit_mid = 0.5 * (P[upper_line[kMouthHalfWidth]] + P[lower_line[kMouthHalfWidth]]);
  ann.mouth_center = slit_mid - Vec3(0, 0, 0.008);
  ann.mouth_width = (P[upper_line.front()] - P[upper_line.back()]).norm();
  return Status::success();
}

}  // namespace lk
