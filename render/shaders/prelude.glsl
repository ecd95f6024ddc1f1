#version 450 core
// Shared prelude of every Quadrix shader stage: ray–quadric roots and depth helpers.
// [Stoll06] eq. 6–7, 14–15; DESIGN §5.

// Positions relative to an origin o, from split (hi + lo) floats: the double-single trick keeps the
// difference of two large coordinates exact to float precision.
vec3 camera_relative(vec3 p_hi, vec3 p_lo, vec3 o_hi, vec3 o_lo) {
  return (p_hi - o_hi) + (p_lo - o_lo);
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

vec3 unpack_colour(uint c) {
  return vec3(float(c & 0xFFu), float((c >> 8) & 0xFFu), float((c >> 16) & 0xFFu)) / 255.0;
}
