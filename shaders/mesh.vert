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

uniform mat4 u_model;
uniform mat4 u_view;
uniform mat4 u_projection;
uniform mat3 u_normal_matrix;  // inverse transpose of the upper 3x3 of view * model

out vec3 v_position_view;
out vec3 v_normal_view;
out vec2 v_uv;
out vec3 v_color;
out vec3 v_barycentric;
out float v_occlusion;

void main() {
  vec4 p = u_view * u_model * vec4(a_position, 1.0);
  v_position_view = p.xyz;
  v_normal_view = u_normal_matrix * a_normal;
  v_uv = a_uv;
  v_color = a_color;
  v_barycentric = a_barycentric;
  v_occlusion = a_occlusion;
  gl_Position = u_projection * p;
}
