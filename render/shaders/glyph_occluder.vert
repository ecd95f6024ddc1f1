// Glyph occluders, the early-depth path's first step: for each sphere and ellipsoid, a depth-only
// square that lies wholly in front of nothing but the glyph itself, so the depth buffer becomes
// an upper bound of the nearest glyph's depth and glyph.frag (GLYPH_NEAREST) runs only where a
// glyph can reach in front of it.
//
// The glyph contains the ball of radius a (its shortest semi-axis) about its centre C. The square
// is inscribed in that ball's cross-section of radius k·a in the plane z = C.z (parallel to the
// image, so its projection is an ellipse in NDC with radii K·k·a/|C.z|), and lies at depth C.z. A
// ray through a pixel inside passes that plane at a point p with |p − C| ≤ k·a, so it enters the
// ball before p by at least a(1 − k) along the ray: at least a(1 − k)·cos θ in z, θ the angle of
// the most oblique ray of the view. Occluders whose margin is under 16 float steps of depth, whose
// radius is under 2 pixels (vertex snapping), or which reach the near plane are not drawn.
uniform mat4 u_proj;
uniform mat3 u_view_rot;
uniform float u_target_distance;
uniform float u_near;
uniform vec2 u_viewport;

const float kInner = 0.85;  // k
const int kSides = 4;        // a square: llvmpipe's cost is per triangle more than per pixel

float ndc_depth(float z) { return (u_proj[2][2] * z + u_proj[3][2]) / -z; }

void main() {
  gl_Position = vec4(2.0, 2.0, 2.0, 1.0);  // nothing drawn unless every test below passes
  Glyph g = glyphs[gl_InstanceID];
  vec3 C = glyph_centre_eye(g, u_view_rot, u_target_distance);
  float a = g.s1.w;
  if (!(C.z + g.s1.z < -u_near * 1.0001)) return;  // reaches the near plane (or behind the eye)
  vec2 K = vec2(u_proj[0][0], u_proj[1][1]);
  vec2 radius = K * (kInner * a / -C.z);  // NDC
  if (!(min(radius.x * u_viewport.x, radius.y * u_viewport.y) >= 4.0)) return;  // 2 px
  float cos_min = inversesqrt(1.0 + 1.0 / (K.x * K.x) + 1.0 / (K.y * K.y));
  float depth = ndc_depth(C.z);
  float front = ndc_depth(C.z + 0.5 * (1.0 - kInner) * a * cos_min);
  if (!(depth < 1.0) || !(depth - front > 16.0 * 2.0 * 1.2e-7)) return;
  int k = strip_vertex(gl_VertexID, kSides);
  float ang = radians(360.0) * float(k) / float(kSides);
  gl_Position = vec4(K * C.xy / -C.z + radius * vec2(cos(ang), sin(ang)), depth, 1.0);
}
