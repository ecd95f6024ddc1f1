#include "core/implicit/interval.h"

#include <numbers>

namespace quadrix::implicit {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kPi = std::numbers::pi;

// Product of bounds where 0·∞ = 0 (the finite factor is an exact zero of the set).
double mul_bound(double a, double b) { return (a == 0.0 || b == 0.0) ? 0.0 : a * b; }

// Widened by k ulps relative (for results whose error grows with an amplification factor).
Interval widen_rel(double lo, double hi, double k) {
  const double e = k * std::numeric_limits<double>::epsilon();
  Interval r = widen(lo, hi);
  r.lo -= std::abs(r.lo) * e;
  r.hi += std::abs(r.hi) * e;
  return r;
}

// The non-negative part of a (the domain of sqrt, log, real powers).
Interval nonnegative(const Interval& a) { return {std::max(a.lo, 0.0), a.hi}; }

}  // namespace

Interval operator+(const Interval& a, const Interval& b) {
  if (a.is_empty() || b.is_empty()) return Interval::empty();
  return widen(a.lo + b.lo, a.hi + b.hi);
}
Interval operator-(const Interval& a, const Interval& b) {
  if (a.is_empty() || b.is_empty()) return Interval::empty();
  return widen(a.lo - b.hi, a.hi - b.lo);
}
Interval operator-(const Interval& a) { return a.is_empty() ? a : Interval{-a.hi, -a.lo}; }

Interval operator*(const Interval& a, const Interval& b) {
  if (a.is_empty() || b.is_empty()) return Interval::empty();
  const double p[4] = {mul_bound(a.lo, b.lo), mul_bound(a.lo, b.hi), mul_bound(a.hi, b.lo), mul_bound(a.hi, b.hi)};
  return widen(*std::min_element(p, p + 4), *std::max_element(p, p + 4));
}

Interval operator/(const Interval& a, const Interval& b) {
  if (a.is_empty() || b.is_empty()) return Interval::empty();
  if (b.contains(0.0)) return Interval::entire();
  const double p[4] = {a.lo / b.lo, a.lo / b.hi, a.hi / b.lo, a.hi / b.hi};
  return widen(*std::min_element(p, p + 4), *std::max_element(p, p + 4));
}

Interval pow_int(const Interval& a, int n) {
  if (a.is_empty()) return a;
  if (n == 0) return Interval::point(1.0);
  if (n == 1) return a;
  if (n < 0) return Interval::point(1.0) / pow_int(a, -n);
  if (n % 2 == 1) return widen_rel(std::pow(a.lo, n), std::pow(a.hi, n), 2);
  const Interval r = widen_rel(std::pow(a.mig(), n), std::pow(a.mag(), n), 2);
  return {std::max(r.lo, 0.0), r.hi};
}

Interval pow_real(const Interval& a, double b) {
  const Interval d = nonnegative(a);
  if (d.is_empty()) return d;
  if (b == 0.0) return Interval::point(1.0);
  const Interval r = b > 0 ? widen_rel(std::pow(d.lo, b), std::pow(d.hi, b), 2)
                           : widen_rel(std::pow(d.hi, b), std::pow(d.lo, b), 2);
  return {std::max(r.lo, 0.0), r.hi};
}

Interval sqrt(const Interval& a) {
  const Interval d = nonnegative(a);
  if (d.is_empty()) return d;
  const Interval r = widen(std::sqrt(d.lo), std::sqrt(d.hi));
  return {std::max(r.lo, 0.0), r.hi};
}

Interval exp(const Interval& a) {
  if (a.is_empty()) return a;
  const Interval r = widen(std::exp(a.lo), std::exp(a.hi));
  return {std::max(r.lo, 0.0), r.hi};
}

Interval log(const Interval& a) {
  const Interval d = nonnegative(a);
  if (d.is_empty()) return d;
  return widen(std::log(d.lo), std::log(d.hi));
}

Interval cos(const Interval& a) {
  if (a.is_empty()) return a;
  if (!(a.width() < 2 * kPi) || !std::isfinite(a.lo) || !std::isfinite(a.hi)) return {-1.0, 1.0};
  // Extremes inside: maxima at 2kπ, minima at (2k+1)π; the test is loosened so that rounding
  // of π can only add an extreme, never drop one.
  const double slack = 1e-12 * std::max(1.0, a.mag());
  const double k_max = std::ceil((a.lo - slack) / (2 * kPi));
  const double k_min = std::ceil((a.lo - slack - kPi) / (2 * kPi));
  double lo = std::min(std::cos(a.lo), std::cos(a.hi)), hi = std::max(std::cos(a.lo), std::cos(a.hi));
  if (2 * kPi * k_max <= a.hi + slack) hi = 1.0;
  if (2 * kPi * k_min + kPi <= a.hi + slack) lo = -1.0;
  const Interval r = widen(lo, hi);
  return {std::max(r.lo, -1.0), std::min(r.hi, 1.0)};
}

Interval sin(const Interval& a) { return cos(a - Interval::point(kPi / 2)); }

Interval tan(const Interval& a) {
  if (a.is_empty()) return a;
  if (!(a.width() < kPi)) return Interval::entire();
  // A pole π/2 + kπ inside (loosened as in cos) makes the range the whole line.
  const double slack = 1e-12 * std::max(1.0, a.mag());
  const double k = std::ceil((a.lo - slack - kPi / 2) / kPi);
  if (kPi / 2 + k * kPi <= a.hi + slack) return Interval::entire();
  return widen(std::tan(a.lo), std::tan(a.hi));
}

