// Glyph pass, fragment stage ([Sigg06] §3, eq. 6–9): the ray is taken into the glyph's
// parameter space u = M⁻¹(x − C), where the glyph is the unit sphere (sphere, ellipsoid) or the
// unit cylinder |u_z| ≤ 1 with its two caps; solved there (glyph_lib.glsl); the eye-space depth
// read off the ray parameter and the normal carried back as M⁻ᵀ∇(u) (eq. 9). Hits nearest the
// eye first; with culling, front-facing hits only (as the CPU reference).
//
// GLYPH_NEAREST (glyph_pass.cpp, the early-depth path): the depth test runs before this stage
// against the occluders' depth, and the stage writes nothing but the nearest hit's depth per
// pixel (atomic min of its bits: window depths are non-negative); drawn again (u_index_pass), the
// index of the glyph hit at that depth (the smallest, on ties) for glyph_resolve.frag.
in vec3 v_dir;
in vec3 v_offset;
flat in float v_centre_z;
flat in float v_scale;  // the ray parameter σ is s / v_scale (huge and tiny glyphs stay in float)
flat in vec3 v_inv0;
flat in vec3 v_inv1;
flat in vec3 v_inv2;
flat in uint v_kind;
flat in uint v_colour;
flat in int v_id;
flat in uint v_index;

layout(std430, binding = 1) buffer Stats {
  uint culled; uint drawn; uint splat_fragments; uint hit_fragments; uint glyph_fragments; uint glyph_hit_fragments;
} stats;

uniform mat4 u_proj;
uniform mat3 u_view_rot;
uniform vec2 u_viewport;
uniform float u_target_distance;
uniform float u_near;  // hits nearer the eye than the near plane are skipped (glyph_lib.glsl)
uniform int u_cull;
uniform int u_count_stats;
uniform int u_proxy;  // debug: every proxy fragment is written, flat, without ray casting

#ifdef GLYPH_NEAREST
layout(early_fragment_tests) in;
layout(std430, binding = 2) buffer Nearest { uint nearest[]; };  // per pixel: window depth bits, glyph index
uniform int u_index_pass;  // 0: the nearest depth; 1: the glyph at that depth
#else
layout(depth_greater) out float gl_FragDepth;
layout(location = 0) out vec4 out_normal_depth;  // world normal (facing the viewer), eye depth
layout(location = 1) out vec4 out_albedo;
layout(location = 2) out int out_id;
#endif

void main() {
  if (u_count_stats != 0) atomicAdd(stats.glyph_fragments, 1u);
#ifdef GLYPH_NEAREST
  // Only the ray's direction and the glyph's index come interpolated (llvmpipe sets up every
  // input of every triangle); the rest is read here.
  GlyphRay r = glyph_ray(glyphs[v_index], v_dir.xy, u_view_rot, u_target_distance);
  GlyphHit h = cast_glyph(r.o, r.d, r.kind, r.scale, r.centre_z, u_near, u_cull != 0);
  if (!h.found) discard;
  if (u_count_stats != 0) atomicAdd(stats.glyph_hit_fragments, 1u);
  ivec2 p = ivec2(gl_FragCoord.xy);
  float depth = clamp(window_depth(r.centre_z - h.s, u_proj), 0.0, 1.0);  // as gl_FragDepth is clamped
  int i = 2 * (p.y * int(u_viewport.x) + p.x);
  // One program for both draws, so the second computes the very same bits.
  if (u_index_pass == 0)
    atomicMin(nearest[i], floatBitsToUint(depth));
  else if (floatBitsToUint(depth) == nearest[i])
    atomicMin(nearest[i + 1], v_index);
#else
  mat3 inv = transpose(mat3(v_inv0, v_inv1, v_inv2));
  vec3 o = inv * v_offset;  // ray in parameter space: u(σ) = o + σ·d
  vec3 d = inv * (v_dir * v_scale);  // per unit σ
  GlyphHit h;
  if (u_proxy != 0) {
    h.found = true;
    h.s = 0.0;
    h.grad = -d;
  } else {
    h = cast_glyph(o, d, v_kind, v_scale, v_centre_z, u_near, u_cull != 0);
  }
  if (!h.found) discard;
  if (u_count_stats != 0) atomicAdd(stats.glyph_hit_fragments, 1u);
  float z = v_centre_z - h.s;  // eye-space z of the hit (the ray's z falls by 1 per unit s)
  gl_FragDepth = window_depth(z, u_proj);
  out_normal_depth = vec4(transpose(u_view_rot) * glyph_normal(inv, h.grad, v_dir), -z);
  out_albedo = vec4(unpack_colour(v_colour), 1.0);
  out_id = v_id;
#endif
}
