#version 300 es
// Point clouds as round sprites of a fixed size in pixels.
precision highp float;

layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;
layout(location = 3) in vec3 a_color;  // sRGB

uniform mat4 u_model;
uniform mat4 u_view;
uniform mat4 u_projection;
uniform float u_point_size;   // pixels
uniform int u_color_source;   // 0 = u_base_color, 1 = a_color, 2 = normal
uniform vec3 u_base_color;    // linear

out vec3 v_color;  // linear

vec3 srgb_to_linear(vec3 c) {
  vec3 lo = c / 12.92;
  vec3 hi = pow((c + 0.055) / 1.055, vec3(2.4));
  return mix(lo, hi, step(vec3(0.04045), c));
}

void main() {
  if (u_color_source == 1) {
    v_color = srgb_to_linear(clamp(a_color, 0.0, 1.0));
  } else if (u_color_source == 2) {
    // World-space normal as a color, so colors stay put while orbiting.
    vec3 n = normalize(mat3(u_model) * a_normal);
    v_color = srgb_to_linear(n * 0.5 + 0.5);
  } else {
    v_color = u_base_color;
  }
  gl_Position = u_projection * u_view * u_model * vec4(a_position, 1.0);
  gl_PointSize = u_point_size;
}
