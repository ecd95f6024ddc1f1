// SLIM passes 1 and 2 ([Stoll06] §5.1.1, DESIGN §6). SLIM_PASS 1 (visibility): depth of the first
// front-facing hit inside the ball (and its clip plane), pushed away from the eye by offset·R
// along the ray. SLIM_PASS 2 (accumulation): the same hit, tested against pass 1's depth without
// writing it, adds (w·n, w) and (w·depth, w·colour) into float targets; w is the SLIM weight.
// SLIM_EARLY (render/passes/slim_pass.h): pass 1 also writes its depth into a colour target;
// pass 2 runs the depth test before this stage, against the quad's conservative depth
// (slim.vert), writes no depth, and compares its hit with pass 1's depth read from that target.
in vec3 v_dir;
in vec3 v_offset;
flat in vec3 v_centre_eye;
flat in float v_radius;
flat in float v_max_push;  // the ball's own push bound (eye units), ≤ 0: u_max_push
flat in vec3 v_A0;
flat in vec3 v_A1;
flat in vec3 v_A2;
flat in vec4 v_bc;
flat in vec4 v_clip[4];
flat in uint v_colour;
flat in int v_id;

uniform mat4 u_proj;
uniform mat3 u_view_rot;
uniform float u_offset;    // pass 1 push-back, relative to R
uniform float u_max_push;  // and at most this (eye units), unless the ball has its own
uniform float u_near;
uniform int u_count_stats;
uniform int u_cull;
// Pass 2's fragments and the ray casts of both passes are counted after the glyphs' counters.
layout(std430, binding = 1) buffer Stats {
  uint culled;
  uint drawn;
  uint splat_fragments;
  uint hit_fragments;
  uint glyph_proxy_fragments;
  uint glyph_hit_fragments;
  uint accumulate_fragments;
  uint cast_fragments;
} stats;

#if defined(SLIM_EARLY) && SLIM_PASS == 2
layout(early_fragment_tests) in;
layout(binding = 0) uniform sampler2D u_pass1_depth;  // window depth after pass 1
#else
layout(depth_greater) out float gl_FragDepth;
#endif
#if defined(SLIM_EARLY) && SLIM_PASS == 1
layout(location = 0) out float out_pass1_depth;  // = gl_FragDepth, kept where the depth test passes
#endif
#if SLIM_PASS == 2
layout(location = 0) out vec4 out_normal_weight;  // Σ w·n (world), Σ w
layout(location = 1) out vec4 out_depth_colour;   // Σ w·depth, Σ w·rgb
#endif

float slim_weight(float r) {
  if (r < 0.5) return exp(-8.0 * r * r);
  float s = 1.0 - r;
  return r <= 1.0 ? 16.0 * exp(-2.0) * s * s * s * s : 0.0;
}

void main() {
#if SLIM_PASS == 1
  if (u_count_stats != 0) atomicAdd(stats.splat_fragments, 1u);  // [Toledo04] A_RTA
#else
  if (u_count_stats != 0) atomicAdd(stats.accumulate_fragments, 1u);
#endif
  vec3 d = normalize(v_dir);
  vec3 o = v_offset;
  // Outside the ball's projected disc: the ray misses the ball; no ray work ([Sigg06]).
  float od = dot(o, d);
  if (dot(o, o) - od * od > 1.0) discard;
  if (u_count_stats != 0) atomicAdd(stats.cast_fragments, 1u);
  mat3 A = mat3(v_A0, v_A1, v_A2);
  vec3 Ao_b = A * o + v_bc.xyz;
  float a = dot(d, A * d);
  float b = dot(d, Ao_b);
  float c = dot(o, Ao_b) + dot(v_bc.xyz, o) + v_bc.w;
  float t;
  if (!front_root(a, b, c, t)) discard;
  vec3 x = o + t * d;  // local units, eye axes
  float r = length(x);
  if (r > 1.0) discard;
  for (int k = 0; k < 4; ++k)  // an unused plane (n = 0, d = 0) keeps everything
    if (dot(v_clip[k].xyz, x) + v_clip[k].w < 0.0) discard;
  vec3 p = v_centre_eye + v_radius * x;  // eye space
  if (-p.z < u_near) discard;           // behind the eye or in front of the near plane
#if SLIM_PASS == 1
  if (u_count_stats != 0) atomicAdd(stats.hit_fragments, 1u);  // A_obj
  float z_push = p.z * (1.0 + min(u_offset * v_radius, v_max_push > 0.0 ? v_max_push : u_max_push) / length(p));
  // Below 1 in the depth buffer even when pushed past the far plane: the resolve runs only where
  // the depth is < 1 (render/passes/slim_pass.h). The colour target keeps it, clamped to 1 as a
  // written depth is, for pass 2's test.
  float depth = window_depth(z_push, u_proj);
  gl_FragDepth = min(depth, kBelowFar);
#ifdef SLIM_EARLY
  out_pass1_depth = min(depth, 1.0);
#endif
#else
#ifdef SLIM_EARLY
  // The depth test GL_LEQUAL on the hit (the clamp as for a written depth).
  if (min(window_depth(p.z, u_proj), 1.0) > texelFetch(u_pass1_depth, ivec2(gl_FragCoord.xy), 0).x) discard;
#else
  gl_FragDepth = covered_window_depth(p.z, u_proj);  // as pass 1's
#endif
  float w = slim_weight(r);
  if (w <= 0.0) discard;
  vec3 n_eye = normalize(A * x + v_bc.xyz);
  vec3 n = transpose(u_view_rot) * n_eye;
  out_normal_weight = vec4(w * n, w);
  out_depth_colour = vec4(w * -p.z, w * unpack_colour(v_colour));
#endif
}
