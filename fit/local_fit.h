#pragma once
/// One SLIM patch's local quadric: weighted least-squares fits in coordinates u = (x − c)/R and
/// the patch's error over the points in its ball (the building block of fit/slim_fit.h).
#include <optional>
#include <span>

#include <Eigen/Core>

#include "core/quadric.h"

namespace quadrix {

/// Points of one ball in local coordinates: u (‖u‖ ≤ 1), unit normals n, fit weights w ≥ 0.
struct LocalSample {
  std::span<const Eigen::Vector3d> u;
  std::span<const Eigen::Vector3d> n;
  std::span<const double> w;
};

/// General quadric g(u) (10 coefficients) minimising Σ wᵢ·[g(uᵢ)² + μ‖∇g(uᵢ) − nᵢ‖²]
/// (normal equations in double with a tiny ridge so flat data stay well posed). ∇g follows the
/// given outward normals, so the exterior has g > 0. Nothing when the system is singular.
std::optional<Quadric> fit_general_quadric(const LocalSample& s, double mu);

/// Height-function quadric over the tangent plane of the weighted mean normal n̄:
/// g(u) = ζ − h(ξ, η), h a bivariate quadratic fitted to positions and (with weight μ) to the
/// slopes implied by the normals. For flat or sparse neighbourhoods; works from 2 points.
std::optional<Quadric> fit_height_quadric(const LocalSample& s, double mu);

/// Error of a local quadric over the points of its ball, in local units (world / R).
struct LocalError {
  double max_taubin = 0;  ///< max |g|/‖∇g‖
  double max_probe = 0;   ///< max |t − h| of the first front-facing in-ball hit along −n from u + h·n
  double sum_sq_taubin = 0;
  bool within = true;     ///< both maxima ≤ bound (evaluation stops at the first point past it)
};

/// Checks g against every point: Taubin distance and the probe ray the blended-surface
/// evaluation uses (fit/evaluate.h), solved by core/ray.h. probe: h in local units; bound: E in local units. A point
/// whose probe finds no in-ball hit fails unless it lies in the outer rim (‖u‖ > rim).
LocalError local_error(const Quadric& g, std::span<const Eigen::Vector3d> u, std::span<const Eigen::Vector3d> n,
                       double probe, double bound, double rim = 0.97);

}  // namespace quadrix
