#include <gtest/gtest.h>

#include <random>

#include "core/error.h"
#include "core/quadric.h"

using namespace quadrix;
using Eigen::Vector3d;

namespace {
Quadric random_quadric(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-1, 1);
  QuadricCoefficients k;
  for (auto& v : k) v = u(rng);
  return Quadric::from_coefficients(k);
}
Vector3d random_point(std::mt19937_64& rng, double s = 1.0) {
  std::uniform_real_distribution<double> u(-s, s);
  return {u(rng), u(rng), u(rng)};
}
double rel(double a, double b, double scale) { return std::abs(a - b) / std::max(1.0, scale); }
}  // namespace

TEST(Quadric, CoefficientsRoundTripAndMonomials) {
  const QuadricCoefficients k{1, 2, 3, 4, 5, 6, 7, 8, 9, 10};
  const Quadric q = Quadric::from_coefficients(k);
  EXPECT_EQ(q.coefficients(), k);
  const Vector3d x(0.3, -1.2, 2.5);
  const double expected = 1 * x.x() * x.x() + 2 * x.y() * x.y() + 3 * x.z() * x.z() + 4 * x.x() * x.y() +
                          5 * x.y() * x.z() + 6 * x.z() * x.x() + 7 * x.x() + 8 * x.y() + 9 * x.z() + 10;
  EXPECT_NEAR(q.eval(x), expected, 1e-12);
  Eigen::Vector4d h;
  h << x, 1.0;
  EXPECT_NEAR(h.dot(q.matrix() * h), expected, 1e-12);
  const Quadric back = Quadric::from_matrix(q.matrix());
  EXPECT_EQ(back.coefficients(), k);
}

TEST(Quadric, GradientMatchesFiniteDifferences) {
  std::mt19937_64 rng(7);
  for (int i = 0; i < 100; ++i) {
    const Quadric q = random_quadric(rng);
    const Vector3d x = random_point(rng, 2);
    const Vector3d g = q.gradient(x);
    for (int a = 0; a < 3; ++a) {
      const double h = 1e-6;
      Vector3d e = Vector3d::Zero();
      e[a] = h;
      EXPECT_NEAR(g[a], (q.eval(x + e) - q.eval(x - e)) / (2 * h), 1e-7);
    }
  }
}

TEST(Quadric, AffineTransformInvariance) {
  std::mt19937_64 rng(11);
  for (int i = 0; i < 1000; ++i) {
    const Quadric q = random_quadric(rng);
    Eigen::Affine3d M = Eigen::Affine3d::Identity();
    M.linear() = Eigen::Matrix3d::Random() + 2.0 * Eigen::Matrix3d::Identity();
    M.translation() = random_point(rng, 10);
    const Quadric qm = q.transformed(M);
    for (int j = 0; j < 5; ++j) {
      const Vector3d x = random_point(rng, 3);
      const double f = q.eval(x);
      EXPECT_LE(rel(qm.eval(M * x), f, std::abs(f) + q.max_abs_coefficient() * (1 + x.squaredNorm())), 1e-12);
    }
  }
}

TEST(Quadric, SingularTransformThrows) {
  Eigen::Affine3d M = Eigen::Affine3d::Identity();
  M.linear().col(2).setZero();
  EXPECT_THROW(Quadric::sphere(Vector3d::Zero(), 1).transformed(M), InvalidInput);
}

TEST(Quadric, TranslateToEyeIsStoll06Eq9) {
  std::mt19937_64 rng(3);
  for (int i = 0; i < 1000; ++i) {
    const Quadric q = random_quadric(rng);
    const Vector3d e = random_point(rng, 100);
    const Quadric qe = q.translated_to_origin(e);
    // Eq. 9 structure: A′ = A, b′ = b + Ae, c′ = f(e).
    EXPECT_EQ(qe.A, q.A);
    EXPECT_LE((qe.b - (q.b + q.A * e)).norm(), 1e-12 * (1 + e.norm()));
    EXPECT_LE(rel(qe.c, q.eval(e), e.squaredNorm()), 1e-12);
    // Same surface: f′(y) = f(y + e), which is also transformed() by a translation.
    Eigen::Affine3d T = Eigen::Affine3d::Identity();
    T.translation() = -e;
    const Quadric qt = q.transformed(T);
    for (int j = 0; j < 3; ++j) {
      const Vector3d y = random_point(rng, 2) - e;
      const double scale = q.max_abs_coefficient() * (1 + (y + e).squaredNorm() + y.squaredNorm());
      EXPECT_LE(rel(qe.eval(y), q.eval(y + e), scale), 1e-12);
      EXPECT_LE(rel(qt.eval(y), qe.eval(y), scale), 1e-12);
    }
  }
}

TEST(Quadric, LocalFrameRoundTrip) {
  std::mt19937_64 rng(5);
  for (int i = 0; i < 500; ++i) {
    const Quadric q = random_quadric(rng);
    const Vector3d o = random_point(rng, 5);
    const double s = std::exp(std::uniform_real_distribution<double>(-5, 5)(rng));
    const Quadric local = q.to_local(o, s);
    const Vector3d u = random_point(rng, 1);
    EXPECT_LE(rel(local.eval(u), q.eval(o + s * u), q.max_abs_coefficient() * (1 + (o + s * u).squaredNorm())), 1e-11);
    const Quadric back = local.from_local(o, s);
    const Vector3d x = random_point(rng, 3);
    EXPECT_LE(rel(back.eval(x), q.eval(x), q.max_abs_coefficient() * (1 + x.squaredNorm() + o.squaredNorm())), 1e-9);
  }
}

TEST(Quadric, NormalisationKeepsZeroSetAndSign) {
  std::mt19937_64 rng(9);
  for (int i = 0; i < 200; ++i) {
    const Quadric q = random_quadric(rng) * 1e7;
    const Quadric n = q.normalized();
    EXPECT_DOUBLE_EQ(n.max_abs_coefficient(), 1.0);
    const Vector3d x = random_point(rng, 2);
    EXPECT_EQ(std::signbit(q.eval(x)), std::signbit(n.eval(x)));
    EXPECT_NEAR(q.taubin_distance(x), n.taubin_distance(x), 1e-9 * (1 + q.taubin_distance(x)));
  }
}
