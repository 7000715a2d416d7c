// Skin texture from photographs (tarini2002 Sec. 3 and 3.2): given a head
// mesh (one boundary loop at the neck) and three to five calibrated photos,
// produce one texture over a single [0,1]^2 chart.
//
// Steps (each in its own header, callable on its own):
//   0. calibrate_photos (below): one camera per photo from 2-D/3-D feature
//      correspondences (core/calib), shared by the CLI and the web app;
//   1. parameterize_stretch (core/uv, Sec. 3.1) when the mesh has no uvs;
//   2. bind_vertices (binding.h): valid photos and main photo per vertex;
//      optionally register_photos (register.h) then binds again with the
//      refined cameras and the photos warped by their correction fields;
//   3. rasterize_chart + resample_texture (chart_raster.h, resample.h):
//      the paper's three triangle cases, <N,V>-weighted, in linear light;
//   4. fill_vertex_colors (hole_fill.h): 80/60/40/20 % one-ring passes,
//      then any coloured neighbour, then (ours) relaxation of the filled
//      colours, so every chart texel gets a colour and holes have no ridge;
//   5. SplineBlender (pyramid.h): per photo a mask = its region shrunk by one
//      triangle ring, under the image "photo i alone where it sees the
//      surface, push-pull continued elsewhere"; plus the complement mask
//      under the feathered resampling (resample_feathered, seam-free);
//      Laplacian pyramids blended under Gaussian pyramids of the masks;
//   6. push_pull_fill / dilate_rings (dilate.h) into the unused texture space.
//
// texture_head runs them all. There are no clocks in the core: progress is
// reported with the step names below at fraction 0 when a step starts and 1
// when it ends, so a caller can time each step from the callback:
//   "parameterize", "bind", "register" (only with register_photos),
//   "resample", "fill holes", "spline", "dilate".
//
// Shapes: mesh positions #V by 3, triangles #F by 3, uvs #V by 2 (optional,
// per vertex); photos #P (1..kMaxTexturePhotos) RGB/RGBA/gray 8-bit sRGB;
// skin size x size x 3 (sRGB 8-bit); region map size * size.
#pragma once
#include "calib/calibrate.h"
#include "calib/camera.h"
#include "common/progress.h"
#include "common/status.h"
#include "image/image.h"
#include "mesh/tri_mesh.h"
#include "texture/binding.h"
#include "texture/hole_fill.h"
#include "texture/labeling.h"
#include "texture/register.h"
#include "texture/resample.h"
#include "uv/stretch_param.h"

#include <vector>

