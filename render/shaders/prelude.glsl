#version 450 core
// Shared prelude of every Quadrix shader stage: ray–quadric roots and depth helpers.
// [Stoll06] eq. 6–7, 14–15; DESIGN §5.

// A position relative to the view target, from a pass's fixed-point origin (render/passes/frame.h
// FixedOrigin): the primitive's offset from the origin as int bits of whole quanta plus a float
// rest, and the origin − the target the same way (set_origin_uniforms). Integers add exactly, so
// near the target the large parts cancel whatever the compiler reorders (it does reorder float
// sums: a hi + lo split kept nothing on llvmpipe).
uniform ivec3 u_origin_q;
uniform vec3 u_origin_rest;
uniform float u_quantum;
vec3 from_fixed_origin(ivec3 quanta, vec3 rest) {
  return vec3(u_origin_q + quanta) * u_quantum + (u_origin_rest + rest);
}
vec3 from_fixed_origin(vec3 quanta_bits, vec3 rest) {  // quanta stored as float bits (buffers of floats)
  return from_fixed_origin(floatBitsToInt(quanta_bits), rest);
}

// Real roots of a·λ² + 2b·λ + c = 0, ascending, by the q-form (no cancellation in −b ∓ √D).
// Returns the root count (0, 1 or 2). The linear case a ≈ 0 falls out of λ = c/q.
int solve_quadratic(float a, float b, float c, out float t0, out float t1) {
  float disc = b * b - a * c;
  if (disc < 0.0) return 0;
  float q = -(b + (b < 0.0 ? -sqrt(disc) : sqrt(disc)));
  if (q == 0.0) { t0 = t1 = 0.0; return 1; }
  float r0 = c / q;
  if (a == 0.0) { t0 = t1 = r0; return 1; }
  float r1 = q / a;
  t0 = min(r0, r1);
  t1 = max(r0, r1);
  return 2;
}

// The front-facing root (a·λ + b < 0, [Stoll06] eq. 14): λ = (−b − √D)/a written stably.
bool front_root(float a, float b, float c, out float t) {
  float disc = b * b - a * c;
  if (disc <= 0.0) return false;
  float s = sqrt(disc);
  if (b > 0.0) {
    if (a == 0.0) return false;
    t = -(b + s) / a;
  } else {
    t = c / (s - b);
  }
  return true;
}

// Window depth in [0,1] of an eye-space z (negative in front of the camera) for an OpenGL
// perspective projection P.
float window_depth(float z_eye, mat4 P) {
  float clip_z = P[2][2] * z_eye + P[3][2];
  float clip_w = -z_eye;
  return 0.5 * (clip_z / clip_w) + 0.5;
}

// The window depth a full-screen pass writes for a G-buffer pixel it covers: below the far
// plane's 1.0 even where the hit lies beyond it, so that "depth < 1" holds at every covered pixel
// and the deferred shading's depth test skips the background (render/passes/shade_pass.h).
const float kBelowFar = 0.99999994;  // the largest float below 1
float covered_window_depth(float z_eye, mat4 P) {
  return min(window_depth(z_eye, P), kBelowFar);
}

// The projected ellipse of x = C + M u (eye space), S = M Mᵀ, in NDC for K = (P₀₀, P₁₁) (in
// slopes x/(−z) for K = 1): centre c and shape S2 = L Lᵀ. From the dual conic D = P Q* Pᵀ normalised by −D₃₃ = C_z² − S_zz; the C Cᵀ terms of
// c cᵀ + D₂ₓ₂ cancel analytically, so they are never formed (far, small glyphs keep their digits).
// The result is invariant under (C, S) → (C/L, S/L²): callers pass lengths in units of the
// glyph's distance, so the fourth powers stay within float's range.
void project_ellipse(vec3 C, mat3 S, vec2 K, out vec2 c, out mat2 S2) {
  float den = C.z * C.z - S[2][2];
  vec2 sz = vec2(S[0][2], S[1][2]);
  vec2 Cxy = C.xy;
  c = K * (sz - Cxy * C.z) / den;
  mat2 sxy = mat2(S[0][0], S[0][1], S[1][0], S[1][1]);
  mat2 N = (den * sxy + S[2][2] * outerProduct(Cxy, Cxy) + outerProduct(sz, sz)) -
           C.z * (outerProduct(sz, Cxy) + outerProduct(Cxy, sz));
  S2 = mat2(K.x * K.x * N[0][0], K.x * K.y * N[0][1], K.x * K.y * N[1][0], K.y * K.y * N[1][1]) / (den * den);
}

// Support of the ellipse (c, S2) in the unit direction n.
float support(vec2 c, mat2 S2, vec2 n) { return dot(n, c) + sqrt(max(dot(n, S2 * n), 0.0)); }
// Support of the hull of two ellipses (a capped cylinder's projection: its two end discs).
float hull_support(vec2 c0, mat2 S0, vec2 c1, mat2 S1, vec2 n) { return max(support(c0, S0, n), support(c1, S1, n)); }

vec3 unpack_colour(uint c) {
  return vec3(float(c & 0xFFu), float((c >> 8) & 0xFFu), float((c >> 16) & 0xFFu)) / 255.0;
}

// Triangle strip order over a convex polygon's vertices: 0, 1, N−1, 2, N−2, …
int strip_vertex(int i, int n) { return i == 0 ? 0 : (i & 1) != 0 ? (i + 1) / 2 : n - i / 2; }
