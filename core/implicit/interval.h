#pragma once
/// Closed intervals of doubles with outward rounding (one ulp either way after every operation),
/// the enclosures that the reference's guaranteed root isolation rests on ([Singh10] §II,
/// Mitchell 1990). An empty interval has lo > hi; operations on an empty interval give an empty
/// one (the function is undefined there, so there is no surface); a result that could be NaN is
/// widened to the whole line.
#include <algorithm>
#include <cmath>
#include <limits>

namespace quadrix::implicit {

struct Interval {
  double lo = 0, hi = 0;

  static Interval point(double v) { return {v, v}; }
  static Interval empty() { return {std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()}; }
  static Interval entire() { return {-std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()}; }
  bool is_empty() const { return !(lo <= hi); }
  bool contains(double v) const { return lo <= v && v <= hi; }
  double width() const { return hi - lo; }
  double mid() const { return 0.5 * (lo + hi); }
  double mag() const { return std::max(std::abs(lo), std::abs(hi)); }  ///< max |x|
  double mig() const { return contains(0.0) ? 0.0 : std::min(std::abs(lo), std::abs(hi)); }  ///< min |x|
};

/// Smallest interval holding both.
inline Interval hull(const Interval& a, const Interval& b) {
  if (a.is_empty()) return b;
  if (b.is_empty()) return a;
  return {std::min(a.lo, b.lo), std::max(a.hi, b.hi)};
}
inline Interval intersect(const Interval& a, const Interval& b) { return {std::max(a.lo, b.lo), std::min(a.hi, b.hi)}; }

/// Rounds outward by one ulp (and turns NaN bounds into infinite ones).
inline Interval widen(double lo, double hi) {
  constexpr double inf = std::numeric_limits<double>::infinity();
  if (std::isnan(lo)) lo = -inf;
  if (std::isnan(hi)) hi = inf;
  return {std::nextafter(lo, -inf), std::nextafter(hi, inf)};
}

Interval operator+(const Interval& a, const Interval& b);
Interval operator-(const Interval& a, const Interval& b);
Interval operator-(const Interval& a);
Interval operator*(const Interval& a, const Interval& b);
/// Whole line when b holds 0 (except 0/0-free cases of an empty a).
Interval operator/(const Interval& a, const Interval& b);

/// a^n for an integer n (even powers are ≥ 0; negative n through 1/a^|n|).
Interval pow_int(const Interval& a, int n);
/// a^b for a real b, on a ≥ 0 (the part of a below 0 is outside the domain).
Interval pow_real(const Interval& a, double b);
Interval sqrt(const Interval& a);
Interval exp(const Interval& a);
Interval log(const Interval& a);
Interval sin(const Interval& a);
Interval cos(const Interval& a);
Interval tan(const Interval& a);
Interval asin(const Interval& a);
Interval acos(const Interval& a);
Interval atan(const Interval& a);
Interval sinh(const Interval& a);
Interval cosh(const Interval& a);
Interval acosh(const Interval& a);
Interval abs(const Interval& a);
Interval min(const Interval& a, const Interval& b);
Interval max(const Interval& a, const Interval& b);
/// Chebyshev polynomial of the first kind T_n, n ≥ 0: its exact range over a, outward rounded.
Interval chebyshev(int n, const Interval& a);
/// T_n′ = n·U_{n−1}: an enclosure over a.
Interval chebyshev_derivative(int n, const Interval& a);

}  // namespace quadrix::implicit
