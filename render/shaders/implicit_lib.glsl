// Helpers of the generated implicit-surface code (core/implicit/expression.h: Expression::glsl):
// powers, real powers and Chebyshev polynomials, each as a value and as a dual (value, ∇).

// aⁿ by repeated squaring (a < 0 fine: a whole exponent is a product).
float qx_powi(float a, int n) {
  float r = 1.0, b = a;
  for (int m = abs(n); m > 0; m >>= 1) {
    if ((m & 1) != 0) r *= b;
    b *= b;
  }
  return n < 0 ? 1.0 / r : r;
}

// a^e: a product for whole e, else pow (undefined for a < 0, as on the CPU where it is NaN).
float qx_pow(float a, float e) {
  if (e == floor(e) && abs(e) < 65536.0) return qx_powi(a, int(e));
  return a < 0.0 ? (0.0 / 0.0) : pow(a, e);
}

// asin and acos to about 2 ulp (the Cephes asinf polynomial, 5e-9 from the true functions on
// [−1, 1]). Mesa's built-in acos on llvmpipe is off by up to 2e-4 rad (measured: a plane
// z = acos(0.3 + 0.01y) − 0.5 lands 1.9e-4 deep), which cos(n·acos x) multiplies by n.
float qx_asin_core(float z) {  // |z| ≤ 0.5
  float s = z * z;
  return ((((4.2163199048e-2 * s + 2.4181311049e-2) * s + 4.5470025998e-2) * s + 7.4953002686e-2) * s +
          1.6666752422e-1) * s * z + z;
}
float qx_asin(float x) {
  float a = abs(x);
  float r = a > 0.5 ? 1.57079632679 - 2.0 * qx_asin_core(sqrt(0.5 * (1.0 - a))) : qx_asin_core(a);
  return x < 0.0 ? -r : r;
}
float qx_acos(float x) {
  if (x > 0.5) return 2.0 * qx_asin_core(sqrt(0.5 * (1.0 - x)));
  if (x < -0.5) return 3.14159265359 - 2.0 * qx_asin_core(sqrt(0.5 * (1.0 + x)));
  return 1.57079632679 - qx_asin_core(x);
}

vec4 qx_div(vec4 a, vec4 b) {
  float q = a.x / b.x;
  return vec4(q, (a.yzw - q * b.yzw) / b.x);
}
dvec4 qx_div(dvec4 a, dvec4 b) {  // the double-precision code (far from the origin)
  double q = a.x / b.x;
  return dvec4(q, (a.yzw - q * b.yzw) / b.x);
}

// (T_n(x), T_n′(x)) by the three-term recurrences of T and U (T_n′ = n·U_{n−1}).
vec2 qx_cheb(int n, float x) {
  if (n == 0) return vec2(1.0, 0.0);
  float t0 = 1.0, t1 = x, u0 = 1.0, u1 = 2.0 * x;
  for (int k = 1; k < n; ++k) {
    float t2 = 2.0 * x * t1 - t0;
    t0 = t1;
    t1 = t2;
    float u2 = 2.0 * x * u1 - u0;
    u0 = u1;
    u1 = u2;
  }
  return vec2(t1, float(n) * u0);
}

vec4 qx_cheb_dual(int n, vec4 a) {
  vec2 c = qx_cheb(n, a.x);
  return vec4(c.x, c.y * a.yzw);
}
dvec4 qx_cheb_dual(int n, dvec4 a) {  // T_n in float, its argument's gradient in double
  vec2 c = qx_cheb(n, float(a.x));
  return dvec4(double(c.x), double(c.y) * a.yzw);
}
