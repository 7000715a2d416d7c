#version 300 es
// One triangle covering the viewport, made from gl_VertexID (no buffers).
precision highp float;
out float v_height;  // 0 at the bottom of the viewport, 1 at the top

void main() {
  vec2 p = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2));  // (0,0) (2,0) (0,2)
  v_height = p.y;
  gl_Position = vec4(p * 2.0 - 1.0, 1.0, 1.0);
}
