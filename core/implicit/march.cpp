#include "core/implicit/march.h"

#include <algorithm>
#include <cmath>

namespace quadrix::implicit {
namespace {

// A sign change between F(a) and F(b) (NaN outside the domain never changes sign).
bool sign_change(double fa, double fb) { return (fa < 0 && fb > 0) || (fa > 0 && fb < 0) || fb == 0; }

}  // namespace

double march_step(const MarchSettings& m, double f, double df) {
  // Step size, eq. 2: proximity |S| and horizon |∇S·D|.
  double s = m.step;
  const double af = std::abs(f);
  if (af <= m.tau1) s = std::abs(df) <= m.tau3 ? 0.25 * m.step : 0.5 * m.step;
  else if (af > m.tau2) s = 2 * m.step;
  if (m.newton_fraction > 0) {
    // A derivative that is not finite gives no Newton distance: the floor, not b, is the safe step.
    const double cap = std::isfinite(df) ? m.newton_fraction * af / std::abs(df) : 0.0;
    s = std::max(std::min(s, cap), std::min(s, m.min_step));
  }
  return s;
}

bool step_is_suspect(const MarchSettings& m, double s, double f0, double df0, double f1, double df1) {
  if (m.remainder <= 0) return false;
  const double h = 0.5 * s;
  const double sg = f0 < 0 ? -1.0 : 1.0;  // f0 and f1 share this sign
  const double margin = 0.5 * m.remainder * std::abs(df1 - df0) / s * h * h;
  const double q = sg * (f0 + df0 * h) - margin, r = sg * (f1 - df1 * h) - margin;
  return !(q > 0 && r > 0);  // NaN (a derivative undefined) counts as suspect
}

MarchResult march_first_root(const CompiledImplicit& c, const Ray& ray, double tmin, double tmax,
                             const MarchSettings& m) {
  MarchResult out;
  const Interval range = intersect(clip_to_box(ray, c.bounds), {tmin, tmax});
  if (!(range.lo < range.hi)) return out;
  const auto eval = [&](double t) {
    const ValueGradient vg = c.expression.value_gradient(ray.at(t), c.parameters);
    return std::pair(vg.value, vg.gradient.dot(ray.dir));
  };
  const double ts = range.lo, te = range.hi;
  double t = ts;
  auto [f0, df0] = eval(t);
  bool found = false;
  double a = 0, b = 0, fa = 0, fb = 0;
  while (out.steps < m.max_steps && t < te) {
    double s = march_step(m, f0, df0);
    double t1 = 0, f1 = 0, df1 = 0;
    for (;;) {
      t1 = std::min(t + s, te);
      std::tie(f1, df1) = eval(t1);
      ++out.steps;
      if (sign_change(f0, f1) || out.steps >= m.max_steps || s <= m.min_step ||
          !step_is_suspect(m, t1 - t, f0, df0, f1, df1))
        break;
      s = std::max(0.25 * s, m.min_step);
      ++out.rejected;
    }
    if (sign_change(f0, f1)) {
      a = t, b = t1, fa = f0, fb = f1;
      found = true;
      break;
    }
    if (m.taylor) {
      // Taylor test, eq. 3: the end values and their linear extensions to the middle.
      const double h = 0.5 * (t1 - t);
      const double q = f0 + df0 * h, r = f1 - df1 * h;
      const double lo = std::min({f0, f1, q, r}), hi = std::max({f0, f1, q, r});
      if (lo <= 0 && hi >= 0) {
        // A root may hide without a sign change: look closer (8 sub-steps, sign test).
        double pa = t, pf = f0;
        for (int k = 1; k <= 8 && !found; ++k) {
          const double tk = t + (t1 - t) * k / 8.0;
          const double fk = c.expression.value(ray.at(tk), c.parameters);
          if (sign_change(pf, fk)) a = pa, b = tk, fa = pf, fb = fk, found = true;
          pa = tk, pf = fk;
        }
        if (found) break;
      }
    }
    t = t1, f0 = f1, df0 = df1;
  }
  if (!found) return out;
  // Bisection of the isolated interval, keeping the half with the sign change.
  for (int k = 0; k < m.bisections; ++k) {
    const double mid = 0.5 * (a + b);
    const double fm = c.expression.value(ray.at(mid), c.parameters);
    if (sign_change(fa, fm)) b = mid, fb = fm;
    else a = mid, fa = fm;
  }
  // Secant through the final bracket.
  out.t = (fb != fa && fb != 0) ? std::clamp(a - fa * (b - a) / (fb - fa), a, b) : b;
  return out;
}

}  // namespace quadrix::implicit
