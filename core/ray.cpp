#include "core/ray.h"

#include <cmath>
#include <limits>

namespace quadrix {

RayQuadratic ray_quadratic(const Quadric& q, const Ray& ray) {
  // [Stoll06] eq. 6: α = vᵀAv, β = (eᵀA + bᵀ)v, γ = (eᵀA + 2bᵀ)e + c.
  const Eigen::Vector3d Ae = q.A * ray.origin;
  return {ray.dir.dot(q.A * ray.dir), (Ae + q.b).dot(ray.dir), ray.origin.dot(Ae + 2.0 * q.b) + q.c};
}

Roots solve_ray_quadratic(const RayQuadratic& e) {
  const double a = e.alpha, b = e.beta, c = e.gamma;
  Roots r;
  if (a == 0.0) {  // degree one: 2βλ + γ = 0
    if (b != 0.0) {
      const double t = -c / (2.0 * b);
      if (std::isfinite(t)) r.t[r.count++] = t;
    }
    return r;
  }
  // Discriminant β² − αγ without catastrophic loss (Kahan's fma trick).
  const double w = a * c;
  const double err = std::fma(-a, c, w);
  double disc = std::fma(b, b, -w) + err;
  // A discriminant negative only by rounding (a tangent ray, or the two nearly coincident sheets
  // of a near-double-plane) is a double root, not a miss.
  if (disc < 0.0 && disc > -8.0 * std::numeric_limits<double>::epsilon() * (b * b + std::abs(w))) disc = 0.0;
  if (!(disc >= 0.0)) return r;
  const double sq = std::sqrt(disc);
  const double qf = -(b + std::copysign(sq, b));  // q-form: no cancellation in β ± √D
  if (qf == 0.0) {                               // β = 0 and αγ = 0: the double root 0
    r.t[r.count++] = 0.0;
    return r;
  }
  double t1 = qf / a;  // → ±∞ as α → 0 (the root leaving for infinity)
  double t2 = c / qf;  // → −γ/(2β) as α → 0: the linear case comes out of the same formula
  if (t1 > t2) std::swap(t1, t2);
  if (std::isfinite(t1)) r.t[r.count++] = t1;
  if (std::isfinite(t2) && (r.count == 0 || t2 != r.t[0])) r.t[r.count++] = t2;
  return r;
}

}  // namespace quadrix
