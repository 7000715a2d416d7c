#version 300 es
// Round sprites shaded as tiny spheres lit from the key light's side, so a
// dense cloud reads as a surface and single points read as dots.
precision highp float;

in vec3 v_color;
uniform vec3 u_key_dir;
uniform float u_exposure;
out vec4 frag_color;

vec3 linear_to_srgb(vec3 c) {
  c = clamp(c, 0.0, 1.0);
  vec3 lo = c * 12.92;
  vec3 hi = 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055;
  return mix(lo, hi, step(vec3(0.0031308), c));
}

void main() {
  vec2 c = gl_PointCoord * 2.0 - 1.0;
  c.y = -c.y;  // gl_PointCoord grows downwards
  float r2 = dot(c, c);
  if (r2 > 1.0) discard;
  vec3 sphere_normal = vec3(c, sqrt(1.0 - r2));
  float light = 0.55 + 0.45 * max(dot(sphere_normal, normalize(u_key_dir)), 0.0);
  frag_color = vec4(linear_to_srgb(v_color * light * u_exposure), 1.0);
}
