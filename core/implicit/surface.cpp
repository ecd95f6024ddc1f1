#include "core/implicit/surface.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "core/error.h"

namespace quadrix::implicit {

CompiledImplicit compile(const ImplicitSurface& s) {
  CompiledImplicit c{Expression::parse(s.expression), {}, s.bounds};
  if (s.bounds.empty() || !s.bounds.min.allFinite() || !s.bounds.max.allFinite())
    throw InvalidInput(fmt::format("implicit surface '{}': bounds must be finite and not empty", s.expression));
  for (const std::string& name : c.expression.parameters()) {
    const auto it = s.parameters.find(name);
    if (it == s.parameters.end())
      throw InvalidInput(fmt::format("implicit surface '{}': parameter '{}' has no value", s.expression, name));
    if (!std::isfinite(it->second))
      throw InvalidInput(fmt::format("implicit surface '{}': parameter '{}' = {} is not finite", s.expression, name,
                                     it->second));
    c.parameters.push_back(it->second);
  }
  for (const auto& [name, value] : s.parameters)
    if (std::find(c.expression.parameters().begin(), c.expression.parameters().end(), name) ==
        c.expression.parameters().end())
      throw InvalidInput(fmt::format("implicit surface '{}': it has no parameter '{}'", s.expression, name));
  return c;
}

Interval clip_to_box(const Ray& ray, const Box3& box) {
  double lo = -std::numeric_limits<double>::infinity(), hi = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 3; ++k) {
    if (ray.dir[k] == 0.0) {
      if (ray.origin[k] < box.min[k] || ray.origin[k] > box.max[k]) return Interval::empty();
      continue;
    }
    double a = (box.min[k] - ray.origin[k]) / ray.dir[k], b = (box.max[k] - ray.origin[k]) / ray.dir[k];
    if (a > b) std::swap(a, b);
    lo = std::max(lo, a);
    hi = std::min(hi, b);
  }
  return {lo, hi};
}

std::optional<ImplicitRoot> first_root(const CompiledImplicit& s, const Ray& ray, double tmin, double tmax,
                                       const RootOptions& o) {
  Interval range = intersect(clip_to_box(ray, s.bounds), {tmin, tmax});
  if (range.is_empty()) return std::nullopt;
  const Expression& e = s.expression;
  const auto at = [&](double t) { return e.enclose(ray.origin, ray.dir, Interval::point(t), s.parameters).value; };
  const double tol = std::max(o.tolerance * s.bounds.diagonal(), 4 * std::numeric_limits<double>::epsilon() * range.mag());
  // Depth-first, nearer half first: the first interval that keeps a root holds the first root.
  std::vector<Interval> stack{range};
  int visited = 0;
  while (!stack.empty()) {
    const Interval I = stack.back();
    stack.pop_back();
    const double m = I.mid();
    if (++visited > o.max_intervals) return ImplicitRoot{m, false};
    const RayEnclosure E = e.enclose(ray.origin, ray.dir, I, s.parameters);
    if (E.value.is_empty() || !E.value.contains(0.0)) continue;
    // Mean-value form F(m) + F′(I)·(I − m): tight on narrow intervals where the natural form is not.
    if (!E.derivative.is_empty()) {
      const Interval mv = at(m) + E.derivative * (I - Interval::point(m));
      if (!mv.is_empty() && !mv.contains(0.0) && std::isfinite(mv.lo) && std::isfinite(mv.hi)) continue;
    }
    if (!E.derivative.is_empty() && !E.derivative.contains(0.0)) {
      // Strictly monotone on I: a proven sign change holds exactly one root; equal signs none.
      const Interval fa = at(I.lo), fb = at(I.hi);
      const bool neg_pos = fa.hi < 0 && fb.lo > 0, pos_neg = fa.lo > 0 && fb.hi < 0;
      if (neg_pos || pos_neg) {
        double a = I.lo, b = I.hi;
        const double sa = neg_pos ? -1.0 : 1.0;
        for (int k = 0; k < 200 && b - a > 2 * std::numeric_limits<double>::epsilon() * std::max(std::abs(a), std::abs(b)); ++k) {
          const double c = 0.5 * (a + b);
          const double fc = e.value(ray.at(c), s.parameters);
          if (fc == 0.0) { a = b = c; break; }
          if ((fc < 0) == (sa < 0)) a = c; else b = c;
        }
        return ImplicitRoot{0.5 * (a + b), true};
      }
      if ((fa.lo > 0 && fb.lo > 0) || (fa.hi < 0 && fb.hi < 0)) continue;
    }
    if (I.width() <= tol) return ImplicitRoot{m, false};
    stack.push_back({m, I.hi});
    stack.push_back({I.lo, m});
  }
  return std::nullopt;
}

}  // namespace quadrix::implicit
