#version 300 es
// Vertical gradient, interpolated in sRGB (as designers pick gradients), with
// a tiny ordered dither so 8-bit output shows no banding.
precision highp float;
in float v_height;
uniform vec3 u_top;     // sRGB
uniform vec3 u_bottom;  // sRGB
out vec4 frag_color;

void main() {
  vec3 c = mix(u_bottom, u_top, clamp(v_height, 0.0, 1.0));
  ivec2 q = ivec2(gl_FragCoord.xy) & 1;
  float dither = (float((q.x * 2 + q.y * 3) & 3) - 1.5) / (255.0 * 4.0);
  frag_color = vec4(c + dither, 1.0);
}
