#include "core/quadric.h"

#include <Eigen/LU>
#include <limits>

#include "core/error.h"

namespace quadrix {

Quadric Quadric::from_coefficients(const QuadricCoefficients& k) {
  Quadric q;
  q.A << k[0], 0.5 * k[3], 0.5 * k[5],  //
      0.5 * k[3], k[1], 0.5 * k[4],     //
      0.5 * k[5], 0.5 * k[4], k[2];
  q.b = 0.5 * Eigen::Vector3d(k[6], k[7], k[8]);
  q.c = k[9];
  return q;
}

Quadric Quadric::from_matrix(const Eigen::Matrix4d& Q) {
  const Eigen::Matrix4d S = 0.5 * (Q + Q.transpose());
  Quadric q;
  q.A = S.topLeftCorner<3, 3>();
  q.b = S.topRightCorner<3, 1>();
  q.c = S(3, 3);
  return q;
}

Quadric Quadric::sphere(const Eigen::Vector3d& centre, double r) {
  Quadric q;
  q.A.setIdentity();
  q.b = -centre;
  q.c = centre.squaredNorm() - r * r;
  return q;
}

Quadric Quadric::plane(const Eigen::Vector3d& n, double d) {
  Quadric q;
  q.b = 0.5 * n;
  q.c = d;
  return q;
}

QuadricCoefficients Quadric::coefficients() const {
  return {A(0, 0),     A(1, 1),     A(2, 2),     2.0 * A(0, 1), 2.0 * A(1, 2),
          2.0 * A(2, 0), 2.0 * b.x(), 2.0 * b.y(), 2.0 * b.z(),   c};
}

Eigen::Matrix4d Quadric::matrix() const {
  Eigen::Matrix4d Q;
  Q.topLeftCorner<3, 3>() = A;
  Q.topRightCorner<3, 1>() = b;
  Q.bottomLeftCorner<1, 3>() = b.transpose();
  Q(3, 3) = c;
  return Q;
}

double Quadric::taubin_distance(const Eigen::Vector3d& x) const {
  const double f = eval(x);
  const double g = gradient(x).norm();
  if (g == 0.0) return f == 0.0 ? 0.0 : std::numeric_limits<double>::infinity();
  return std::abs(f) / g;
}

Quadric Quadric::transformed(const Eigen::Affine3d& M) const {
  const Eigen::Matrix3d L = M.linear();
  Eigen::FullPivLU<Eigen::Matrix3d> lu(L);
  if (!lu.isInvertible()) throw InvalidInput("Quadric::transformed: the affine map is singular");
  // x = L⁻¹(y − t): A′ = L⁻ᵀAL⁻¹, b′ = L⁻ᵀ(b − A L⁻¹t), c′ = f(−L⁻¹t).
  const Eigen::Matrix3d Li = lu.inverse();
  const Eigen::Vector3d x0 = -Li * M.translation();
  Quadric q;
  q.A = Li.transpose() * A * Li;
  q.A = 0.5 * (q.A + q.A.transpose());
  q.b = Li.transpose() * (A * x0 + b);
  q.c = eval(x0);
  return q;
}

Quadric Quadric::translated_to_origin(const Eigen::Vector3d& e) const {
  // [Stoll06] eq. 9: A′ = A, b′ = b + Ae, c′ = c + eᵀ(Ae + 2b).
  return {A, b + A * e, c + e.dot(A * e + 2.0 * b)};
}

Quadric Quadric::to_local(const Eigen::Vector3d& o, double s) const {
  return {A * (s * s), (A * o + b) * s, eval(o)};
}

Quadric Quadric::from_local(const Eigen::Vector3d& o, double s) const {
  const double is = 1.0 / s;
  const Eigen::Vector3d Ao = A * o;
  return {A * (is * is), b * is - Ao * (is * is), o.dot(Ao) * (is * is) - 2.0 * b.dot(o) * is + c};
}

double Quadric::max_abs_coefficient() const {
  return std::max({A.cwiseAbs().maxCoeff(), b.cwiseAbs().maxCoeff(), std::abs(c)});
}

Quadric Quadric::normalized() const {
  const double m = max_abs_coefficient();
  if (!(m > 0.0) || !std::isfinite(m)) return *this;
  return *this * (1.0 / m);
}

}  // namespace quadrix
