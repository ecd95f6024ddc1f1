// The depth buffer from the G-buffer's eye depth, where a pass wrote a conservative depth there
// (the tetrahedron pass writes its entry faces' depth so the early depth test stays on).
layout(binding = 0) uniform sampler2D g_normal_depth;
uniform mat4 u_proj;

void main() {
  float eye_depth = texelFetch(g_normal_depth, ivec2(gl_FragCoord.xy), 0).w;
  if (!(eye_depth > 0.0)) discard;
  gl_FragDepth = covered_window_depth(-eye_depth, u_proj);
}
