// The GLSL ES 3.00 sources of shaders/, embedded at build time (lk_shaders).
#pragma once
#include <cstddef>
#include <string>

namespace likeness_embedded {
extern const unsigned char shaders_mesh_vert[];
extern const std::size_t shaders_mesh_vert_size;
extern const unsigned char shaders_mesh_frag[];
extern const std::size_t shaders_mesh_frag_size;
extern const unsigned char shaders_points_vert[];
extern const std::size_t shaders_points_vert_size;
extern const unsigned char shaders_points_frag[];
extern const std::size_t shaders_points_frag_size;
extern const unsigned char shaders_background_vert[];
extern const std::size_t shaders_background_vert_size;
extern const unsigned char shaders_background_frag[];
extern const std::size_t shaders_background_frag_size;
extern const unsigned char shaders_lines_vert[];
extern const std::size_t shaders_lines_vert_size;
extern const unsigned char shaders_lines_frag[];
extern const std::size_t shaders_lines_frag_size;
}  // namespace likeness_embedded

namespace lk::shader_sources {
inline std::string text(const unsigned char* data, std::size_t size) {
  return std::string(reinterpret_cast<const char*>(data), size);
}
}  // namespace lk::shader_sources
