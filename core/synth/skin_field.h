// A synthetic photo session with ground truth, for scoring the skin texture
// of tarini2002 Sec. 3.2: a procedural skin albedo defined at every 3-D
// point of a head (so the colour every texel should get is known whatever
// the parameterization), a ring of cameras around the front hemisphere like
// the paper's "three to five photographs ... from different positions", and
// the feature vertices whose projections stand in for the 12-15 clicked
// correspondences of Sec. 3. Not from the paper itself.
//
// The albedo: a base skin tone (drawn per seed) modulated by value noise at
// three scales (blotches ~3 cm, mottling ~6 mm, pores ~2.5 mm), sparse
// freckles (dark spots ~1-2 mm, denser on the face), redder lips and dark
// eyebrows placed from the head's annotations (lip vertex boxes, eye
// sockets). Linear RGB,
// every channel in [0.02, 0.7] so lighting gains up to ~1.1 stay below the
// renderer's tone-mapping shoulder (0.8). Uses only +,-,*,/, floor and the
// splitmix hash (prng.h): the same seed gives the same field natively and in
// wasm.
//
// Cameras use lk::Camera (calib/camera.h, header-only data; this module does
// not link calib, which depends on synth).
//
// Shapes: head mesh #V by 3; albedo #points by 3; cameras #views.
#pragma once
#include "calib/camera.h"
#include "common/status.h"
#include "head/head_model.h"

#include <cstdint>
#include <vector>

namespace lk {

struct SkinFieldOptions {
  double tone_range = 0.10;            // base tone varies +-10 % per seed (per channel, correlated)
  double blotch_amplitude = 0.12;      // relative brightness variation of the ~3 cm noise
  double blotch_wavelength_m = 0.03;
  double mottle_amplitude = 0.06;      // relative variation of the fine noise
  double mottle_wavelength_m = 0.006;
  double pore_amplitude = 0.05;        // relative variation of single-octave noise at pore scale
  double pore_wavelength_m = 0.0025;   // about two vertex spacings of a 171k-triangle head
  double freckle_spacing_m = 0.006;    // one candidate freckle per cell of this size
  double freckle_probability = 0.35;   // share of cells that hold a freckle (face; 1/3 of it elsewhere)
  double freckle_radius_m = 0.0015;    // mean radius (+-40 %)
  double freckle_darkening = 0.35;     // albedo multiplier at a freckle's centre is 1 - this
  double lip_strength = 1.0;           // 0 = no lip colour
  double brow_strength = 1.0;          // 0 = no eyebrows
};

// The field's parameters, drawn from the seed and placed on the head.
struct SkinField {
  std::uint64_t seed = 0;
  SkinFieldOptions options;
  Vec3 base = Vec3(0.50, 0.29, 0.21);     // linear RGB skin tone
  Vec3 lip_color = Vec3(0.36, 0.11, 0.10);
  Vec3 brow_color = Vec3(0.06, 0.04, 0.03);
  Vec3 look = Vec3::UnitZ(), up = Vec3::UnitY(), side = Vec3::UnitX();  // head frame (side = up x look)
  Vec3 face_center = Vec3::Zero();        // freckles are densest within face_radius of it
  double face_radius = 0.08;
  Vec3 lip_center = Vec3::Zero();         // rounded box around both lips
  Vec3 lip_half_extent = Vec3(0.025, 0.011, 0.02);  // along side, up, look
  Vec3 brow_center[2] = {Vec3::Zero(), Vec3::Zero()};  // left (+x), right
  double brow_half_width = 0.024, brow_half_height = 0.0045, brow_arch = 0.006;
};

// Places the field on a head (generic or synthesized: positions and
// annotations must agree). Fails with InvalidInput when the mesh is empty,
// the lip regions are missing or empty, or an index is out of range.
Status make_skin_field(const GenericHead& head, std::uint32_t seed, const SkinFieldOptions& options,
                       SkinField& out);

// Albedo (linear RGB) at a point in the head's coordinates (metres).
Vec3 skin_albedo(const SkinField& field, const Vec3& point);
// The same for many points: #points by 3.
std::vector<Vec3> skin_albedo(const SkinField& field, const std::vector<Vec3>& points);

// A camera position around the head: yaw turns around the head's up axis
// from the front (+ = towards the head's left, +x), pitch raises the camera.
struct RingView {
  double yaw_deg = 0, pitch_deg = 0;
};

// The photo session of the self-test: 0 front, 1 left 45, 2 right 45,
// 3 left 80, 4 right 80, 5 above (pitch +30), 6 below (pitch -25); the
// first n of these (n in 1..7).
std::vector<RingView> default_ring_views(int n);
// The held-out evaluation view: front-left 25 degrees, slightly above.
RingView held_out_view();

struct CameraRingOptions {
  int width = 1200, height = 800;  // pixels
  double distance_m = 0.7;         // camera to the head's centre (one lens, one distance for all photos)
  double fill = 0.85;              // share of the image height the head's bounding sphere spans
  double jitter_deg = 2.0;         // seeded random offset of yaw, pitch and roll (hand-held camera)
  double aim_jitter_m = 0.005;     // seeded random offset of the aim point
};

// Pinhole cameras (no distortion, principal point at the image centre, one
// focal length for all views chosen from `fill`) looking at the centre of
// `points` (the head's vertices) from each view; head frame from the
// annotations' look and up. Fails with InvalidInput on empty points, a
// non-positive size or distance, or a distance inside the head.
Status camera_ring(const std::vector<Vec3>& points, const Vec3& look, const Vec3& up,
                   const std::vector<RingView>& views, std::uint32_t seed, const CameraRingOptions& options,
                   std::vector<Camera>& cameras);

// A camera at `eye` looking at `target`, image y down with `up` pointing to
// the top of the image; fx = fy = focal; principal point at the image centre.
Camera look_at(const Vec3& eye, const Vec3& target, const Vec3& up, double focal, int width, int height);

// Feature vertices for correspondences (Sec. 3: "12-15 corresponding feature
// points"): eye corners and top of each eye rim, nose and mouth landmarks,
// ear landmarks, the chin's lowest front vertex, the forehead's top centre,
// and per side what a profile photo shows (ear top, lobe, back and front,
// cheekbone, lower cheek, jaw angle and middle, temple, two scalp points,
// the side of the neck); indices into head.mesh (about 46). Which
// of them a photo sees is the caller's business (it depends on the camera).
std::vector<int> feature_vertices(const GenericHead& head);

}  // namespace lk
