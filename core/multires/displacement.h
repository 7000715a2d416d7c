// The scalar normal displacements of jeong2002 Sec. 5: before each Butterfly
// refinement, every vertex's signed distance along its normal to the surface
// the scan points sample near that normal line. One scalar per vertex and
// level (d_l, #V_l), stored in MultiresMesh::displacements.
//
// jeong2002 measures on dense scans (Table 1: 50k+ points on a head). Real
// scans can be much sparser or patchy (a Cyberware face patch with points
// 3.4 mm apart, five to six times the level-3 edge), so each measurement
// adapts to the data near the vertex:
//   - footprint: the disk around the normal line grows until it holds
//     footprint_points points (the LOCAL point spacing sets the finest detail
//     a displacement can carry), never below half an edge of the level;
//   - the points are weighted by a smooth kernel of their distance from the
//     line, so neighbouring vertices see nearly the same data and the
//     displaced surface is smooth where the samples are far apart;
//   - the height field is fitted to the points' heights ABOVE THE BASE
//     SURFACE (the level's undisplaced mesh around the vertex, a quadric
//     through its one-ring), with a ridge towards zero: few or badly spread
//     points keep the base surface's shape and only shift it, dense ones
//     give the full least-squares quadric as before;
//   - data support: where the points lie on one side of the line (the
//     scan's edge, a hole) the displacement tapers to 0 instead of
//     extrapolating the height field beyond the data.
//   - noise: on the finest level, where the fit's own residuals say its
//     height is uncertain against the level's edge (dense noisy scans),
//     footprints of 2, 4, ... times the points are fitted too and the
//     widest that agrees with all narrower ones is kept (intersection of
//     confidence intervals, Goldenshluger & Nemirovski 1997, Katkovnik
//     1999): the noise is averaged, the detail the narrow fits agree on
//     is kept (opt-in);
//   - and, by default, the finest level's heights are smoothed over the
//     mesh's one-rings, each weighted by its standard error, only between
//     neighbours that agree within their errors (DisplacementOptions::
//     smooth_*).
#pragma once
#include "common/progress.h"
#include "common/status.h"
#include "mesh/tri_mesh.h"
#include "multires/multires.h"

#include <vector>

