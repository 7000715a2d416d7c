// Dense stereo for the photos fit (fua1998 Sec. 3.1): for pairs of photos
// whose calibrated cameras see the head from 10-40 deg apart, a disparity
// map by normalized cross-correlation over a window along the rectified rows
// (rectify.h), restricted to the head's region and to the depth range of a
// head mesh; a left-right consistency check (occlusions, mismatches);
// sub-pixel disparity from a parabola through the best score and its two
// neighbours; 3-D points by triangulation; then a plane fitted robustly to
// the points of each small image cell (outliers by the median absolute
// deviation dropped, refitted) gives a patch: a centre and a normal, the
// paper's "attractors" (stereo_obs.h).
//
// The paper's correlation algorithm ([7], Fua 1993) also works on several
// resolutions and interpolates; this is the plain single-scale version.
//
// Shapes: disparity maps width x height of the left rectified image (NaN =
// none); patches #K.
#pragma once
#include "calib/camera.h"
#include "common/status.h"
#include "image/image.h"
#include "mesh/tri_mesh.h"
#include "photos/rectify.h"

#include <string>
#include <vector>

namespace lk {

struct DisparityOptions {
  int radius = 4;              // correlation window (2 radius + 1)^2
  double min_ncc = 0.6;        // a best score below this: no disparity
  double min_std = 0.004;      // grey-level standard deviation a window needs (texture), levels in [0, 1]
  int lr_tolerance = 1;        // |d_left - d_right| allowed, pixels
};

struct DisparityMap {
  int width = 0, height = 0;
  std::vector<float> d;        // #width*height, column in left - column in right, pixels; NaN = none
  // Counts over the masked left pixels.
  int searched = 0, low_texture = 0, low_score = 0, lr_rejected = 0, at_range_end = 0, valid = 0;
  float at(int x, int y) const { return d[size_t(y) * size_t(width) + size_t(x)]; }
};

// Disparities d in [d_min, d_max] (integers searched, then refined) for the
// left pixels with mask 1 (empty mask: all). The right image must have the
// left's height. Fails on sizes that do not match or d_min > d_max.
Status compute_disparity(const ImageF& left, const ImageF& right, const std::vector<std::uint8_t>& mask, int d_min,
                         int d_max, const DisparityOptions& options, DisparityMap& out);

// The world point of left rectified pixel (x, y) (its centre) at disparity d.
// False when the disparity puts it behind the cameras.
bool triangulate_rectified(const RectifiedCameras& rc, double x, double y, double d, Vec3& X);

struct StereoPatch {
  Vec3 centre = Vec3::Zero();
  Vec3 normal = Vec3::Zero();  // unit, towards the first photo's camera
  int points = 0;              // inliers the plane was fitted to
  double rms = 0;              // their distances to the plane, world units
  int pair = 0;                // index into StereoResult::pairs
};

struct StereoOptions {
  DisparityOptions disparity;
  int max_size = 400;            // rectified frame's larger side, pixels (downscaled for speed)
  double min_angle_deg = 10, max_angle_deg = 40;  // pairs: angle between the views at the head's centre
  int max_pairs_per_photo = 2;
  double depth_margin = 0.03;    // around the head mesh's depth range, world units
  double region_grow = 1.15;     // the landmarks' hull grown about its centroid
  int patch_px = 8;              // patch cell, rectified pixels
  double min_patch_fill = 0.5;   // share of a cell's pixels with a 3-D point
  double max_patch_rms = 0.002;  // after the robust refit, world units
  double max_patch_slant_deg = 75;  // patch normal to the view direction
};

// One photo: its image, calibrated camera and the region to search (e.g.
// its detected landmarks; their convex hull is used).
struct StereoView {
  const Image* image = nullptr;
  Camera camera;
  std::vector<Vec2> region;
  std::string name;
};

struct StereoPairReport {
  int a = 0, b = 0;              // indices into the views
  double angle_deg = 0;          // between the views, at the centre of the head (run_stereo) or of the shared region
  int width = 0, height = 0;     // rectified frame
  int d_min = 0, d_max = 0;
  DisparityMap disparity;        // counts; the map itself is kept only with keep_maps
  int points = 0, patches = 0;
  std::string refusal;           // why the pair gave nothing (empty when it did)
};

struct StereoResult {
  std::vector<StereoPatch> patches;
  std::vector<StereoPairReport> pairs;
};

// One pair: rectify (roi = head vertices seen by both cameras inside a's
// region), disparity, triangulation, patches (appended to out.patches with
// pair index = out.pairs.size()); the pair's report is appended too.
// Fails with a message naming the problem (tiny image, no overlap, no
// texture ...) and leaves a report with that refusal.
Status stereo_pair(const StereoView& a, const StereoView& b, const TriMesh& head, const StereoOptions& options,
                   StereoResult& out, int index_a = 0, int index_b = 1);

// Pairs chosen by the cameras' angle at the head's centre, each photo in at
// most max_pairs_per_photo pairs (nearest to the middle of the angle range
// first); every pair's report, refused ones included. Fails only on bad
// options.
Status run_stereo(const std::vector<StereoView>& views, const TriMesh& head, const StereoOptions& options,
                  StereoResult& out);

// Robust plane through points: least squares, points beyond 2.5 robust
// sigmas (1.4826 MAD, at least min_sigma) dropped, refitted. False with
// fewer than 3 inliers or a degenerate spread.
bool fit_plane_robust(const std::vector<Vec3>& points, double min_sigma, Vec3& centre, Vec3& normal, int& inliers,
                      double& rms);

}  // namespace lk
