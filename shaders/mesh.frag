#version 300 es
// Key + fill + rim lights fixed to the camera, hemisphere ambient, wrapped
// diffuse (a cheap stand-in for skin's subsurface softening of the
// terminator) and Blinn-Phong specular with Schlick Fresnel. Shading is
// linear; the output is sRGB-encoded because the framebuffers we draw into
// (WebGL2 canvas, OSMesa buffer) do no conversion.
precision highp float;

in vec3 v_position_view;
in vec3 v_normal_view;
in vec2 v_uv;
in vec3 v_color;
in vec3 v_barycentric;
in float v_occlusion;

// 0 = u_base_color, 1 = vertex color, 2 = texture
uniform int u_albedo_source;
uniform vec3 u_base_color;  // linear
uniform sampler2D u_texture; // sRGB8_ALPHA8: sampled values are linear
uniform float u_specular;
uniform float u_shininess;
uniform bool u_has_occlusion;

uniform bool u_surface;
uniform bool u_flat;        // facet normals from screen-space derivatives
uniform bool u_wireframe;
uniform vec3 u_wire_color;  // linear
uniform float u_wire_width; // pixels

uniform vec3 u_key_dir;
uniform vec3 u_key_color;
uniform vec3 u_fill_dir;
uniform vec3 u_fill_color;
uniform vec3 u_rim_dir;
uniform vec3 u_rim_color;
uniform vec3 u_ambient_sky;
uniform vec3 u_ambient_ground;
uniform float u_exposure;

out vec4 frag_color;

vec3 linear_to_srgb(vec3 c) {
  c = clamp(c, 0.0, 1.0);
  vec3 lo = c * 12.92;
  vec3 hi = 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055;
  return mix(lo, hi, step(vec3(0.0031308), c));
}

// Soft shoulder above 0.8 so bright highlights roll off instead of clipping.
vec3 tone_map(vec3 c) {
  vec3 over = max(c - 0.8, 0.0);
  return min(c, 0.8) + over / (1.0 + over * 5.0);
}

// Wrapped Lambert: light reaches a little past the terminator, tinted warm
// where it wraps, as light scattered under skin would be.
vec3 wrapped_diffuse(vec3 n, vec3 l, vec3 albedo) {
  const float wrap = 0.35;
  float ndl = dot(n, l);
  float lit = max((ndl + wrap) / (1.0 + wrap), 0.0);
  float plain = max(ndl, 0.0);
  vec3 scatter_tint = vec3(1.0, 0.55, 0.45);
  return albedo * (plain + (lit - plain) * scatter_tint);
}

float blinn_phong(vec3 n, vec3 l, vec3 v) {
  vec3 h = normalize(l + v);
  float ndh = max(dot(n, h), 0.0);
  float ndl = max(dot(n, l), 0.0);
  // Normalization keeps the highlight's energy similar across shininess.
  return pow(ndh, u_shininess) * ndl * (u_shininess + 8.0) / 64.0;
}

void main() {
  // Barycentrics are 0 on an edge and grow inwards; fwidth turns them into
  // pixels. Each of the two triangles sharing an edge draws half the line.
  // (Unrolled meshes only; a uniform branch, so derivatives stay defined,
  // and the common case pays nothing for it.)
  float edge = 0.0;
  if (u_wireframe) {
    vec3 d = fwidth(v_barycentric);
    float half_width = 0.5 * u_wire_width;
    vec3 edge_ramp = smoothstep(d * (half_width - 0.5), d * (half_width + 0.5), v_barycentric);
    edge = 1.0 - min(min(edge_ramp.x, edge_ramp.y), edge_ramp.z);
  }

  if (!u_surface) {
    if (edge < 0.02) discard;
    frag_color = vec4(linear_to_srgb(u_wire_color), edge);
    return;
  }

  // Degenerate triangles have zero normals: face the viewer rather than NaN.
  vec3 n = dot(v_normal_view, v_normal_view) > 1e-20 ? normalize(v_normal_view) : vec3(0.0, 0.0, 1.0);
  if (!gl_FrontFacing) n = -n;  // insides (mouth bag, open scans) lit as seen
  if (u_flat) {
    // The triangle's plane from how the position changes across pixels;
    // already facing the viewer, so no front/back flip.
    vec3 facet = cross(dFdx(v_position_view), dFdy(v_position_view));
    if (dot(facet, facet) > 1e-30) n = normalize(facet);
  }
  vec3 v = normalize(-v_position_view);

  vec3 albedo = u_base_color;
  if (u_albedo_source == 1) albedo = v_color;
  if (u_albedo_source == 2) {
    // Textures are uploaded with premultiplied alpha. Alpha test: texels
    // below half coverage (the teeth texture's voids) are holes that show
    // whatever lies behind; the rest get their unpremultiplied colour.
    vec4 texel = texture(u_texture, v_uv);
    if (texel.a < 0.5) discard;
    albedo = texel.rgb / texel.a;
  }

  vec3 key = normalize(u_key_dir);
  vec3 fill = normalize(u_fill_dir);
  vec3 rim = normalize(u_rim_dir);
  // Baked occlusion darkens what reaches cavities: all of the ambient, part
  // of the direct light (a real shadow would need a shadow map).
  float ao = u_has_occlusion ? v_occlusion : 1.0;
  float direct_ao = mix(1.0, ao, 0.8);

  float ndv = max(dot(n, v), 0.0);
  // Powers by multiplication: software rasterizers pay for every pow().
  float m1 = 1.0 - ndv, m2 = m1 * m1;
  float fresnel = 0.04 + 0.96 * (m2 * m2 * m1);
  float ambient_t = 0.5 + 0.5 * n.y;
  vec3 color = albedo * mix(u_ambient_ground, u_ambient_sky, ambient_t) * ao;
  color += direct_ao * u_key_color *
           (wrapped_diffuse(n, key, albedo) +
            vec3(u_specular * mix(1.0, 2.5, fresnel)) * blinn_phong(n, key, v));
  color += direct_ao * u_fill_color *
           (albedo * max(dot(n, fill), 0.0) + vec3(0.3 * u_specular) * blinn_phong(n, fill, v));
  // Rim: light from behind grazing the silhouette, strongest where the
  // surface turns away from the viewer.
  float grazing = m2;
  color += ao * u_rim_color * grazing * max(dot(n, rim) + 0.3, 0.0) * mix(albedo, vec3(1.0), 0.3);

  color = tone_map(color * u_exposure);
  color = mix(color, u_wire_color, edge);
  frag_color = vec4(linear_to_srgb(color), 1.0);
}
