#include <gtest/gtest.h>

#include <random>

#include "core/bounds.h"
#include "core/ray.h"

using namespace quadrix;
using Eigen::Vector3d;

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();
const auto kAnywhere = [](const Vector3d&) { return true; };

Vector3d random_unit(std::mt19937_64& rng) {
  std::normal_distribution<double> n;
  return Vector3d(n(rng), n(rng), n(rng)).normalized();
}

// Nearest positive root of a·t² + 2b·t + c in long double (the textbook form is fine here:
// the truth is computed in higher precision).
long double nearest_root(long double a, long double b, long double c) {
  const long double d = b * b - a * c;
  if (d < 0) return -1;
  const long double s = std::sqrt(d);
  long double t1 = (-b - s) / a, t2 = (-b + s) / a;
  if (t1 > t2) std::swap(t1, t2);
  return t1 > 0 ? t1 : t2;
}
}  // namespace

TEST(Ray, SphereHitsMatchClosedForm) {
  std::mt19937_64 rng(1);
  for (int i = 0; i < 20000; ++i) {
    const Vector3d c = 10 * random_unit(rng);
    const double r = std::exp(std::uniform_real_distribution<double>(-3, 3)(rng));
    const Vector3d o = c + r * (1.5 + 20 * std::uniform_real_distribution<double>(0, 1)(rng)) * random_unit(rng);
    // Aim at a random point inside the sphere so the ray hits.
    const Vector3d target = c + 0.99 * r * std::cbrt(std::uniform_real_distribution<double>(0, 1)(rng)) * random_unit(rng);
    const Vector3d d = (target - o).normalized();
    // Quadric local to its centre, ray rebased (the library's convention, DESIGN §5).
    Ray local;
    const double t0 = rebase_ray({o, d}, c, local);
    Hit hit;
    ASSERT_TRUE(intersect_quadric(Quadric::sphere(Vector3d::Zero(), r), local, -t0, kInf, true, kAnywhere, hit));
    hit.t += t0;
    const long double b = d.cast<long double>().dot((o - c).cast<long double>());
    const long double cc = (o - c).cast<long double>().squaredNorm() - (long double)r * r;
    const long double t = -b - std::sqrt(b * b - cc);
    EXPECT_LE(std::abs(hit.t - t) / t, 1e-12) << "sphere " << i;
    EXPECT_TRUE(hit.front_facing);
    EXPECT_LT(hit.gradient.dot(d), 0.0);
  }
}

TEST(Ray, EllipsoidCylinderHyperboloidMatchClosedForm) {
  std::mt19937_64 rng(2);
  int hits = 0;
  for (int i = 0; i < 20000; ++i) {
    const int kind = i % 3;
    const Vector3d o = 3.0 * random_unit(rng) * (1.5 + std::uniform_real_distribution<double>(0, 2)(rng));
    const Vector3d d = (0.3 * random_unit(rng) - o).normalized();
    Quadric q;
    const Vector3d s(1.3, 0.7, 0.5);
    if (kind == 0) {  // ellipsoid (x/1.3)² + (y/0.7)² + (z/0.5)² = 1
      q.A = s.cwiseInverse().cwiseAbs2().asDiagonal();
      q.c = -1;
    } else if (kind == 1) {  // cylinder x² + y² = 0.49
      q.A = Vector3d(1, 1, 0).asDiagonal();
      q.c = -0.49;
    } else {  // one-sheet hyperboloid x² + y² − z² = 0.25
      q.A = Vector3d(1, 1, -1).asDiagonal();
      q.c = -0.25;
    }
    // Closed form in long double from the diagonal A: α = Σ aᵢdᵢ², β = Σ aᵢoᵢdᵢ, γ = Σ aᵢoᵢ² + c.
    long double a = 0, b = 0, c = q.c;
    for (int k = 0; k < 3; ++k) {
      a += (long double)q.A(k, k) * d[k] * d[k];
      b += (long double)q.A(k, k) * o[k] * d[k];
      c += (long double)q.A(k, k) * o[k] * o[k];
    }
    Hit hit;
    const bool found = intersect_quadric(q, {o, d}, 0.0, kInf, false, kAnywhere, hit);
    const long double t = nearest_root(a, b, c);
    if (t <= 0) {
      EXPECT_FALSE(found && hit.t > 1e-9) << i;
      continue;
    }
    ASSERT_TRUE(found) << i;
    ++hits;
    EXPECT_LE(std::abs(hit.t - t) / t, 1e-12) << "kind " << kind << " case " << i;
  }
  EXPECT_GT(hits, 10000);
}

