#include "fit/local_fit.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Cholesky>

namespace quadrix {
namespace {

// Monomials in the order of QuadricCoefficients: xx yy zz xy yz zx x y z 1.
using Vec10 = Eigen::Matrix<double, 10, 1>;

inline void basis(const Eigen::Vector3d& u, Vec10& phi, Vec10& gx, Vec10& gy, Vec10& gz) {
  const double x = u.x(), y = u.y(), z = u.z();
  phi << x * x, y * y, z * z, x * y, y * z, z * x, x, y, z, 1.0;
  gx << 2 * x, 0, 0, y, 0, z, 1, 0, 0, 0;
  gy << 0, 2 * y, 0, x, z, 0, 0, 1, 0, 0;
  gz << 0, 0, 2 * z, 0, y, x, 0, 0, 1, 0;
}

}  // namespace

std::optional<Quadric> fit_general_quadric(const LocalSample& s, double mu) {
  const std::size_t m = s.u.size();
  if (m < 3) return std::nullopt;
  // Stacked rows √w·φ (target 0) and √(wμ)·∂φ (target √(wμ)·n), normal equations XᵀX k = Xᵀy.
  Eigen::Matrix<double, Eigen::Dynamic, 10> X(4 * m, 10);
  Eigen::VectorXd y = Eigen::VectorXd::Zero(4 * m);
  Vec10 phi, gx, gy, gz;
  for (std::size_t i = 0; i < m; ++i) {
    basis(s.u[i], phi, gx, gy, gz);
    const double sw = std::sqrt(s.w[i]), sg = std::sqrt(s.w[i] * mu);
    X.row(4 * i) = sw * phi.transpose();
    X.row(4 * i + 1) = sg * gx.transpose();
    X.row(4 * i + 2) = sg * gy.transpose();
    X.row(4 * i + 3) = sg * gz.transpose();
    y.segment<3>(4 * i + 1) = sg * s.n[i];
  }
  Eigen::Matrix<double, 10, 10> M = Eigen::Matrix<double, 10, 10>::Zero();
  M.selfadjointView<Eigen::Lower>().rankUpdate(X.transpose());
  M = M.selfadjointView<Eigen::Lower>();
  const double ridge = 1e-9 * M.diagonal().maxCoeff();
  if (!(ridge > 0)) return std::nullopt;
  M.diagonal().array() += ridge;
  Eigen::LDLT<Eigen::Matrix<double, 10, 10>> ldlt(M);
  if (ldlt.info() != Eigen::Success) return std::nullopt;
  Vec10 k = ldlt.solve(X.transpose() * y);
  if (!k.allFinite()) return std::nullopt;
  // A unit-length gradient target biases the zero set of any quadric whose ‖∇g‖ varies
  // (an ellipsoid). Re-target the gradients to ‖∇g(uᵢ)‖·nᵢ with the previous solution: the exact
  // quadric of exact data is then a fixed point. Only the right-hand side changes.
  for (int iteration = 0; iteration < 2; ++iteration) {
    for (std::size_t i = 0; i < m; ++i) {
      basis(s.u[i], phi, gx, gy, gz);
      const double len = Eigen::Vector3d(gx.dot(k), gy.dot(k), gz.dot(k)).norm();
      const double sg = std::sqrt(s.w[i] * mu);
      y.segment<3>(4 * i + 1) = sg * std::clamp(len, 0.2, 5.0) * s.n[i];
    }
    const Vec10 next = ldlt.solve(X.transpose() * y);
    if (!next.allFinite()) break;
    k = next;
  }
  QuadricCoefficients c;
  for (int i = 0; i < 10; ++i) c[i] = k[i];
  return Quadric::from_coefficients(c);
}

std::optional<Quadric> fit_height_quadric(const LocalSample& s, double mu) {
  const std::size_t m = s.u.size();
  if (m < 2) return std::nullopt;
  Eigen::Vector3d nbar = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < m; ++i) nbar += s.w[i] * s.n[i];
  if (!(nbar.norm() > 0)) return std::nullopt;
  nbar.normalize();
  // Tangent frame (t1, t2, n̄).
  Eigen::Vector3d t1 = std::abs(nbar.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  t1 = (t1 - t1.dot(nbar) * nbar).normalized();
  const Eigen::Vector3d t2 = nbar.cross(t1);
  // h(ξ, η) = a ξ² + b ξη + c η² + d ξ + e η + f.
  using Vec6 = Eigen::Matrix<double, 6, 1>;
  Eigen::Matrix<double, 6, 6> M = Eigen::Matrix<double, 6, 6>::Zero();
  Vec6 rhs = Vec6::Zero();
  for (std::size_t i = 0; i < m; ++i) {
    const double xi = t1.dot(s.u[i]), eta = t2.dot(s.u[i]), zeta = nbar.dot(s.u[i]);
    Vec6 row;
    row << xi * xi, xi * eta, eta * eta, xi, eta, 1.0;
    M += s.w[i] * row * row.transpose();
    rhs += s.w[i] * zeta * row;
    const double nz = nbar.dot(s.n[i]);
    if (nz > 0.3) {  // slopes h_ξ = −n_ξ/n_ζ, h_η = −n_η/n_ζ
      Vec6 rx, ry;
      rx << 2 * xi, eta, 0, 1, 0, 0;
      ry << 0, xi, 2 * eta, 0, 1, 0;
      const double wm = s.w[i] * mu;
      M += wm * (rx * rx.transpose() + ry * ry.transpose());
      rhs += wm * (-t1.dot(s.n[i]) / nz * rx - t2.dot(s.n[i]) / nz * ry);
    }
  }
  const double ridge = 1e-9 * M.diagonal().maxCoeff();
  if (!(ridge > 0)) return std::nullopt;
  M.diagonal().array() += ridge;
  Eigen::LDLT<Eigen::Matrix<double, 6, 6>> ldlt(M);
  if (ldlt.info() != Eigen::Success) return std::nullopt;
  const Vec6 h = ldlt.solve(rhs);
  if (!h.allFinite()) return std::nullopt;
  // g(u) = n̄ᵀu − h(t1ᵀu, t2ᵀu): A = −(a t1t1ᵀ + ½b(t1t2ᵀ + t2t1ᵀ) + c t2t2ᵀ), 2b = n̄ − d t1 − e t2, c = −f.
  Quadric g;
  g.A = -(h[0] * t1 * t1.transpose() + 0.5 * h[1] * (t1 * t2.transpose() + t2 * t1.transpose()) +
          h[2] * t2 * t2.transpose());
  g.b = 0.5 * (nbar - h[3] * t1 - h[4] * t2);
  g.c = -h[5];
  return g;
}

std::optional<double> first_front_hit(const Quadric& g, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                                      double tmin, double tmax) {
  const Eigen::Vector3d Ad = g.A * d;
  const double alpha = d.dot(Ad);
  const double beta = Ad.dot(o) + g.b.dot(d);
  const double gamma = g.eval(o);
  double t[2];
  int count = 0;
  if (alpha == 0.0) {
    if (beta == 0.0) return std::nullopt;
    t[count++] = -gamma / (2.0 * beta);
  } else {
    const double disc = beta * beta - alpha * gamma;
    if (disc < 0.0) return std::nullopt;
    const double q = -(beta + std::copysign(std::sqrt(disc), beta));
    if (q == 0.0) {
      t[count++] = 0.0;  // β = γ = 0: double root at the origin
    } else {
      t[0] = q / alpha;
      t[1] = gamma / q;
      if (t[0] > t[1]) std::swap(t[0], t[1]);
      count = 2;
    }
  }
  for (int i = 0; i < count; ++i) {
    if (!(t[i] > tmin && t[i] < tmax)) continue;
    if (alpha * t[i] + beta >= 0.0) continue;  // back-facing ([Stoll06] eq. 14)
    if ((o + t[i] * d).squaredNorm() > 1.0) continue;
    return t[i];
  }
  return std::nullopt;
}

LocalError local_error(const Quadric& g, std::span<const Eigen::Vector3d> u, std::span<const Eigen::Vector3d> n,
                       double probe, double bound, double rim) {
  LocalError e;
  const double inf = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < u.size(); ++i) {
    const double tau = g.taubin_distance(u[i]);
    e.max_taubin = std::max(e.max_taubin, tau);
    e.sum_sq_taubin += tau * tau;
    double err = 0;
    if (const auto t = first_front_hit(g, u[i] + probe * n[i], -n[i], 0.0, inf))
      err = std::abs(*t - probe);
    else if (u[i].squaredNorm() <= rim * rim)
      err = inf;
    e.max_probe = std::max(e.max_probe, err);
    if (!(tau <= bound && err <= bound)) {
      e.within = false;
      return e;
    }
  }
  return e;
}

}  // namespace quadrix
