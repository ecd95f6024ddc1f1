// Glyph pass, fragment stage ([Sigg06] §3, eq. 6–9): the ray is taken into the glyph's
// parameter space u = M⁻¹(x − C), where the glyph is the unit sphere (sphere, ellipsoid) or the
// unit cylinder |u_z| ≤ 1 with its two caps; solved there; the eye-space depth read off the
// ray parameter and the normal carried back as M⁻ᵀ∇(u) (eq. 9). Hits nearest the eye first;
// with culling, front-facing hits only (as the CPU reference).
in vec3 v_dir;
in vec3 v_offset;
flat in float v_centre_z;
flat in float v_scale;  // the ray parameter σ below is s / v_scale (huge and tiny glyphs stay in float)
flat in vec3 v_inv0;
flat in vec3 v_inv1;
flat in vec3 v_inv2;
flat in uint v_kind;
flat in uint v_colour;
flat in int v_id;

layout(std430, binding = 1) buffer Stats {
  uint culled; uint drawn; uint splat_fragments; uint hit_fragments; uint glyph_fragments; uint glyph_hit_fragments;
} stats;

uniform mat4 u_proj;
uniform mat3 u_view_rot;
uniform int u_cull;
uniform int u_count_stats;
uniform int u_proxy;  // debug: every proxy fragment is written, flat, without ray casting

layout(depth_greater) out float gl_FragDepth;
layout(location = 0) out vec4 out_normal_depth;  // world normal (facing the viewer), eye depth
layout(location = 1) out vec4 out_albedo;
layout(location = 2) out int out_id;

float s_best;
vec3 g_best;  // gradient in parameter space at the best hit
bool found = false;

void consider(float sigma, vec3 grad_u, vec3 d) {
  float s = sigma * v_scale;
  if (s <= v_centre_z || (found && s >= s_best)) return;  // behind the eye, or not nearer
  if (u_cull != 0 && dot(grad_u, d) >= 0.0) return;     // back-facing
  s_best = s;
  g_best = grad_u;
  found = true;
}

void main() {
  if (u_count_stats != 0) atomicAdd(stats.glyph_fragments, 1u);
  mat3 inv = transpose(mat3(v_inv0, v_inv1, v_inv2));
  vec3 o = inv * v_offset;  // ray in parameter space: u(σ) = o + σ·d
  vec3 d = inv * (v_dir * v_scale);  // per unit σ
  if (u_proxy != 0) {
    s_best = 0.0;
    g_best = -d;
    found = true;
  } else if (v_kind != 2u) {
    float s0, s1;
    int n = solve_quadratic(dot(d, d), dot(o, d), dot(o, o) - 1.0, s0, s1);
    if (n > 0) consider(s0, o + s0 * d, d);
    if (n > 1) consider(s1, o + s1 * d, d);
  } else {
    float s0, s1;
    float a = dot(d.xy, d.xy);  // 0: the ray runs along the axis and meets only the caps
    int n = a > 0.0 ? solve_quadratic(a, dot(o.xy, d.xy), dot(o.xy, o.xy) - 1.0, s0, s1) : 0;
    vec3 u0 = o + s0 * d, u1 = o + s1 * d;
    if (n > 0 && abs(u0.z) <= 1.0) consider(s0, vec3(u0.xy, 0.0), d);
    if (n > 1 && abs(u1.z) <= 1.0) consider(s1, vec3(u1.xy, 0.0), d);
    if (d.z != 0.0) {
      for (int i = 0; i < 2; ++i) {
        float side = i == 0 ? 1.0 : -1.0;
        float s = (side - o.z) / d.z;
        vec2 uxy = o.xy + s * d.xy;
        if (dot(uxy, uxy) <= 1.0) consider(s, vec3(0.0, 0.0, side), d);
      }
    }
  }
  if (!found) discard;
  if (u_count_stats != 0) atomicAdd(stats.glyph_hit_fragments, 1u);
  // [Sigg06] eq. 9: the normal is M⁻ᵀ times the parameter-space gradient (eye axes here).
  vec3 n = transpose(inv) * g_best;
  n = normalize(n / max(max(abs(n.x), abs(n.y)), abs(n.z)));  // |n|² would leave float for tiny glyphs
  if (dot(n, v_dir) > 0.0) n = -n;  // two-sided when culling is off
  float z = v_centre_z - s_best;    // eye-space z of the hit (the ray's z falls by 1 per unit s)
  gl_FragDepth = window_depth(z, u_proj);
  out_normal_depth = vec4(transpose(u_view_rot) * n, -z);
  out_albedo = vec4(unpack_colour(v_colour), 1.0);
  out_id = v_id;
}
