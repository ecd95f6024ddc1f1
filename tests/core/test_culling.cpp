// Randomized property test: the per-quadric backface tests ([Stoll06] eq. 18, 19) never cull a
// primitive that has a front-facing hit inside its bounding volume, over ≥10⁵ configurations.
#include <gtest/gtest.h>

#include <random>

#include "core/bounds.h"
#include "core/ray.h"

using namespace quadrix;
using Eigen::Vector3d;

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();

Quadric random_quadric_through(std::mt19937_64& rng, const Vector3d& p) {
  std::uniform_real_distribution<double> u(-1, 1);
  QuadricCoefficients k;
  for (auto& v : k) v = u(rng);
  Quadric q = Quadric::from_coefficients(k);
  q.c -= q.eval(p);  // the surface passes through p
  return q;
}
Vector3d random_unit(std::mt19937_64& rng) {
  std::normal_distribution<double> n;
  return Vector3d(n(rng), n(rng), n(rng)).normalized();
}

struct Counts {
  int configs = 0, culled = 0, with_front_hit = 0, violations = 0;
};

// Any front-facing root inside the volume along rays from the eye through sample points?
template <typename Inside, typename Sample>
bool has_front_hit(const Quadric& q_eye, Inside&& inside, Sample&& sample, std::mt19937_64& rng) {
  for (int s = 0; s < 24; ++s) {
    const Vector3d dir = sample(rng).normalized();
    Hit h;
    if (intersect_quadric(q_eye, {Vector3d::Zero(), dir}, 0.0, kInf, true, inside, h)) return true;
  }
  return false;
}
}  // namespace

TEST(Culling, SphereTestNeverCullsVisibleFrontFaces) {
  std::mt19937_64 rng(2024);
  std::uniform_real_distribution<double> u(0, 1);
  Counts n;
  for (int i = 0; i < 100000; ++i) {
    const Vector3d centre = random_unit(rng) * u(rng);
    const double r = 0.05 + u(rng);
    const Quadric q = random_quadric_through(rng, centre + 0.5 * r * random_unit(rng));
    const Vector3d eye = centre + random_unit(rng) * r * (1.2 + 6 * u(rng));
    const Quadric qe = q.translated_to_origin(eye);  // [Stoll06] eq. 9
    const Vector3d ce = centre - eye;
    const bool culled = sphere_backfacing(qe, ce, r);
    const auto inside = [&](const Vector3d& y) { return (y - ce).squaredNorm() <= r * r; };
    const auto sample = [&](std::mt19937_64& g) { return Vector3d(ce + r * std::cbrt(u(g)) * random_unit(g)); };
    const bool front = has_front_hit(qe, inside, sample, rng);
    ++n.configs;
    n.culled += culled;
    n.with_front_hit += front;
    n.violations += culled && front;
  }
  EXPECT_EQ(n.violations, 0);
  // The property is not vacuous: the test culls a real share, and front hits are common.
  EXPECT_GT(n.culled, n.configs / 50);
  EXPECT_GT(n.with_front_hit, n.configs / 4);
  std::printf("sphere: %d configs, %d culled, %d with front-facing hits\n", n.configs, n.culled, n.with_front_hit);
}

TEST(Culling, TetrahedronTestNeverCullsVisibleFrontFaces) {
  std::mt19937_64 rng(99);
  std::uniform_real_distribution<double> u(0, 1);
  Counts n;
  for (int i = 0; i < 100000; ++i) {
    std::array<Vector3d, 4> p;
    for (auto& c : p) c = random_unit(rng) * (0.2 + u(rng));
    if (is_degenerate_tetrahedron(p, 1e-6)) continue;
    const Tetrahedron tet(p);
    const Vector3d centroid = 0.25 * (p[0] + p[1] + p[2] + p[3]);
    const Quadric q = random_quadric_through(rng, centroid);
    const Vector3d eye = centroid + random_unit(rng) * (2.5 + 6 * u(rng));
    const Quadric qe = q.translated_to_origin(eye);
    std::array<Vector3d, 4> pe;
    for (int k = 0; k < 4; ++k) pe[k] = p[k] - eye;
    const bool culled = tetrahedron_backfacing(qe, pe);
    const auto inside = [&](const Vector3d& y) { return tet.contains(y + eye, 1e-12); };
    const auto sample = [&](std::mt19937_64& g) {
      double w[4], s = 0;
      for (double& x : w) s += (x = -std::log(1 - u(g)));  // uniform barycentrics
      Vector3d y = Vector3d::Zero();
      for (int k = 0; k < 4; ++k) y += (w[k] / s) * pe[k];
      return y;
    };
    const bool front = has_front_hit(qe, inside, sample, rng);
    ++n.configs;
    n.culled += culled;
    n.with_front_hit += front;
    n.violations += culled && front;
  }
  EXPECT_GE(n.configs, 99000);
  EXPECT_EQ(n.violations, 0);
  EXPECT_GT(n.culled, n.configs / 50);
  EXPECT_GT(n.with_front_hit, n.configs / 4);
  std::printf("tetrahedron: %d configs, %d culled, %d with front-facing hits\n", n.configs, n.culled,
              n.with_front_hit);
}

TEST(Culling, BackfacingSphereIsCulledFrontFacingIsNot) {
  // Unit sphere seen from outside: its near half faces the eye, so the test must not cull;
  // a small ball around the far pole bounds only back-facing surface and must be culled.
  const Quadric q = Quadric::sphere(Vector3d::Zero(), 1.0);
  const Vector3d eye(0, 0, 10);
  const Quadric qe = q.translated_to_origin(eye);
  EXPECT_FALSE(sphere_backfacing(qe, Vector3d(0, 0, 1) - eye, 0.2));
  EXPECT_TRUE(sphere_backfacing(qe, Vector3d(0, 0, -1) - eye, 0.2));
}
