#include "fit/local_fit.h"

#include <algorithm>
#include <array>
#include <cmath>

#include <Eigen/Cholesky>

#include "core/ray.h"

namespace quadrix {
namespace {

// Monomials in the order of QuadricCoefficients: xx yy zz xy yz zx x y z 1.
using Vec10 = Eigen::Matrix<double, 10, 1>;
constexpr int kExponents[10][3] = {{2, 0, 0}, {0, 2, 0}, {0, 0, 2}, {1, 1, 0}, {0, 1, 1},
                                   {1, 0, 1}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0, 0, 0}};
// Index of the moment xᵃyᵇzᶜ (a + b + c ≤ 4) in the accumulation below (−1: not used).
constexpr auto kMoment = [] {
  std::array<std::array<std::array<int, 5>, 5>, 5> idx{};
  int k = 0;
  for (int a = 0; a < 5; ++a)
    for (int b = 0; b < 5; ++b)
      for (int c = 0; c < 5; ++c) idx[a][b][c] = a + b + c <= 4 ? k++ : -1;
  return idx;
}();

}  // namespace

std::optional<Quadric> fit_general_quadric(const LocalSample& s, double mu) {
  const std::size_t m = s.u.size();
  if (m < 3) return std::nullopt;
  // Normal equations of the stacked rows √w·φ (target 0) and √(wμ)·∂φ (target √(wμ)·n):
  // M = Σ w·(φφᵀ + μ·Σ_axes ∂φ∂φᵀ). Every entry is a weighted moment Σ w·xⁱyʲzᵏ of degree ≤ 4,
  // so the points are summed once into the 35 moments (the hot loop of the fitter).
  double S[35] = {};  // Σ w·xᵃyᵇzᶜ, a + b + c ≤ 4, indexed by kMoment
  for (std::size_t i = 0; i < m; ++i) {
    const double x = s.u[i].x(), y = s.u[i].y(), z = s.u[i].z(), w = s.w[i];
    const double x2 = x * x, y2 = y * y, z2 = z * z, x3 = x2 * x, y3 = y2 * y, z3 = z2 * z;
    const double x4 = x2 * x2, y4 = y2 * y2, z4 = z2 * z2;
    const double t[35] = {
        1, z, z2, z3, z4, y, y * z, y * z2, y * z3, y2, y2 * z, y2 * z2, y3, y3 * z, y4, x,
        x * z, x * z2, x * z3, x * y, x * y * z, x * y * z2, x * y2, x * y2 * z, x * y3, x2,
        x2 * z, x2 * z2, x2 * y, x2 * y * z, x2 * y2, x3, x3 * z, x3 * y, x4
    };
    for (int k = 0; k < 35; ++k) S[k] += w * t[k];
  }
  Eigen::Matrix<double, 10, 10> M;
  for (int a = 0; a < 10; ++a)
    for (int b = 0; b <= a; ++b) {
      const auto &ea = kExponents[a], &eb = kExponents[b];
      double v = S[kMoment[ea[0] + eb[0]][ea[1] + eb[1]][ea[2] + eb[2]]];
      for (int k = 0; k < 3; ++k)  // ∂/∂x_k of xᵉ is e_k·x^(e − 1_k)
        if (ea[k] > 0 && eb[k] > 0) {
          int e[3] = {ea[0] + eb[0], ea[1] + eb[1], ea[2] + eb[2]};
          e[k] -= 2;
          v += mu * ea[k] * eb[k] * S[kMoment[e[0]][e[1]][e[2]]];
        }
      M(a, b) = M(b, a) = v;
    }
  const double ridge = 1e-9 * M.diagonal().maxCoeff();
  if (!(ridge > 0)) return std::nullopt;
  M.diagonal().array() += ridge;
  Eigen::LDLT<Eigen::Matrix<double, 10, 10>> ldlt(M);
  if (ldlt.info() != Eigen::Success) return std::nullopt;
  // Right-hand side Σ wμ·len·J·n with the gradient targets scaled by len per point (1 at first).
  auto rhs = [&](const Vec10* k) {
    double r[10] = {};
    for (std::size_t i = 0; i < m; ++i) {
      const double x = s.u[i].x(), y = s.u[i].y(), z = s.u[i].z();
      double len = 1.0;
      if (k) {
        const Vec10& c = *k;  // ∇g = (2c0x + c3y + c5z + c6, 2c1y + c3x + c4z + c7, 2c2z + c4y + c5x + c8)
        const double gx = 2 * c[0] * x + c[3] * y + c[5] * z + c[6];
        const double gy = 2 * c[1] * y + c[3] * x + c[4] * z + c[7];
        const double gz = 2 * c[2] * z + c[4] * y + c[5] * x + c[8];
        len = std::clamp(std::sqrt(gx * gx + gy * gy + gz * gz), 0.2, 5.0);
      }
      const double f = s.w[i] * mu * len;
      const double nx = f * s.n[i].x(), ny = f * s.n[i].y(), nz = f * s.n[i].z();
      r[0] += 2 * x * nx, r[1] += 2 * y * ny, r[2] += 2 * z * nz;
      r[3] += y * nx + x * ny, r[4] += z * ny + y * nz, r[5] += z * nx + x * nz;
      r[6] += nx, r[7] += ny, r[8] += nz;
    }
    return Vec10(Eigen::Map<const Vec10>(r));
  };
  Vec10 k = ldlt.solve(rhs(nullptr));
  if (!k.allFinite()) return std::nullopt;
  // A unit-length gradient target biases the zero set of any quadric whose ‖∇g‖ varies
  // (an ellipsoid). Re-target the gradients to ‖∇g(uᵢ)‖·nᵢ with the previous solution: the exact
  // quadric of exact data is then a fixed point. Only the right-hand side changes.
  for (int iteration = 0; iteration < 2; ++iteration) {
    const Vec10 next = ldlt.solve(rhs(&k));
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

LocalError local_error(const Quadric& g, std::span<const Eigen::Vector3d> u, std::span<const Eigen::Vector3d> n,
                       double probe, double bound, double rim) {
  LocalError e;
  const double inf = std::numeric_limits<double>::infinity();
  const auto in_ball = [](const Eigen::Vector3d& x) { return x.squaredNorm() <= 1.0; };
  for (std::size_t i = 0; i < u.size(); ++i) {
    const double tau = g.taubin_distance(u[i]);
    e.max_taubin = std::max(e.max_taubin, tau);
    e.sum_sq_taubin += tau * tau;
    double err = 0;
    Hit hit;
    if (intersect_quadric(g, Ray{u[i] + probe * n[i], -n[i]}, 0.0, inf, /*cull_backfaces=*/true, in_ball, hit))
      err = std::abs(hit.t - probe);
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