Interval asin(const Interval& a) {
  const Interval d = intersect(a, {-1.0, 1.0});
  if (d.is_empty()) return d;
  return widen(std::asin(d.lo), std::asin(d.hi));
}
Interval acos(const Interval& a) {
  const Interval d = intersect(a, {-1.0, 1.0});
  if (d.is_empty()) return d;
  const Interval r = widen(std::acos(d.hi), std::acos(d.lo));
  return {std::max(r.lo, 0.0), r.hi};
}
Interval atan(const Interval& a) {
  if (a.is_empty()) return a;
  return widen(std::atan(a.lo), std::atan(a.hi));
}
Interval sinh(const Interval& a) {
  if (a.is_empty()) return a;
  return widen(std::sinh(a.lo), std::sinh(a.hi));
}
Interval cosh(const Interval& a) {
  if (a.is_empty()) return a;
  const Interval r = widen(std::cosh(a.mig()), std::cosh(a.mag()));
  return {std::max(r.lo, 1.0), r.hi};
}
Interval acosh(const Interval& a) {
  const Interval d = {std::max(a.lo, 1.0), a.hi};
  if (d.is_empty()) return d;
  const Interval r = widen(std::acosh(d.lo), std::acosh(d.hi));
  return {std::max(r.lo, 0.0), r.hi};
}
Interval abs(const Interval& a) {
  if (a.is_empty()) return a;
  return {a.mig(), a.mag()};
}
Interval min(const Interval& a, const Interval& b) {
  if (a.is_empty() || b.is_empty()) return Interval::empty();
  return {std::min(a.lo, b.lo), std::min(a.hi, b.hi)};
}
Interval max(const Interval& a, const Interval& b) {
  if (a.is_empty() || b.is_empty()) return Interval::empty();
  return {std::max(a.lo, b.lo), std::max(a.hi, b.hi)};
}

Interval chebyshev(int n, const Interval& a) {
  if (a.is_empty()) return a;
  if (n == 0) return Interval::point(1.0);
  if (n == 1) return a;
  Interval r = Interval::empty();
  // |x| ≤ 1: T_n(cos θ) = cos(nθ), θ = acos x ∈ [0, π]; the range of cos over nθ is exact.
  if (const Interval in = intersect(a, {-1.0, 1.0}); !in.is_empty()) {
    const Interval theta = acos(in);
    Interval c = cos(Interval::point(n) * theta);
    const double e = 4.0 * n * std::numeric_limits<double>::epsilon();  // acos's error times n
    c = {std::max(c.lo - e, -1.0), std::min(c.hi + e, 1.0)};
    r = hull(r, c);
  }
  // x ≥ 1: T_n = cosh(n·acosh x), increasing; x ≤ −1: T_n(x) = (−1)ⁿ T_n(−x).
  const auto outer = [n](double l, double h) {  // 1 ≤ l ≤ h
    return widen_rel(std::cosh(n * std::acosh(l)), std::cosh(n * std::acosh(h)), 8.0 * n);
  };
  if (a.hi > 1.0) r = hull(r, outer(std::max(a.lo, 1.0), a.hi));
  if (a.lo < -1.0) {
    const Interval m = outer(std::max(-a.hi, 1.0), -a.lo);
    r = hull(r, n % 2 == 0 ? m : -m);
  }
  return r;
}

Interval chebyshev_derivative(int n, const Interval& a) {
  if (a.is_empty()) return a;
  if (n == 0) return Interval::point(0.0);
  if (n == 1) return Interval::point(1.0);
  const double nn = double(n) * n;  // |T_n′| ≤ n² on [−1, 1], reached at ±1
  Interval r = Interval::empty();
  if (const Interval in = intersect(a, {-1.0, 1.0}); !in.is_empty()) {
    // T_n′ = n·sin(nθ)/sin θ where θ stays away from 0 and π; else the bound n².
    const Interval theta = acos(in);
    Interval d{-nn, nn};
    if (theta.lo > 1e-3 && theta.hi < kPi - 1e-3) {
      const Interval q = Interval::point(n) * sin(Interval::point(n) * theta) / sin(theta);
      const double e = 1e-9 * nn;
      d = intersect(d, {q.lo - e, q.hi + e});
    }
    r = hull(r, d);
  }
  // x ≥ 1: T_n′ = n·sinh(nφ)/sinh φ with φ = acosh x, increasing from n² at x = 1.
  const auto outer = [n, nn](double l, double h) {
    const auto f = [n, nn](double x) {
      const double phi = std::acosh(x);
      return phi < 1e-8 ? nn : n * std::sinh(n * phi) / std::sinh(phi);
    };
    const Interval w = widen_rel(f(l), f(h), 16.0 * n);
    return Interval{std::max(std::min(w.lo, nn), 0.0), w.hi};
  };
  if (a.hi > 1.0) r = hull(r, outer(std::max(a.lo, 1.0), a.hi));
  if (a.lo < -1.0) {
    const Interval m = outer(std::max(-a.hi, 1.0), -a.lo);
    r = hull(r, n % 2 == 1 ? m : -m);
  }
  return r;
}

}  // namespace quadrix::implicit
