#version 300 es
// The wireframe of an indexed mesh: GL_LINES over its unique edges, reading
// the same interleaved vertex buffer as the surface (only the position).
precision highp float;

layout(location = 0) in vec3 a_position;

uniform mat4 u_model;
uniform mat4 u_view;
uniform mat4 u_projection;

void main() {
  gl_Position = u_projection * (u_view * (u_model * vec4(a_position, 1.0)));
}
