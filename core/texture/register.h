// Photometric re-registration of the photos on the surface before they are
// blended (after Zhou & Koltun 2014, "Color Map Optimization for 3D
// Reconstruction with Consumer Depth Cameras", Sec. 4-5): self-calibrated
// cameras disagree by a few pixels and the surface is mm off the person, so
// two photos put the same feature on different texels and the blend shows
// it twice (doubled brows, ghost edges). Each photo i gets
//   - a pose correction (rotation omega and translation dt in the camera
//     frame: x_c' = exp([omega]x) (R X + t) + dt),
//   - an intensity gain and bias (a_i, b_i: the photos' lights differ),
//   - a smooth 2-D correction field F_i on a K x K lattice over the image
//     (bilinear), the paper's non-rigid part: it absorbs the parallax a
//     wrong surface causes, which no single pose can;
// chosen to minimise, over the surface's vertices v and their valid photos,
//   sum  w_vi (a_i G_i(q_i(v)) + b_i - C(v))^2 + regulariser(F_i),
//   q_i(v) = p_i(v) + F_i(p_i(v)),  p_i(v) = camera_i.project(X_v),
// with G_i the photo's luminance (linear light, Gaussian-blurred, coarse to
// fine) and C(v) the vertices' consensus. Alternating as the paper does:
// C(v) = the weighted mean over photos; then one damped Gauss-Newton step
// per photo (the photos decouple once C is fixed). One photo (the reference)
// is held fixed, which removes the common drift the paper leaves free.
//
// apply_registration then gives the texturing an ordinary TexturePhoto:
// the corrected camera and the photo resampled through F (I'(p) = I(p + F(p))),
// so every later step (binding, resampling, spline) is unchanged.
//
// Shapes: mesh #V, normals #V (unit), binding over #P photos.
#pragma once
#include "calib/camera.h"
#include "common/status.h"
#include "image/image.h"
#include "mesh/tri_mesh.h"
#include "texture/binding.h"
#include "texture/resample.h"

#include <vector>

namespace lk {

struct RegisterOptions {
  // Lattice nodes per side of F (0 = no field: pose and gain only). Off by
  // default: on the ground truth the field lowered the texture's PSNR
  // (39.9 -> 35.9 dB in tests/texture/test_register.cpp; docs/design/texture.md).
  int field_nodes = 0;
  bool refine_pose = true;
  // Coarse to fine: the luminance halved (2x2 box) levels-1 times, each
  // coarser level blurred by blur_px (sigma, in that level's pixels; the
  // finest is not blurred); Gauss-Newton iterations at each level, the
  // coarsest first (a wide basin for misregistrations of a few pixels).
  int levels = 3;
  double blur_px = 1.0;
  int iterations = 8;
  // Regulariser of F, per residual and pixel: lambda_0 |f_k|^2 pulls the
  // nodes towards 0 and lambda_s |f_k - f_l|^2 (lattice neighbours) keeps F
  // smooth; both scaled by the photo's residual count / K^2 so they weigh
  // the same whatever the mesh's density.
  double field_weight = 1e-5;
  double field_smoothness = 1e-4;
  // Prior on the pose change: a mean image motion of the photo's vertices
  // of pose_prior_px costs as much as a luminance residual of 0.01 at every
  // vertex (0 = no prior). Self-calibrated cameras are a few pixels off.
  double pose_prior_px = 10.0;
  int reference = -1;            // photo held fixed; -1 = the one facing the shared vertices most (summed <N, V>)
  // A vertex takes part in photo i only where <N, V_i> >= min_facing:
  // grazing views smear a pixel's blur over much surface and mix in the
  // background at the silhouette, so their colours differ from the other
  // photos' even with true cameras and would pull the registration off.
  double min_facing = 0.4;
  int max_vertices = 30000;      // vertices used (an even stride over those seen twice or more)
};

// One photo's correction. The corrected projection of X is
// q = p + F(p), p = camera.project(X) with the refined camera.
struct PhotoRegistration {
  Camera camera;                 // refined pose (intrinsics unchanged)
  double gain = 1, bias = 0;     // intensity model a G + b
  int nodes = 0;                 // K (0 = no field)
  std::vector<Vec2> field;       // K*K node offsets in pixels, row-major (node (x, y) at y*K + x)
  int vertices = 0;              // residual vertices the photo took part in
  double rms_before = 0, rms_after = 0;  // |a G + b - C| over them at the finest blur, before / after
  double rotation_deg = 0, translation_mm = 0;  // size of the pose change
  double field_max_px = 0;       // largest |f_k|
};

struct RegisterReport {
  std::vector<PhotoRegistration> photos;  // #P
  int reference = -1;
  int vertices = 0;                       // vertices seen by two photos or more, used
  double rms_before = 0, rms_after = 0;   // over all residuals, finest blur
};

// Registers the photos against each other over the mesh. `binding` is the
// visibility of the mesh's vertices in the photos' current cameras
// (bind_vertices). Fails with InvalidInput on inconsistent sizes and with
// Empty when fewer than two photos share vertices (then there is
// nothing to register: a caller may texture without).
Status register_photos(const TriMesh& mesh, const std::vector<Vec3>& normals, const VertexBinding& binding,
                       const std::vector<TexturePhoto>& photos, const RegisterOptions& options,
                       RegisterReport& report);

// F(p) and the corrected projection.
Vec2 field_offset(const PhotoRegistration& reg, const Vec2& p);
bool registered_project(const PhotoRegistration& reg, const Vec3& X, Vec2& q);

// The photo as the texturing should see it: reg.camera, and the image
// resampled so that its pixel p shows the original at p + F(p) (bilinear,
// per channel). Without a field only the camera changes.
void apply_registration(const PhotoRegistration& reg, TexturePhoto& photo);

// For tests: the residual a G(q) + b - C of one vertex X in one photo and
// its derivatives, the parameter order being omega (3), dt (3), a, b, then
// the field nodes' (x, y) offsets (2 K^2). G is the luminance image the
// residuals use (linear, 1 channel, pixel centres at integer + 0.5).
// Returns false when X does not project into G.
bool photometric_residual(const ImageF& luminance, const PhotoRegistration& reg, const Vec3& X, double consensus,
                          double& residual, std::vector<double>& jacobian);
// Linear-light luminance of a photo, blurred by sigma pixels (0 = none).
ImageF photo_luminance(const Image& image, double sigma_px);

}  // namespace lk