namespace lk {

// Calibrates each photo from its correspondences (at least 6 per photo):
// correspondences #P, image_sizes #P (width, height). results gets #P
// entries. With same_camera, the photos share one focal length
// (calibrate_cameras_shared: one joint LM over the focal and all poses,
// much steadier than one focal per photo from 12-15 points). Fails on the
// first photo that cannot be calibrated, with a message naming it
// ("photo 2: ..."), or InvalidInput when the counts differ.
// True when there are at least two photos and all have the size of the
// first, or that size turned by 90 degrees: most likely one camera, whose
// focal length in pixels is then the same in every photo, so
// calibrate_photos(..., same_camera = true) is the better choice.
bool photos_look_like_one_camera(const std::vector<std::array<int, 2>>& image_sizes);

Status calibrate_photos(const std::vector<std::vector<Correspondence>>& correspondences,
                        const std::vector<std::array<int, 2>>& image_sizes,
                        const CalibOptions& options, std::vector<CalibResult>& results,
                        bool same_camera = false);

struct TextureOptions {
  int size = 2048;                      // texture width = height, texels (16 .. 4096; ~120 B/texel peak)
  BindingOptions binding;               // visibility tests (min_facing 0.1, 2 px margin, ...)
  HoleFillOptions hole_fill;            // 80/60/40/20 % passes (paper)
  bool multiresolution_spline = true;   // blend the regions (paper: "if necessary")
  int spline_levels = 0;                // pyramid levels; 0 = as many as the size allows
  // Unused texture space: < 0 = push-pull fill of the whole background
  // (smooth, mipmap-safe), 0 = leave black, > 0 = dilate this many rings.
  int dilate_texels = -1;
  // Chart texels the rasterizer gives to the nearest triangle although their
  // centre lies just outside (fraction of a texel), see chart_raster.h.
  double conservative_texels = 0.75;
  UvOptions uv;                         // used only when the mesh has no uvs
  bool keep_unblended = false;          // also return the texture before the spline
  // Photometric re-registration of the photos on the surface (register.h)
  // between binding and resampling: refined poses, gains and a smooth 2-D
  // correction per photo, then the binding is made again with them.
  bool register_photos = false;
  RegisterOptions registration;
  // One photo per region (labeling.h): the spline's regions become a
  // labelling that prefers frontal views and puts its boundaries where the
  // photos agree, and the masks are the regions themselves (not shrunk), so
  // at fine scales each texel of a region shows that photo alone and the
  // feathered blend is left only to the case-2/3 triangles.
  bool label_regions = false;
  LabelingOptions labeling;
};

struct TexturePhotoReport {
  int vertices_valid = 0;   // vertices for which the photo is valid
  int vertices_main = 0;    // vertices whose main photo it is
  long texels_colored = 0;  // texels of its region (case-1 triangles it dominates)
  long texels_seen = 0;     // texels of triangles whose three corners it sees (spline on; else 0)
};

struct TextureReport {
  std::vector<TexturePhotoReport> photos;  // #P
  int vertices = 0, triangles = 0;
  int vertices_unbound = 0;
  int triangles_case[3] = {0, 0, 0};   // the paper's cases 1, 2, 3
  long texels_case[3] = {0, 0, 0};
  long chart_texels = 0;               // texels covered by the chart
  long background_filled = 0;          // texels filled by dilation / push-pull
  HoleFillReport hole_fill;
  int spline_levels = 0;               // 0 when the spline was off
  bool parameterized = false;          // uvs computed here (else taken from the mesh)
  UvStats uv;                          // stretch of the chart used (measured either way)
  bool registered = false;             // register_photos ran and its corrections were used
  RegisterReport registration;         // its figures (photos empty when it did not run)
  bool labeled = false;                // label_regions ran
  LabelingReport labeling;             // its figures
  // Chart texels whose fine detail mixes two or more photos: the spline's
  // complement (feathered blend) over triangles whose corners see >= 2 photos.
  long texels_blended = 0;
};

struct TexturedHead {
  TriMesh mesh;            // the input mesh with per-vertex uvs, texture_name = "skin.png"
  Image skin;              // size x size x 3, sRGB
  Image unblended;         // the same before the spline (only with keep_unblended)
  std::vector<int> region; // size * size: photo index, kRegionFilled or kRegionBackground
  // size * size, spline on (else empty): where each texel's fine detail comes
  // from: the photo whose mask holds it, kRegionBlended (complement over >= 2
  // photos), kRegionFilled (complement over < 2 photos) or kRegionBackground.
  std::vector<int> source;
  TextureReport report;
};

// The whole Sec. 3.2 job. The mesh may come with per-vertex uvs in [0,1]^2
// (used as they are) or without (parameterized here with options.uv).
// Fails with InvalidInput on an empty/invalid mesh, per-corner uvs, no photo,
// more than kMaxTexturePhotos, an empty photo or a camera whose size differs
// from its image; NotAHead when some photo sees no vertex at all (the message
// names the photo: wrong calibration or wrong photo); uv errors are passed on;
// Cancelled when progress returns false.
Status texture_head(const TriMesh& mesh, const std::vector<TexturePhoto>& photos,
                    const TextureOptions& options, TexturedHead& out,
                    const ProgressFn& progress = {});

}  // namespace lk
