// A virtual structured-light range scanner: the kind of input jeong2002
// (Sec. 3, Fig. 2) starts from, a cloud of ~300k points with holes, noise and
// outliers, but made from a known surface so the error of every later stage
// can be measured.
//
// Model. Several stations on an arc around the head, each a camera and a
// projector `baseline_m` apart, both aimed at the head centre. A camera pixel
// yields a point only where the surface is (1) the first hit of the camera
// ray, (2) lit by the projector (a shadow ray from the point to the projector
// is free) and (3) seen by both at less than `max_incidence_deg` from the
// normal. So the projector's shadows leave holes where real scanners have
// them: behind the ears, under the chin and the nose. Hair (the scalp region)
// returns only sparse junk. Depth noise is Gaussian along the camera ray.
// Where a point is also seen by another station (the scans overlap), a small
// share of points gets a misregistration-like offset: the station's own rigid
// shift, at least `outlier_offset_m` off the surface. The pixel grid of every
// station is sized from a pilot pass to land on `target_points`; surplus
// points are dropped at random.
//
// Shapes: truth #Vt by 3, #Ft by 3; options.hair_triangles #Ft or empty;
// out.positions (and normals) #P by 3; stats.point_station #P.
// Deterministic: the same truth, options and seed give the same bytes
// (splitmix64, no std distributions, no libm in the random draws).
#pragma once
#include "common/progress.h"
#include "common/status.h"
#include "mesh/tri_mesh.h"

#include <cstdint>
#include <vector>

namespace lk {

struct ScannerOptions {
  int stations = 6;                  // camera+projector pairs
  double arc_degrees = 200.0;        // azimuth span of the stations, centred on the face;
                                     // wider arcs see into the groove behind the ears
  // Elevations (degrees, + is above the head centre) for stations from the
  // ends of the arc inwards; mirrored so left and right match, cycled if short.
  std::vector<double> elevations_deg = {-5.0, 15.0, 0.0};
  double distance_m = 0.7;           // camera to head centre
  double baseline_m = 0.25;          // camera to projector
  double baseline_angle_deg = 65.0;  // projector direction from the camera in its image
                                     // plane: 0 = sideways toward the face, 90 = straight up
  double max_incidence_deg = 75.0;   // grazing limit (camera and projector) from the normal
  int target_points = 300000;        // about this many points overall
  double noise_sigma_m = 0.0002;     // depth noise along the camera ray (std)
  double outlier_fraction = 0.005;   // share of points misregistered (taken from overlaps)
  double outlier_offset_m = 0.002;   // misregistered points lie at least this far off
  std::vector<char> hair_triangles;  // #Ft: 1 = hair (scalp), empty = no hair
  double hair_junk_fraction = 0.03;  // share of hair pixels that still return a (junk) point
  double hair_junk_range_m = 0.01;   // junk lies up to this far above the scalp
  bool store_normals = true;         // fill out.normals (surface normal, perturbed)
  double normal_noise = 0.05;        // std of the normal perturbation (radians, roughly)
  Vec3 look = Vec3::UnitZ();         // the face's direction (the arc's centre)
  Vec3 up = Vec3::UnitY();
};

struct ScannerStation {
  Vec3 camera = Vec3::Zero(), projector = Vec3::Zero();
  Vec3 forward = Vec3::UnitZ(), right = Vec3::UnitX(), up = Vec3::UnitY();  // camera axes
  double azimuth_deg = 0, elevation_deg = 0;
  double half_fov_tan = 0;  // tan of half the (square) field of view
  int grid = 0;             // pixels per side used for the scan
  // What happened to its pixels:
  int rays = 0, misses = 0, back_facing = 0, grazing = 0, shadowed = 0, hair = 0;
  int points = 0;           // points kept (after thinning to the target)
  int junk = 0, outliers = 0;
};

struct ScanStats {
  std::vector<ScannerStation> stations;
  std::vector<int> point_station;  // #P: which station produced each point
  std::vector<char> point_kind;    // #P: 0 surface, 1 outlier (misregistered), 2 hair junk
  int points = 0, outliers = 0, junk = 0;
  int pilot_grid = 0;              // grid of the pilot pass used to size the real one
};

// Scans `truth`. Fails with InvalidInput on an invalid or empty mesh, a hair
// mask of the wrong size, or out-of-range options (no stations, a target
// below 1 or above 20 million, negative noise, a fraction outside [0,1]);
// with Cancelled when progress asks to stop.
Status scan_virtual(const TriMesh& truth, const ScannerOptions& options, std::uint32_t seed,
                    PointCloud& out, ScanStats* stats = nullptr, const ProgressFn& progress = {});

}  // namespace lk
