#version 300 es
// Solid wire colour; the surface under the lines was pushed back by polygon
// offset, so the lines win the depth test where they lie on it.
precision highp float;

uniform vec3 u_wire_color;  // sRGB, written as is (the framebuffer is not sRGB-aware)

out vec4 frag_color;

void main() {
  frag_color = vec4(u_wire_color, 1.0);
}
