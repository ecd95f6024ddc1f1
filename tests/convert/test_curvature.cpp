// Curvature glyphs against analytic curvatures: a sphere (k = 1/R both), a cylinder (1/R along
// the circle, 0 along the axis) and a saddle z = x² − y² (±2 at the origin).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "convert/curvature_glyphs.h"
#include "core/error.h"

using namespace quadrix;

namespace {

// A grid mesh (quads) of u × v vertices from a parametrisation; `wrap_u` closes the u direction.
template <class F>
PolygonMesh grid(int nu, int nv, bool wrap_u, F f) {
  PolygonMesh m;
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) m.vertices.push_back(f(double(i) / (wrap_u ? nu : nu - 1), double(j) / (nv - 1)));
  for (int j = 0; j + 1 < nv; ++j)
    for (int i = 0; i < (wrap_u ? nu : nu - 1); ++i) {
      const int i1 = (i + 1) % nu;
      m.add_face(std::array{j * nu + i, j * nu + i1, (j + 1) * nu + i1, (j + 1) * nu + i});
    }
  return m;
}

double median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

}  // namespace

TEST(CurvatureGlyphs, SphereHasCurvatureOneOverRadius) {
  const double R = 2.0, pi = std::numbers::pi;
  // Latitudes away from the poles (the grid is open there); outward faces.
  const PolygonMesh m = grid(64, 33, true, [&](double u, double v) {
    const double phi = 2 * pi * u, theta = 0.85 * pi - 0.7 * pi * v;
    return Eigen::Vector3d(R * std::sin(theta) * std::cos(phi), R * std::sin(theta) * std::sin(phi), R * std::cos(theta));
  });
  const CurvatureGlyphs g = curvature_glyphs(m);
  ASSERT_GT(g.model.glyphs.size(), m.vertices.size() * 9 / 10);
  EXPECT_NEAR(median(g.k_max), 1 / R, 0.03 / R);
  EXPECT_NEAR(median(g.k_min), 1 / R, 0.03 / R);
  for (const Glyph& gl : g.model.glyphs) EXPECT_EQ(gl.kind, GlyphKind::ellipsoid);
}

TEST(CurvatureGlyphs, CylinderBendsAlongTheCircleOnly) {
  const double R = 1.0, pi = std::numbers::pi;
  const PolygonMesh m = grid(96, 40, true, [&](double u, double v) {
    return Eigen::Vector3d(R * std::cos(2 * pi * u), R * std::sin(2 * pi * u), 4.0 * v);
  });
  const CurvatureGlyphs g = curvature_glyphs(m);
  EXPECT_NEAR(median(g.k_max), 1 / R, 0.03);
  EXPECT_NEAR(median(g.k_min), 0.0, 0.03);
  // The longest in-plane axis (maximal curvature) runs around the circle, not along z.
  int along_circle = 0;
  for (std::size_t i = 0; i < g.model.glyphs.size(); ++i) {
    const Eigen::Vector3d d = g.model.glyphs[i].axes.col(0).normalized();
    along_circle += std::abs(d.z()) < 0.1;
    EXPECT_GT(g.model.glyphs[i].axes.col(0).norm(), g.model.glyphs[i].axes.col(1).norm() * 2) << "vertex " << i;
  }
  EXPECT_GE(along_circle, int(g.model.glyphs.size()) * 95 / 100);
}

TEST(CurvatureGlyphs, SaddleAtTheOrigin) {
  const PolygonMesh m = grid(41, 41, false, [](double u, double v) {
    const double x = 0.4 * (2 * u - 1), y = 0.4 * (2 * v - 1);
    return Eigen::Vector3d(x, y, x * x - y * y);
  });
  const CurvatureGlyphs g = curvature_glyphs(m, {.jet_degree = 3, .neighbours = 24});
  const auto it = std::find(g.vertex.begin(), g.vertex.end(), std::size_t(20 * 41 + 20));
  ASSERT_NE(it, g.vertex.end());
  const std::size_t i = static_cast<std::size_t>(it - g.vertex.begin());
  // Faces wind counter-clockwise seen from +z: the normal is +z, z = x² − y² gives ±2.
  EXPECT_NEAR(g.k_max[i], 2.0, 0.05);
  EXPECT_NEAR(g.k_min[i], -2.0, 0.05);
}

TEST(CurvatureGlyphs, RefusesBadInput) {
  EXPECT_THROW(curvature_glyphs(PolygonMesh{}), InvalidInput);
  const PolygonMesh m = grid(5, 5, false, [](double u, double v) { return Eigen::Vector3d(u, v, 0); });
  EXPECT_THROW(curvature_glyphs(m, {.jet_degree = 4, .neighbours = 10}), InvalidInput);
}
