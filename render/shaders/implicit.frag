// Implicit surfaces by adaptive marching points ([Singh10] Algorithm 1): one full-screen pass
// per surface. S_value and S_grad (S and ∇S) are generated from the surface's expression and
// prepended with implicit_lib.glsl. The ray of each pixel is clipped to the surface's bounds
// box and the near plane, marched with the step of eq. 2, tested for a root by the sign test or
// the Taylor test (eq. 3), and the isolated interval bisected; depth and the G-buffer are
// written like every other kind, so implicits mix depth-correct with the other primitives.
in vec2 v_uv;

uniform mat4 u_proj;
uniform mat3 u_view_rot;
uniform vec2 u_viewport;
uniform float u_near;
// Positions relative to the surface's origin S_origin (render/passes/implicit_pass.h): the world's
// origin for surfaces near it, their bounds' centre, in double, for those far from it.
uniform vec3 u_eye;
uniform vec3 u_box_min;      // bounds
uniform vec3 u_box_max;
uniform float u_step;        // base step b, world units
uniform vec3 u_tau;          // τ₁ τ₂ τ₃ of eq. 2
uniform int u_taylor;        // 0: sign test, 1: Taylor test
uniform float u_newton;      // step cap: this fraction of |S|/|∇S·D| (0: off)
uniform float u_remainder;   // κ of the remainder test (0: off)
uniform float u_min_step;    // floor of the cap and of quartering
uniform int u_bisections;
uniform int u_max_steps;
uniform uint u_colour;
uniform int u_id;

layout(location = 0) out vec4 out_normal_depth;
layout(location = 1) out vec4 out_albedo;
layout(location = 2) out int out_id;

// A sign change between F(a) and F(b) (NaN outside the domain never changes sign).
bool sign_change(float fa, float fb) { return (fa < 0.0 && fb > 0.0) || (fa > 0.0 && fb < 0.0) || fb == 0.0; }

void main() {
  vec2 ndc = 2.0 * gl_FragCoord.xy / u_viewport - 1.0;
  vec3 e = normalize(vec3(ndc.x / u_proj[0][0], ndc.y / u_proj[1][1], -1.0));  // eye space
  vec3 d = transpose(u_view_rot) * e;                                          // world, unit
  // Slab test against the bounds; the near plane (eye z = −near) starts the range.
  vec3 inv = 1.0 / d;
  vec3 ta = (u_box_min - u_eye) * inv, tb = (u_box_max - u_eye) * inv;
  vec3 tlo = min(ta, tb), thi = max(ta, tb);
  float ts = max(max(tlo.x, tlo.y), max(tlo.z, u_near / -e.z));
  float te = min(min(thi.x, thi.y), thi.z);
  if (!(ts < te)) discard;

  float t = ts;
  vec4 g0 = S_grad(u_eye + t * d);
  float f0 = g0.x, df0 = dot(g0.yzw, d);
  bool found = false;
  float a = 0.0, b = 0.0, fa = 0.0, fb = 0.0;
  // The same maths as the CPU march, core/implicit/march.cpp (march_step, step_is_suspect).
  int steps = 0;
  while (steps < u_max_steps && t < te) {
    // Step size, eq. 2: proximity |S| and horizon |∇S·D|.
    float s = u_step;
    float af = abs(f0);
    if (af <= u_tau.x) s = abs(df0) <= u_tau.z ? 0.25 * u_step : 0.5 * u_step;
    else if (af > u_tau.y) s = 2.0 * u_step;
    if (u_newton > 0.0) {
      // A derivative that is not finite gives no Newton distance (∞·0 where cos(n·acos x) meets
      // its clamp at |x| = 1, the faces rays enter through): the floor, not b, is the safe step.
      float cap = isnan(df0) || isinf(df0) ? 0.0 : u_newton * af / abs(df0);
      s = max(min(s, cap), min(s, u_min_step));
    }
    float t1, f1, df1;
    for (;;) {
      t1 = min(t + s, te);
      vec4 g1 = S_grad(u_eye + t1 * d);
      f1 = g1.x, df1 = dot(g1.yzw, d);
      ++steps;
      if (sign_change(f0, f1) || steps >= u_max_steps || s <= u_min_step || u_remainder <= 0.0) break;
      // Remainder test: the Taylor lines from both ends to the middle must stay on the ends'
      // sign by κ·L·h²/2, L = |ΔF′|/s estimating |F″|; else a pair of roots may hide here.
      float w = t1 - t, h = 0.5 * w;
      float sg = f0 < 0.0 ? -1.0 : 1.0;
      float margin = 0.5 * u_remainder * abs(df1 - df0) / w * h * h;
      float q = sg * (f0 + df0 * h) - margin, r = sg * (f1 - df1 * h) - margin;
      if (q > 0.0 && r > 0.0) break;
      s = max(0.25 * s, u_min_step);
    }
    if (sign_change(f0, f1)) {
      a = t, b = t1, fa = f0, fb = f1;
      found = true;
      break;
    }
    if (u_taylor != 0) {
      // Taylor test, eq. 3: the end values and their linear extensions to the middle.
      float h = 0.5 * (t1 - t);
      float q = f0 + df0 * h, r = f1 - df1 * h;
      float lo = min(min(f0, f1), min(q, r)), hi = max(max(f0, f1), max(q, r));
      if (lo <= 0.0 && hi >= 0.0) {
        // A root may hide without a sign change: look closer (8 sub-steps, sign test).
        float pa = t, pf = f0;
        for (int k = 1; k <= 8; ++k) {
          float tk = mix(t, t1, float(k) / 8.0);
          float fk = S_value(u_eye + tk * d);
          if (sign_change(pf, fk)) {
            a = pa, b = tk, fa = pf, fb = fk;
            found = true;
            break;
          }
          pa = tk, pf = fk;
        }
        if (found) break;
      }
    }
    t = t1, f0 = f1, df0 = df1;
  }
  if (!found) discard;
  // Bisection of the isolated interval, keeping the half with the sign change.
  for (int k = 0; k < u_bisections; ++k) {
    float m = 0.5 * (a + b);
    float fm = S_value(u_eye + m * d);
    if (sign_change(fa, fm)) { b = m; fb = fm; } else { a = m; fa = fm; }
  }
  // Secant through the final bracket.
  float th = (fb != fa && fb != 0.0) ? clamp(a - fa * (b - a) / (fb - fa), a, b) : b;
  vec3 p = u_eye + th * d;
  vec3 grad = S_grad(p).yzw;
  vec3 n = dot(grad, grad) > 0.0 ? normalize(grad) : -d;
  if (dot(n, d) > 0.0) n = -n;  // two-sided: face the viewer
  float depth = th * -e.z;
  gl_FragDepth = window_depth(-depth, u_proj);
  out_normal_depth = vec4(n, depth);
  out_albedo = vec4(unpack_colour(u_colour), 1.0);
  out_id = u_id;
}
