// Iris texture from one eye photograph: Tarini, Yamauchi, Haber, Seidel,
// "Texturing Faces", Graphics Interface 2002, Sec. 4.1.
//
// Stages (each re-runnable with new options):
//   find_iris        growing circle from a rough guess inside the pupil,
//                    then sub-pixel refinement on the limbus edge
//   iris_to_polar    resamples the iris annulus into polar coordinates
//                    (#angles rows by #radii columns, RGB) and marks the
//                    valid pixels (not skin-like, within alpha standard
//                    deviations of their ring's mean)
//   iris_synthesize  a new full-circle polar iris from the reference patch
//                    (largest valid sector up to 60 deg; the whole valid
//                    set below 20 deg): a Markov chain of rows along the
//                    angle axis, or the 2-D neighbourhood fallback
//   eyeball_texture  the square texture of the frontal hemisphere
//
// Eyeball texture layout (azimuthal equidistant projection): a point on the
// eyeball with unit direction d, the front axis being +z and +y up, has
//   theta = acos(d.z), phi = atan2(d.y, d.x), rho = theta / (pi/2),
//   u = 0.5 + 0.5 rho cos(phi), v = 0.5 - 0.5 rho sin(phi)   (v down).
// The texture covers rho <= 1 (the frontal hemisphere); outside is sclera.
#pragma once
#include <cstdint>
#include <vector>

#include "common/progress.h"
#include "common/status.h"
#include "common/types.h"
#include "image/image.h"

