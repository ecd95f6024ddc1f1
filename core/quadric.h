#pragma once
/// Quadric surfaces f(x) = xᵀAx + 2bᵀx + c = 0 in double precision ([Stoll06] eq. 2–4).
/// Exterior is f > 0; the outward normal is ∇f = 2(Ax + b) ([Stoll06] eq. 11).
#include <array>
#include <cmath>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace quadrix {

/// The 10 monomial coefficients in the order xx yy zz xy yz zx x y z 1
/// (the order of Kanai's .slim2t files and of the .qxm `k_*` properties).
using QuadricCoefficients = std::array<double, 10>;

struct Quadric {
  Eigen::Matrix3d A = Eigen::Matrix3d::Zero();  ///< symmetric quadratic part
  Eigen::Vector3d b = Eigen::Vector3d::Zero();  ///< half the linear part
  double c = 0.0;                               ///< constant

  /// From monomial coefficients k (order xx yy zz xy yz zx x y z 1).
  static Quadric from_coefficients(const QuadricCoefficients& k);
  /// From the symmetric homogeneous 4×4 matrix Q̃ = [A b; bᵀ c] ([Stoll06] eq. 4).
  static Quadric from_matrix(const Eigen::Matrix4d& Q);
  /// Sphere ‖x − centre‖² − r² (negative inside).
  static Quadric sphere(const Eigen::Vector3d& centre, double r);
  /// Plane nᵀx + d (degree one; A = 0).
  static Quadric plane(const Eigen::Vector3d& n, double d);

  QuadricCoefficients coefficients() const;
  Eigen::Matrix4d matrix() const;

  double eval(const Eigen::Vector3d& x) const { return x.dot(A * x + 2.0 * b) + c; }
  Eigen::Vector3d gradient(const Eigen::Vector3d& x) const { return 2.0 * (A * x + b); }
  /// Taubin's first-order distance |f| / ‖∇f‖ (infinity where ∇f = 0 and f ≠ 0).
  double taubin_distance(const Eigen::Vector3d& x) const;

  /// The quadric of the image set M(S): f′(y) = f(M⁻¹y), i.e. Q̃′ = M̃⁻ᵀ Q̃ M̃⁻¹.
  /// \throws InvalidInput when M is singular.
  Quadric transformed(const Eigen::Affine3d& M) const;
  /// f′(y) = f(y + e): the eye (or any origin) e moved to 0 ([Stoll06] eq. 9).
  Quadric translated_to_origin(const Eigen::Vector3d& e) const;
  /// f′(u) = f(o + s·u): local coordinates centred on o and scaled by s (SLIM patches).
  Quadric to_local(const Eigen::Vector3d& o, double s) const;
  /// Inverse of to_local: world-space quadric from one local to (o, s).
  Quadric from_local(const Eigen::Vector3d& o, double s) const;
  /// Scaled by a positive factor so the largest |coefficient| of Q̃ is 1 (same zero set, same sign).
  Quadric normalized() const;
  /// Largest |entry| of Q̃.
  double max_abs_coefficient() const;
  Quadric operator*(double s) const { return {A * s, b * s, c * s}; }
  bool is_finite() const { return A.allFinite() && b.allFinite() && std::isfinite(c); }
};

}  // namespace quadrix