TEST(Ray, LinearCaseAlphaZero) {
  // x² + y² − z² = ¼ along its asymptotic direction: α = 0 exactly, one finite root.
  Quadric q;
  q.A = Vector3d(1, 1, -1).asDiagonal();
  q.c = -0.25;
  const Vector3d d = Vector3d(1, 0, 1).normalized();
  const Vector3d o(-3, 0.2, -2);
  const RayQuadratic e = ray_quadratic(q, {o, d});
  EXPECT_EQ(e.alpha, 0.0);
  const Roots r = solve_ray_quadratic(e);
  ASSERT_EQ(r.count, 1);
  EXPECT_NEAR(q.eval(o + r.t[0] * d), 0.0, 1e-12);
  // Nearly linear: α = 1e-20 relative; the finite root must come out of the q-form exactly
  // (the textbook (−β ± √D)/α loses every digit here).
  for (const double alpha : {1e-8, 1e-12, 1e-16, 1e-20, 1e-300}) {
    const RayQuadratic near{alpha, -1.0, 0.5};
    const Roots rr = solve_ray_quadratic(near);
    ASSERT_GE(rr.count, 1);
    const long double la = alpha;
    const double expected = static_cast<double>(0.5L / (1.0L + std::sqrt(1.0L - 0.5L * la)));
    EXPECT_NEAR(rr.t[0], expected, 1e-15) << alpha;
  }
}

TEST(Ray, TangentAndMissingRays) {
  const Quadric unit = Quadric::sphere(Vector3d::Zero(), 1.0);
  // Exactly tangent: a double root at t = 5, never NaN.
  const Roots r = solve_ray_quadratic(ray_quadratic(unit, {Vector3d(-5, 1, 0), Vector3d::UnitX()}));
  ASSERT_GE(r.count, 1);
  EXPECT_NEAR(r.t[0], 5.0, 1e-7);
  // A tangent root is neither front- nor back-facing; with culling it is dropped.
  Hit hit;
  EXPECT_FALSE(intersect_quadric(unit, {Vector3d(-5, 1, 0), Vector3d::UnitX()}, 0, kInf, true, kAnywhere, hit));
  // Missing.
  EXPECT_EQ(solve_ray_quadratic(ray_quadratic(unit, {Vector3d(-5, 1.001, 0), Vector3d::UnitX()})).count, 0);
  // Degenerate quadric (all zero): no roots, no NaN.
  EXPECT_EQ(solve_ray_quadratic({0, 0, 0}).count, 0);
  EXPECT_EQ(solve_ray_quadratic({0, 0, 1}).count, 0);
}

TEST(Ray, Eq15VisitsNearRootFirstAndFallsBackToFarRoot) {
  // Unit sphere clipped to z < 0.5 seen from +z: the near root is clipped, the far one is inside.
  const Quadric unit = Quadric::sphere(Vector3d::Zero(), 1.0);
  const Ray ray{Vector3d(0, 0, 5), Vector3d(0, 0, -1)};
  Hit hit;
  ASSERT_TRUE(intersect_quadric(unit, ray, 0, kInf, false, [](const Vector3d& p) { return p.z() < 0.5; }, hit));
  EXPECT_NEAR(hit.t, 6.0, 1e-12);
  EXPECT_FALSE(hit.front_facing);
  // With per-fragment culling only the front-facing root counts, so the clipped sphere vanishes.
  EXPECT_FALSE(intersect_quadric(unit, ray, 0, kInf, true, [](const Vector3d& p) { return p.z() < 0.5; }, hit));
  ASSERT_TRUE(intersect_quadric(unit, ray, 0, kInf, true, kAnywhere, hit));
  EXPECT_NEAR(hit.t, 4.0, 1e-12);
}

TEST(Ray, FarCameraKeepsRelativePrecisionWhenRebased) {
  // A unit sphere seen from 10⁴ to 10⁸ sizes away: with the ray rebased to its closest approach
  // the relative error of t stays at double level (without it, γ = ‖e‖² − 1 loses every digit).
  for (const double dist : {1e4, 1e6, 1e8}) {
    const Vector3d o(0.3, 0.2, dist);
    const Ray ray{o, (Vector3d(0.1, -0.2, 0) - o).normalized()};
    Ray local;
    const double t0 = rebase_ray(ray, Vector3d::Zero(), local);
    Hit hit;
    ASSERT_TRUE(intersect_quadric(Quadric::sphere(Vector3d::Zero(), 1.0), local, -t0, kInf, true, kAnywhere, hit));
    hit.t += t0;
    // Truth in long double, from the closest approach (b² − c would itself cancel at 10⁸).
    const Eigen::Matrix<long double, 3, 1> ol = o.cast<long double>(), dl = ray.dir.cast<long double>();
    const long double tc = -ol.dot(dl) / dl.squaredNorm();
    const long double t = tc - std::sqrt((1.0L - (ol + tc * dl).squaredNorm()) / dl.squaredNorm());
    EXPECT_LE(std::abs(hit.t - t) / t, 1e-12) << dist;
  }
}

