// Ground-truth photos for tests and benchmarks of texturing (not from the
// paper): a z-buffered software rasterization of a mesh seen by a known
// camera, each pixel coloured by a function of the exact surface point, so
// the colour every texel should get is known. Camera distortion is ignored
// (k1 = k2 = 0 is expected); colours are linear RGB, encoded to sRGB.
//
// Shapes: mesh positions #V by 3, triangles #F by 3; photo camera.width x
// camera.height x 3.
#pragma once
#include "calib/camera.h"
#include "common/status.h"
#include "image/image.h"
#include "mesh/tri_mesh.h"

#include <functional>
#include <vector>

namespace lk {

// Linear RGB in [0,1] of a surface point with its (interpolated, unit) normal.
using SurfaceColorFn = std::function<Vec3(const Vec3& point, const Vec3& normal)>;

// An exact sphere drawn with the mesh (e.g. an eyeball in its socket): the
// z-buffer decides between it and the triangles, its own colour function.
struct SyntheticSphere {
  Vec3 center = Vec3::Zero();
  double radius = 0;
  SurfaceColorFn color;
};

// Renders the photo. Pixels whose centre sees no triangle (nor sphere) get
// `background`. Fails with InvalidInput on a camera without image size, an
// invalid mesh or a sphere without radius or colour.
Status render_synthetic_photo(const TriMesh& mesh, const Camera& camera, const SurfaceColorFn& color,
                              const Vec3& background, Image& photo,
                              const std::vector<SyntheticSphere>& spheres = {});

// A smooth 3-D colour field with detail at several scales (skin-like hues,
// linear RGB in about [0.1, 0.8]); `scale` is its finest wavelength in
// mesh units (e.g. 0.01 for a head in metres).
Vec3 procedural_color_field(const Vec3& point, double scale);

// A camera at `eye` looking at `target` (image y down, up ~ +y), focal
// length `focal` pixels, principal point at the image centre.
Camera look_at_camera(const Vec3& eye, const Vec3& target, const Vec3& up, double focal, int width, int height);

}  // namespace lk