namespace lk {

struct DisplacementOptions {
  // Fixed radius of the cylinder around a vertex's normal line that collects
  // scan points (the kernel's support). 0: adaptive, the smallest radius
  // whose cylinder holds footprint_points points, but at least half the mean
  // edge length of the level being measured (the footprint shrinks with the
  // triangles where the data allows) and at most max_radius.
  double radius = 0.0;
  // Points the adaptive footprint gathers. The kernel weights them (1 -
  // (rho/R)^2)^2, so about half of them count: 16 points weigh like 9, a
  // margin over the 6 coefficients of the quadric; larger footprints blur
  // the face.
  int footprint_points = 16;
  // Noise (jeong2002 measures on clean dense scans; ours carry 0.2 mm depth
  // noise over level-3 edges of ~1.3 mm): where the footprint_points fit's
  // height has a standard error above noise_edge_fraction x the level's
  // mean edge (estimated from the fit's own residuals), footprints of 2, 4,
  // ... times the points, up to max_footprint_points and a radius of
  // noise_max_radius_edges edges, are fitted too, and the widest whose
  // height agrees with every narrower one within noise_confidence standard
  // errors is used (intersection of confidence intervals: a wider footprint
  // that disagrees is smoothing away detail, not noise). Sparse scans
  // (Fran, James) mostly have footprints wider than that radius already:
  // they are measured as before. Only where the first footprint holds
  // exactly footprint_points (its radius is set by the points, not by half
  // an edge) and the line crosses one sheet (near lips and lids a wider
  // footprint reaches the other sheet). max_footprint_points <=
  // footprint_points: off. Off by default (16 = footprint_points): it
  // costs time and left lip crossings; the smoothing over the mesh below
  // (on by default) reaches the same roughness for a fraction of the time
  // (figures: docs/design/subdiv_multires.md). `likeness fit
  // --widen-footprints` and the bench's --fit-noise-points 128 turn it on.
  int max_footprint_points = 16;
  double noise_edge_fraction = 0.01;
  double noise_max_radius_edges = 2.5;
  double noise_confidence = 2.0;
  // ... on this many of the finest levels. Each level's displacements are
  // measured after the coarser ones are applied, so a coarser level's
  // smoothing is undone by the finer levels where the data is dense; the
  // finest level's noise nothing corrects (the orange-peel). Coarser
  // levels' residuals mix noise with detail their quadric cannot follow,
  // which the interval test takes for noise: widening every level cost
  // the real scans accuracy.
  int noise_finest_levels = 1;
  // Denoising by smoothing over the mesh (on by default): on this many of
  // the finest levels, the measured heights (#V_l, above the level's base
  // surface; a vertex a coarser level measured has height 0 there, with
  // that level's error) are smoothed over the level's one-rings, each
  // vertex weighted by its own height's standard error (the
  // footprint_points fit's, from its residuals pooled over the one-ring):
  // smooth_iterations Jacobi steps of the screened smoothing
  //   min sum_v (x_v - h_v)^2 / s_v^2
  //       + smooth_strength / median(s^2) sum_edges w_uv (x_u - x_v)^2,
  // where a neighbour counts fully (w_uv = 1) while the two heights agree
  // within smooth_agreement x sqrt(s_u^2 + s_v^2) and not at all from twice
  // that on (a lip edge, a nostril, a lid: real detail the noise cannot
  // explain), and no vertex moves farther than smooth_agreement x s_v from
  // its own measurement (the result stays inside its confidence interval).
  // Work shared between neighbours instead of wider footprints: O(#V x
  // ring x iterations), no search. Neighbours are neighbours on the mesh,
  // so the smoothing never reaches across closed lips to the other lip
  // (the widened 3-D footprints did). 0 levels: off
  // (`likeness fit --no-denoise`).
  // Two levels: a coarser level's heights are what the finer one is
  // measured against and are never measured again (one displacement per
  // vertex), so smoothing the finest level alone left the level before's
  // noise in a quarter of its vertices. Level 2 needs the height and
  // normal rules below, or it crosses an ear's fold. Figures:
  // docs/design/subdiv_multires.md.
  int smooth_finest_levels = 2;
  int smooth_iterations = 8;
  double smooth_strength = 1.0;
  double smooth_agreement = 2.0;
  // Only vertices whose footprint radius is at most this many of the
  // finest level's mean edges take part (on every smoothed level; the
  // level's own edge would let a sparse scan's level 2 in): neighbours a
  // wider footprint apart see nearly the same points already (sparse
  // scans' level-3 footprints are several edges wide), their heights are
  // as smooth as the data allows, and their residuals are the misfit of
  // real detail, not noise (smoothing them cost the real scans accuracy).
  double smooth_max_radius_edges = 2.0;
  // A vertex's pooled noise (from its fit's residuals) counts as at most
  // this many times the level's median noise (standard deviations): above
  // that the residuals are the quadric's misfit of real detail, not the
  // scanner's noise, and must not make the vertex's own height the least
  // trusted. 0: no cap.
  double smooth_noise_cap = 1.5;
  // No height moves (or is compared with a neighbour's) by more than
  // smooth_agreement x min(its standard error, smooth_move_cap x the
  // level's median standard error). 0: its own standard error only.
  double smooth_move_cap = 1.0;
  // Heights are along each vertex's own normal: neighbours count fully
  // while their (base) normals are at most this many degrees apart, not
  // at all from twice that on (ear rims, lids, lip edges). 0: off.
  double smooth_normal_degrees = 10.0;
  // Only heights within this many of the level's median standard errors
  // of the base surface take part: a taller one is detail the coarser
  // levels missed (an ear's fold, a nostril), not noise. 0: no limit.
  double smooth_max_height_errors = 4.0;
  // Largest adaptive radius. 0: the larger of half the level's mean edge and
  // twice the mean point spacing sqrt(level area / #points) over the whole
  // level (a patchy scan is denser where it has data, so its footprints fit
  // well inside); a line that finds fewer than min_points within it has no
  // data.
  double max_radius = 0.0;
  // Points farther than this along the normal are ignored (another sheet of
  // the surface, outliers). 0: twice the larger of the mean edge length of
  // the level and the radius.
  double max_distance = 0.0;
  // On levels >= 1 the line is also at most this many times the larger of
  // the level's mean edge and the radius long (each side): the coarser
  // levels already put the surface near the data, and a long line only
  // reaches the other sheet of thin features and costs search time (1 vs
  // off on the synthetic heads: same mean distance, a third fewer folded
  // triangles to limit, ~20 % fewer crossing pairs). 0: off.
  double fine_line_edges = 1.0;
  // When the cloud has normals (#P, as scanners give them), a point counts
  // only if its normal and the vertex normal agree: dot of the unit normals
  // above this. Thin features put two sheets facing away from each other
  // within a normal line (upper against lower lip, the two sides of an ear
  // rim, lid against socket); their points face the other way and are not
  // taken for the vertex's own sheet. Below -1: off.
  double min_normal_agreement = 0.0;
  // Fewer points than this in the cylinder means "no data": displacement 0,
  // and the subdivision surface stays smooth there (Sec. 5).
  int min_points = 3;
  // The line may cross the scan more than once (ears, lips): sorted by
  // height above the base surface, a gap wider than this fraction of
  // max_distance (plus half the local point spacing) separates two sheets,
  // and only the sheet nearest to the vertex is used.
  double cluster_fraction = 0.25;
  // Ridge on the height field's slope and curvature coefficients (scaled to
  // the footprint), as a fraction of the summed kernel weights: negligible
  // for a well-spread footprint, it keeps the base surface's shape where
  // the points cannot tell (few, or all in a line). 0: plain least squares.
  double ridge = 1e-3;
  // Data support: the kernel-weighted centroid of the points, off the line
  // by this fraction of the radius or less, counts as all round (the full
  // displacement). 16 points spread all round are off by 0.06 per axis
  // (std), so 0.2 is a 3-sigma event; 0.12 tapered most interior vertices
  // of a sparse plane a little and left it 3 sigma off the truth.
  double support_full_offset = 0.2;
  // ... and at this offset or more the line lies at or beyond the data's
  // edge (a half disk of uniform samples is off by 0.29): displacement 0.
  // Between the two the displacement tapers smoothly, over about a third
  // of the footprint inside the data's edge.
  double support_zero_offset = 0.4;
  // Points in regions this many times sparser than the scan's typical
  // sampling are ignored (see isolated_scan_points): the sparse returns of
  // hair and stray reflections, which a footprint that grows to hold
  // footprint_points points would otherwise take for a surface (bumps along
  // the hairline). A scan that is sparse everywhere (Fran) keeps all its
  // points: the test is relative to the scan's own median spacing. 0: off.
  // 30 halves the synthetic heads' truth-to-surface distance against off;
  // 10 also drops sparse but real points behind the ears.
  double isolated_density_ratio = 30.0;
  // The data's edge (the neck cut, the border of a face-only scan, a
  // scan's hole). Sec. 5 leaves the surface smooth where there is no data,
  // so on every level the vertices just outside the data kept d = 0 while
  // those just inside followed the scan: where the data and the control
  // mesh's smooth surface disagree, a ledge about one edge of a fine level
  // wide (a ridge round James's face). Instead, on every level, the
  // displacements of the fully supported vertices along the edge are
  // carried into the vertices without full support (each takes the mean of
  // its neighbours', so they are averaged along the edge too) and faded out
  // with a smoothstep of the distance over the level's edges from the
  // supported vertices, reaching 0 at this many of the control mesh's mean
  // edges: the surface passes from the data to the smooth surface as a
  // slope, not a step. Fully supported vertices keep their measurement; a
  // partly supported one (support taper s < 1) takes s of its measurement
  // plus 1 - s of the carried value. The band does not turn round rims
  // (neighbours whose normals differ by more than 15 degrees). One control
  // edge is too short: a control vertex just past the data is a whole edge
  // from the last supported one and gets nothing (the flat-patch test).
  // 0: off (the ledge).
  double edge_fade_control_edges = 2.0;
  // jeong2002 stores one displacement per vertex introduced on each level;
  // vertices inherited from the coarser level already lie on the data. Set
  // to re-measure them on every level as well.
  bool remeasure_coarse_vertices = false;
};

struct DisplacementStats {
  std::vector<int> measured;       // L+1: vertices with data, per level
  std::vector<int> candidates;     // L+1: vertices measured for, per level
  std::vector<double> mean_abs;    // L+1: mean |d| over measured vertices
  std::vector<double> max_abs;     // L+1
  std::vector<int> tapered;        // L+1: measured vertices whose d the support taper reduced
  std::vector<double> mean_radius; // L+1: mean footprint radius over measured vertices
  std::vector<int> widened;        // L+1: measured vertices whose footprint the noise widened
  std::vector<int> smoothed;       // L+1: vertices the smoothing over the mesh moved (denoising)
  std::vector<double> mean_smoothing;  // L+1: their mean |change| of d
  std::vector<int> faded;          // L+1: vertices without full support given a share of their edge's displacement
  double edge_fade_width = 0;      // the fade's width (DisplacementOptions::edge_fade_control_edges), cloud units
};

// Flags (#P, 1 = isolated) the points whose neighbourhood holds fewer than
// 1/density_ratio of the points a surface sampled at the scan's typical
// spacing would put there. Typical spacing: the median nearest-neighbour
// distance of up to 4096 evenly picked points; neighbourhood: the 3x3x3
// cells of a grid of 4 typical spacings around the point (a surface crosses
// it with about (12 s)^2 / s^2 = 144 points, half that at a data edge).
std::vector<char> isolated_scan_points(const std::vector<Vec3>& points, double density_ratio);

// Measures d_0 .. d_L from a point cloud (jeong2002 Sec. 5): before each
// refinement, the signed distance along N_l from each vertex to the surface
// the points sample near the normal line (see DisplacementOptions).
// Overwrites mesh.displacements and mesh.data_support and re-evaluates. Fails with Empty on an
// empty cloud, InvalidInput on non-finite points or options out of range,
// Cancelled when progress asks to stop (the mesh is then left with zero
// displacements).
Status measure_displacements(const PointCloud& cloud, const DisplacementOptions& options, MultiresMesh& mesh,
                             DisplacementStats* stats = nullptr, const ProgressFn& progress = {});

}  // namespace lk