TEST(Bounds, ClippedTetrahedraTileThePartInsideTheBox) {
  // Random tetrahedra against random boxes: the pieces of clip_tetrahedron_to_box contain a point
  // of the tetrahedron exactly when the box does, never twice, and their volumes add up.
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const auto vol = [](const std::array<Eigen::Vector3d, 4>& p) {
    return std::abs((p[1] - p[0]).cross(p[2] - p[0]).dot(p[3] - p[0])) / 6.0;
  };
  int partial = 0;
  for (int trial = 0; trial < 300; ++trial) {
    std::array<Eigen::Vector3d, 4> t;
    for (auto& c : t) c = Eigen::Vector3d(u(rng), u(rng), u(rng));
    if (is_degenerate_tetrahedron(t, 1e-3)) continue;
    const Eigen::Vector3d lo(u(rng) * 0.6 - 0.3, u(rng) * 0.6 - 0.3, u(rng) * 0.6 - 0.3);
    const Eigen::Vector3d hi = lo + Eigen::Vector3d(0.2 + 0.8 * std::abs(u(rng)), 0.2 + 0.8 * std::abs(u(rng)), 1.0);
    const auto pieces = clip_tetrahedron_to_box(t, lo, hi);
    std::vector<Tetrahedron> tets;
    double total = 0;
    for (const auto& p : pieces) {
      for (const auto& c : p) {
        EXPECT_TRUE((c.array() >= lo.array() - 1e-12).all() && (c.array() <= hi.array() + 1e-12).all());
        EXPECT_TRUE(Tetrahedron(t).contains(c, 1e-9));
      }
      total += vol(p);
      if (!is_degenerate_tetrahedron(p)) tets.emplace_back(p);
    }
    EXPECT_LE(total, vol(t) * (1 + 1e-9));
    partial += !pieces.empty() && total < vol(t) * (1 - 1e-6);
    const Tetrahedron whole(t);
    std::uniform_real_distribution<double> b(0.0, 1.0);
    for (int s = 0; s < 200; ++s) {
      // A random point of the tetrahedron (sorted uniforms give uniform barycentrics).
      std::array<double, 5> k{0, b(rng), b(rng), b(rng), 1};
      std::sort(k.begin() + 1, k.end() - 1);
      const Eigen::Vector3d x = (k[1] - k[0]) * t[0] + (k[2] - k[1]) * t[1] + (k[3] - k[2]) * t[2] + (k[4] - k[3]) * t[3];
      const bool in_box = (x.array() > lo.array() + 1e-9).all() && (x.array() < hi.array() - 1e-9).all();
      const bool near_box = (x.array() >= lo.array() - 1e-9).all() && (x.array() <= hi.array() + 1e-9).all();
      int inside = 0, strictly = 0;
      for (const auto& p : tets) {
        inside += p.contains(x, 1e-9);
        strictly += p.contains(x, -1e-9);
      }
      if (in_box) {
        EXPECT_GE(inside, 1) << "trial " << trial;
      }
      if (!near_box) {
        EXPECT_EQ(inside, 0) << "trial " << trial;
      }
      EXPECT_LE(strictly, 1) << "pieces overlap, trial " << trial;
    }
  }
  EXPECT_GT(partial, 100);  // most trials really cut the tetrahedron
}

TEST(Bounds, QuadricMayVanishIsConservativeAndRefinementTightens) {
  // Random tetrahedra and quadrics: wherever a sampled point shows both signs the test must say
  // "may vanish" at every depth, deeper never says yes where shallower said no, and on the unit
  // sphere the refined test drops tetrahedra the plain net keeps.
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0), b(0.0, 1.0);
  int refined_away = 0;
  for (int trial = 0; trial < 400; ++trial) {
    std::array<Vector3d, 4> t;
    for (auto& c : t) c = Vector3d(u(rng), u(rng), u(rng));
    if (is_degenerate_tetrahedron(t, 1e-3)) continue;
    Quadric q;
    const Eigen::Matrix3d M = Eigen::Matrix3d::NullaryExpr([&] { return u(rng); });
    q.A = trial % 2 ? Eigen::Matrix3d(M + M.transpose()) : Eigen::Matrix3d::Identity();
    q.b = trial % 2 ? Vector3d(u(rng), u(rng), u(rng)) : Vector3d::Zero();
    q.c = trial % 2 ? u(rng) : -(0.3 + b(rng));  // odd: general; even: spheres about the origin
    const Vector3d origin = 0.25 * (t[0] + t[1] + t[2] + t[3]);
    const Quadric local = q.translated_to_origin(origin);  // the same function of y = x − origin
    bool pos = false, neg = false;
    for (int s = 0; s < 300; ++s) {
      std::array<double, 5> k{0, b(rng), b(rng), b(rng), 1};
      std::sort(k.begin() + 1, k.end() - 1);
      const Vector3d x = (k[1] - k[0]) * t[0] + (k[2] - k[1]) * t[1] + (k[3] - k[2]) * t[2] + (k[4] - k[3]) * t[3];
      const double f = local.eval(x - origin);
      EXPECT_NEAR(f, q.eval(x), 1e-12);
      pos = pos || f > 0, neg = neg || f < 0;
    }
    bool previous = true;
    for (const int depth : {0, 2, 4, 6, 8}) {
      const bool may = quadric_may_vanish(t, local, origin, depth);
      if (pos && neg) {
        EXPECT_TRUE(may) << "trial " << trial << " depth " << depth;
      }
      if (!previous) {
        EXPECT_FALSE(may) << "trial " << trial << " depth " << depth;
      }
      refined_away += depth == 8 && !may && quadric_may_vanish(t, local, origin, 0);
      previous = may;
    }
  }
  EXPECT_GT(refined_away, 10);
}