namespace lk {

// The eyeball texture's layout (above) for a unit direction d from the
// eyeball's centre: rho = acos(d.z) / (pi/2), unclamped (>= 1 off the
// texture's disk, at or behind the equator).
double eyeball_rho(const Vec3& d);
// Its (u, v), rho clamped to 1: directions at or behind the equator land on
// the disk's rim (sclera), the back pole (0, 0, -1) on (1, 0.5).
Vec2 eyeball_uv(const Vec3& d);

struct IrisCircle {
  Vec2 center = Vec2::Zero();  // pixels, x right, y down (pixel centres at integers)
  double radius = 0;           // iris (limbus) radius, pixels
  double pupil_radius = 0;     // pixels
};

struct IrisFindOptions {
  // Circle growth stops when at least this fraction of the circle's samples
  // is "too bright" (outside the iris).
  double stop_bright_fraction = 0.5;
  // Brightness threshold between iris and sclera/skin, as a fraction from the
  // dark level (around the guess) to the bright level (95th percentile).
  double bright_level = 0.7;
  // Smallest accepted iris radius, pixels.
  double min_radius = 6;
  // Sub-pixel refinement iterations of the limbus circle fit.
  int refine_iterations = 3;
};

// Default guess when the user gives none: the darkest blob near the image
// centre (box-filtered luminance, with a penalty growing with the distance
// from the centre). Fails with NotAHead when the image has no dark blob.
Status iris_default_guess(const Image& photo, Vec2& guess);

// photo: RGB or RGBA (gray accepted). guess must lie inside the pupil or the
// iris. Fails (InvalidInput / NotAHead / NotConverged) on an empty image, a
// guess outside the image, a uniform image or when the circle never stops.
Status find_iris(const Image& photo, const Vec2& guess, const IrisFindOptions& options,
                 IrisCircle& circle);

// The iris annulus in polar coordinates: row a is the angle
// 2 pi a / angles (counter-clockwise on screen, 0 = +x), column r the radius
// pupil_radius + (r + 0.5) * (radius - pupil_radius) / radii.
struct PolarIris {
  int angles = 0, radii = 0;
  std::vector<float> rgb;              // angles * radii * 3, in [0,1]
  std::vector<std::uint8_t> valid;     // angles * radii, 1 = usable sample
  const float* at(int a, int r) const { return &rgb[(static_cast<size_t>(a) * radii + r) * 3]; }
  float* at(int a, int r) { return &rgb[(static_cast<size_t>(a) * radii + r) * 3]; }
};

struct IrisValidityOptions {
  double alpha = 2.3;            // paper: within [2, 3]; remove beyond alpha std of the ring mean
  int alpha_passes = 2;          // ring statistics are recomputed after each removal
  double skin_distance = 0.12;   // RGB distance (0..1 units) below which a pixel is skin-like
  int angles = 0;                // 0: about one sample per pixel along the limbus, at most max_auto_angles
  int radii = 0;                 // 0: about one sample per pixel across the annulus, at most max_auto_radii
  // Caps of the automatic sizes: they bound the synthesis's work on a huge
  // circle (a whole-face photo gave 3300 x 350 samples and minutes in the
  // page). A 512 px eyeball texture shows the iris at about 85 px radius,
  // so 720 angles and 128 radii lose nothing it can show.
  int max_auto_angles = 720, max_auto_radii = 128;
};

// Also estimates the skin colour from the photo's border (median of the
// outer 8% band), since close-up eye photos are framed by skin.
Status iris_to_polar(const Image& photo, const IrisCircle& circle,
                     const IrisValidityOptions& options, PolarIris& polar);

struct IrisSynthesisOptions {
  double max_sector_deg = 60;    // reference patch: largest valid sector up to this
  double min_sector_deg = 20;    // below this the whole valid set is used (2-D synthesis)
  double row_valid_fraction = 0.9;  // a row belongs to a sector when this share is valid
  // Neighbourhood mask (radius x angle) for an iris of 80 px diameter,
  // scaled with the actual diameter (paper: 3 x 6).
  int mask_radius = 3, mask_angle = 6;
  double candidate_slack = 0.1;  // choose randomly among candidates within (1+slack) of the best
  int radius_tolerance = 1;      // 2-D: candidate radius within this many columns
  int max_candidates = 600;      // 2-D: random subset of candidates per pixel
  bool force_2d = false;         // use the 2-D scheme even with a large sector
  std::uint32_t seed = 1;
};

struct IrisSynthesisReport {
  int sector_begin = 0, sector_rows = 0;  // reference rows (circular), when a sector was used
  double sector_deg = 0;
  bool used_2d = false;
  int valid_pixels = 0;
};

// output has input.angles rows and input.radii columns, all valid.
Status iris_synthesize(const PolarIris& input, const IrisSynthesisOptions& options,
                       PolarIris& output, IrisSynthesisReport* report = nullptr,
                       const ProgressFn& progress = {});

struct EyeballTextureOptions {
  int size = 512;                 // square texture, pixels
  double iris_angle_deg = 30;     // angular radius of the limbus seen from the eyeball centre
  double limbus_width = 0.08;     // darkening ring, fraction of the iris radius
  double pupil_scale = 1.0;       // dilation: pupil radius multiplier
  int veins = 14;                 // procedural sclera veins
  std::uint32_t seed = 7;
};

// Square RGB eyeball texture (layout above): black pupil, the synthesized iris,
// a darkened limbus, white-ish sclera with faint veins.
Status eyeball_texture(const PolarIris& iris, double pupil_to_iris_ratio,
                       const EyeballTextureOptions& options, Image& texture);

// Whether the found circle is an eye's iris in a close-up of one eye, not a
// dark patch of a face, hair or background: NotAHead with the reason unless
//  - the iris's radius is at most 0.4 of the photo's short side (an eye
//    photo shows the white of the eye or the lids beside the iris), and
//  - the limbus is round: on at least 38 % of 180 rays from the centre the
//    strongest dark-to-bright step between 0.6 and 1.5 radii lies within
//    10 % of the radius (eyelids may hide the rest), and
//  - a pupil darker than the iris sits at the centre: the median luminance
//    at 0.6 radii exceeds that within 0.1 radii by at least 0.12.
// Measured (docs/design/untrusted_images.md): the real eye close-up (radius
// 0.27 of the short side, round 0.56, contrast 0.28) and the synthetic test
// eye pass; the ten portraits of multiview_faces, two intraoral photos and a
// scanner texture each fail one (the roundest 0.48 with contrast -0.07); a
// portrait given a guess at its eye found the face's outline (0.46 of the
// short side, round 0.42). A stopgap until the face landmarks (issue 37)
// locate the eye.
Status check_eye_closeup(const Image& photo, const IrisCircle& circle);

// In a photo of a face whose eye's place and size are known (a fitted head
// seen by its recovered camera): the limbus as the circle with the
// strongest dark-to-bright step across its left and right arcs (Daugman's
// integro-differential operator, on the arcs the lids leave uncovered; the
// median along each arc ignores lashes and catchlights), its centre within
// search_px of guess and its radius in [min_radius, max_radius] pixels;
// the pupil as the strongest bright step inside it (0.35 of the iris when
// none is clear). Works for light irises, where find_iris's dark-disk growth
// does not. NotAHead when no arc step of at least 0.04 (luminance 0..1) is
// found: no iris there.
Status find_iris_near(const Image& photo, const Vec2& guess, double search_px, double min_radius,
                      double max_radius, IrisCircle& circle);

// Everything above with default options: photo (+ guess or nullptr) -> texture.
// Photos with a side over max_side pixels are first reduced by an integer
// box filter (the circle found is given back in the photo's pixels), so the
// work is bounded whatever the photo; check_eye_closeup runs on the circle.
struct IrisResult {
  IrisCircle circle;
  PolarIris input_polar, synthesized;
  IrisSynthesisReport report;
  Image texture;
};
Status iris_texture_from_photo(const Image& photo, const Vec2* guess, IrisResult& result,
                               const EyeballTextureOptions& texture_options = {}, const ProgressFn& progress = {},
                               int max_side = 1024);

// The steps after the circle: polar samples, synthesis, eyeball texture
// (result.circle = circle).
Status iris_texture_from_circle(const Image& photo, const IrisCircle& circle, IrisResult& result,
                                const EyeballTextureOptions& texture_options = {}, const ProgressFn& progress = {});

}  // namespace lk
