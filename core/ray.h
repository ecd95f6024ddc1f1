#pragma once
/// Robust ray–quadric intersection in double ([Stoll06] §4.2–4.4, DESIGN §5).
#include <array>
#include <limits>

#include <Eigen/Core>

#include "core/quadric.h"

namespace quadrix {

/// x(λ) = origin + λ·dir. dir need not be unit length; λ is in units of ‖dir‖.
struct Ray {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  Eigen::Vector3d dir = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d at(double t) const { return origin + t * dir; }
};

/// αλ² + 2βλ + γ = 0 along a ray ([Stoll06] eq. 6; eq. 10 when the origin is the eye).
struct RayQuadratic {
  double alpha = 0, beta = 0, gamma = 0;
};

RayQuadratic ray_quadratic(const Quadric& q, const Ray& ray);

/// The ray expressed relative to `centre` and restarted at its closest approach to it:
/// local.origin = ray.at(t0) − centre, local.dir = ray.dir; returns t0. A root λ of a quadric
/// written relative to `centre` is then t0 + λ along the original ray. Keeps γ = f(origin)
/// small when the eye is far away, so no digits cancel (DESIGN §5).
inline double rebase_ray(const Ray& ray, const Eigen::Vector3d& centre, Ray& local) {
  const double t0 = (centre - ray.origin).dot(ray.dir) / ray.dir.squaredNorm();
  local.origin = ray.at(t0) - centre;
  local.dir = ray.dir;
  return t0;
}

/// Real roots of αλ² + 2βλ + γ = 0, ascending. Stable q-form: q = −(β + sign(β)√(β²−αγ)),
/// λ₁ = q/α, λ₂ = γ/q; the linear case (|α| negligible against β and γ) and the tangent case
/// (one double root) handled explicitly. count is 0, 1 or 2.
struct Roots {
  int count = 0;
  std::array<double, 2> t{};
};
Roots solve_ray_quadratic(const RayQuadratic& e);

/// A point where a ray meets a surface.
struct Hit {
  double t = std::numeric_limits<double>::infinity();
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
  Eigen::Vector3d gradient = Eigen::Vector3d::Zero();  ///< ∇f at the hit (outward, unnormalised)
  bool front_facing = true;                            ///< dirᵀ∇f < 0 ([Stoll06] eq. 12–14)
};

/// The nearest root λ ∈ (tmin, tmax) whose point satisfies inside(point), visiting roots
/// nearest first ([Stoll06] eq. 15: check the near root, then the far one only if the near one is
/// clipped). With cull_backfaces only front-facing roots (αλ + β < 0) count ([Stoll06] eq. 14).
template <typename Inside>
bool intersect_quadric(const Quadric& q, const Ray& ray, double tmin, double tmax, bool cull_backfaces,
                       Inside&& inside, Hit& hit) {
  const RayQuadratic e = ray_quadratic(q, ray);
  const Roots roots = solve_ray_quadratic(e);
  for (int i = 0; i < roots.count; ++i) {
    const double t = roots.t[i];
    if (!(t > tmin && t < tmax)) continue;
    const double facing = e.alpha * t + e.beta;  // ½ dirᵀ∇f at x(t)
    if (cull_backfaces && facing >= 0.0) continue;
    const Eigen::Vector3d p = ray.at(t);
    if (!inside(p)) continue;
    hit.t = t;
    hit.point = p;
    hit.gradient = q.gradient(p);
    hit.front_facing = facing < 0.0;
    return true;
  }
  return false;
}

}  // namespace quadrix
