// likeness photos' texture step: the skin from the self-calibrated cameras
// (tarini2002 Sec. 3.2, texture/texture.h), what `likeness texture` does
// from clicked points, here with no click. Its own file because
// project/texture_job.h (the chart) and photos/ name different types alike.
#pragma once
#include "calib/camera.h"
#include "common/status.h"
#include "image/image.h"
#include "mesh/tri_mesh.h"
#include "subdiv/butterfly.h"
#include "texture/texture.h"

#include <string>
#include <vector>

namespace lk::cli {

// Prints the chart texels whose fine detail blends >= 2 photos and, when it
// ran, the region labelling's figures (texture/labeling.h), each line
// started with `indent`.
void print_blend_figures(const TextureReport& report, const char* indent);

// The finest of levels (positions fine_positions) with the control mesh's
// chart refined to it, textured from the images (image_paths, cameras and
// names #P, the used photos) at size x size texels; writes
// out_dir/textured.obj, textured.mtl and skin.png. Errors name the photo.
// uvs and skin (optional): the chart and the skin, for the head project;
// images (optional): the decoded photos, for the iris (eye_from_views.h).
// Also writes out_dir/sources.png: each texel coloured by where its fine
// detail comes from (one colour per photo, white = blended from >= 2 photos,
// grey = interpolated, black = background), the doubling diagnostic.
Status write_photos_texture(const TriMesh& control, const std::vector<ButterflyLevel>& levels,
                            const std::vector<Vec3>& fine_positions, const std::vector<std::string>& image_paths,
                            const std::vector<std::string>& names, const std::vector<Camera>& cameras, int size,
                            const std::string& out_dir, std::vector<Vec2>* uvs = nullptr, Image* skin = nullptr,
                            std::vector<Image>* images = nullptr, bool register_photos = false,
                            bool label_regions = false);

}  // namespace lk::cli
