#version 300 es
// Triangle meshes, indexed or unrolled to three vertices per triangle (see
// renderer.h; barycentrics are only set, and the wireframe only drawn here,
// for unrolled meshes).
// Lighting happens in view space, where the light rig is defined.
precision highp float;

layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in vec2 a_uv;
layout(location = 3) in vec3 a_color;       // linear RGB
layout(location = 4) in vec3 a_barycentric; // (1,0,0), (0,1,0), (0,0,1) per corner
layout(location = 5) in float a_occlusion;  // baked ambient occlusion, 1 = open
// Morph targets (Renderer::set_morph_targets): this vertex's entries, in
// shape order, are texels 2*(first+k) (position offset, shape) and
// 2*(first+k)+1 (normal offset), k < count, of u_morph_offsets (rows of
// u_morph_width texels); bit s of the mask says shape s has an entry here.
// Unset: (0, 0) and no bits, no entries.
layout(location = 6) in vec2 a_morph;        // (first entry, count)
layout(location = 7) in uvec4 a_morph_mask;  // shapes 0-127

uniform mat4 u_model;
uniform mat4 u_view;
uniform mat4 u_projection;
uniform mat3 u_normal_matrix;  // inverse transpose of the upper 3x3 of view * model
// 0: no weight; 1: the shapes with a weight listed (at most 32), so a
// vertex looks only at those; 2: every entry of the vertex, weighted by
// u_morph_weights[s / 4][s % 4].
uniform int u_morph_mode;
uniform highp sampler2D u_morph_offsets;
uniform int u_morph_width;
uniform int u_morph_active_count;
uniform ivec4 u_morph_active[8];         // shape of active slot i: [i / 4][i % 4]
uniform vec4 u_morph_active_weights[8];
uniform vec4 u_morph_weights[32];

out vec3 v_position_view;
out vec3 v_normal_view;
out vec2 v_uv;
out vec3 v_color;
out vec3 v_barycentric;
out float v_occlusion;

uint bit_count(uint x) {  // GLSL ES 3.00 has no bitCount
  x = x - ((x >> 1u) & 0x55555555u);
  x = (x & 0x33333333u) + ((x >> 2u) & 0x33333333u);
  x = (x + (x >> 4u)) & 0x0F0F0F0Fu;
  return (x * 0x01010101u) >> 24u;
}

ivec2 morph_texel(int t) { return ivec2(t % u_morph_width, t / u_morph_width); }

void main() {
  vec3 position = a_position, normal = a_normal;
  if (u_morph_mode == 1 && any(notEqual(a_morph_mask, uvec4(0u)))) {
    for (int i = 0; i < u_morph_active_count; ++i) {
      int s = u_morph_active[i / 4][i % 4];
      int word = s / 32;
      uint bit = uint(s % 32), m = a_morph_mask[word];
      if (((m >> bit) & 1u) == 0u) continue;
      // The entry's place among the vertex's: the shapes before s it has.
      uint before = bit_count(m & ((1u << bit) - 1u));
      for (int k = 0; k < word; ++k) before += bit_count(a_morph_mask[k]);
      int t = 2 * (int(a_morph.x) + int(before));
      float w = u_morph_active_weights[i / 4][i % 4];
      position += w * texelFetch(u_morph_offsets, morph_texel(t), 0).xyz;
      normal += w * texelFetch(u_morph_offsets, morph_texel(t + 1), 0).xyz;
    }
  } else if (u_morph_mode == 2) {
    int first = int(a_morph.x), count = int(a_morph.y);
    for (int k = 0; k < count; ++k) {
      int t = 2 * (first + k);
      vec4 dp = texelFetch(u_morph_offsets, morph_texel(t), 0);
      int s = int(dp.w);
      float w = u_morph_weights[s / 4][s % 4];
      if (w == 0.0) continue;
      position += w * dp.xyz;
      normal += w * texelFetch(u_morph_offsets, morph_texel(t + 1), 0).xyz;
    }
  }
  vec4 p = u_view * u_model * vec4(position, 1.0);
  v_position_view = p.xyz;
  v_normal_view = u_normal_matrix * normal;
  v_uv = a_uv;
  v_color = a_color;
  v_barycentric = a_barycentric;
  v_occlusion = a_occlusion;
  gl_Position = u_projection * p;
}
