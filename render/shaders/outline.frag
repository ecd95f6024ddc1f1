// Outlines [Sigg06] §5: the detector of core/outlines.h (keep the two in step). One-pixel black
// lines on covered pixels: next to background (silhouettes), on the nearer side of a depth
// discontinuity (nearer than its two neighbours predict, linear in 1/depth, by more than u_min_gap
// and u_depth_pixels footprints), before a crease along +x or +y (normals differ by more than the
// crease angle).
in vec2 v_uv;
layout(binding = 0) uniform sampler2D g_normal_depth;
uniform mat4 u_proj;
uniform vec2 u_viewport;
uniform float u_min_gap;       // world units
uniform float u_depth_pixels;  // pixel footprints
uniform float u_cos_crease;
out vec4 out_colour;

bool inside(ivec2 q) { return all(greaterThanEqual(q, ivec2(0))) && all(lessThan(q, ivec2(u_viewport))); }
vec4 at(ivec2 q) { return inside(q) ? texelFetch(g_normal_depth, q, 0) : vec4(0.0); }

bool is_edge(ivec2 p) {
  const ivec2 k[4] = ivec2[4](ivec2(1, 0), ivec2(-1, 0), ivec2(0, 1), ivec2(0, -1));
  vec4 c = at(p);
  if (!(c.w > 0.0)) return false;
  for (int i = 0; i < 4; ++i)
    if (inside(p + k[i]) && !(at(p + k[i]).w > 0.0)) return true;
  // Pixel footprint at depth d: d·2·tan(fov/2)/height = 2d/(P[1][1]·height).
  float limit = max(u_min_gap, u_depth_pixels * c.w * 2.0 / (u_proj[1][1] * u_viewport.y));
  for (int axis = 0; axis < 2; ++axis) {
    vec4 a = at(p - k[2 * axis]), b = at(p + k[2 * axis]);
    if (!(a.w > 0.0) || !(b.w > 0.0)) continue;
    float predicted = 2.0 / (1.0 / a.w + 1.0 / b.w);
    if (predicted - c.w > limit) return true;
  }
  for (int i = 0; i < 4; i += 2) {
    vec4 q = at(p + k[i]);
    if (q.w > 0.0 && dot(c.xyz, q.xyz) < u_cos_crease) return true;
  }
  return false;
}

void main() {
  if (!is_edge(ivec2(gl_FragCoord.xy))) discard;
  out_colour = vec4(0.0, 0.0, 0.0, 1.0);
}
