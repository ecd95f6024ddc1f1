// Models as triangle meshes: the measured error against analytic truth, watertightness, colours.
#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "convert/to_mesh.h"
#include "core/error.h"
#include "core/reference.h"
#include "core/synth.h"

using namespace quadrix;

namespace {

/// Vertices, edge midpoints and face centroids: the points a mesh's error is judged at.
std::vector<Eigen::Vector3d> mesh_samples(const PolygonMesh& m) {
  std::vector<Eigen::Vector3d> s = m.vertices;
  for (std::size_t f = 0; f < m.face_count(); ++f) {
    const auto v = m.face(f);
    const Eigen::Vector3d &a = m.vertices[v[0]], &b = m.vertices[v[1]], &c = m.vertices[v[2]];
    s.insert(s.end(), {(a + b + c) / 3.0, 0.5 * (a + b), 0.5 * (b + c), 0.5 * (c + a)});
  }
  return s;
}

double signed_volume(const PolygonMesh& m) {
  double v = 0;
  for (std::size_t f = 0; f < m.face_count(); ++f) {
    const auto i = m.face(f);
    v += m.vertices[i[0]].dot(m.vertices[i[1]].cross(m.vertices[i[2]])) / 6.0;
  }
  return v;
}

}  // namespace

TEST(EdgewiseSubdivision, KCubedTetrahedraFillingTheSimplex) {
  for (int k = 1; k <= 5; ++k) {
    const auto sub = edgewise_subdivision(k);
    ASSERT_EQ(sub.size(), static_cast<std::size_t>(k * k * k)) << "k = " << k;
    for (const auto& t : sub) {
      const Eigen::Matrix3i E{{t[1].x() - t[0].x(), t[2].x() - t[0].x(), t[3].x() - t[0].x()},
                              {t[1].y() - t[0].y(), t[2].y() - t[0].y(), t[3].y() - t[0].y()},
                              {t[1].z() - t[0].z(), t[2].z() - t[0].z(), t[3].z() - t[0].z()}};
      EXPECT_EQ(std::abs(E.cast<double>().determinant()), 1.0);  // unit lattice volume: all k³ disjoint, equal
    }
  }
}

TEST(ToMesh, SphereGlyphWithinItsBoundAgainstTheAnalyticSphere) {
  const Model m = synth_model("sphere");
  const Glyph& g = m.glyphs.at(0);
  const double bound = 1e-3;
  const ToMeshResult r = mesh_model(m, {.max_error = bound, .progress = {}});
  ASSERT_TRUE(r.within) << "max " << r.max_error();
  EXPECT_LE(r.max_error(), bound);
  EXPECT_EQ(r.open_edges, 0u);
  EXPECT_EQ(r.mesh_to_surface.misses, 0u);
  double worst = 0;
  for (const auto& p : mesh_samples(r.mesh)) worst = std::max(worst, std::abs((p - g.centre).norm() - g.radius));
  EXPECT_LE(worst, bound);
  EXPECT_GT(worst, 0.05 * bound) << "a suspiciously fine mesh: " << r.mesh.face_count() << " triangles";
  // The measure agrees with the truth: the measured maximum is the analytic one (same samples).
  EXPECT_NEAR(r.mesh_to_surface.max, worst, 0.02 * bound);
  EXPECT_GT(signed_volume(r.mesh), 0.0);  // wound outward
  ASSERT_EQ(r.mesh.colours.size(), r.mesh.vertices.size());
  EXPECT_EQ(r.mesh.colours[0], *g.colour);
}

TEST(ToMesh, EllipsoidAndCylinderGlyphsWithinTheirBound) {
  for (const char* kind : {"ellipsoid", "cylinder"}) {
    const Model m = synth_model(kind);
    const double bound = 2e-3;
    const ToMeshResult r = mesh_model(m, {.max_error = bound, .progress = {}});
    EXPECT_TRUE(r.within) << kind << ": max " << r.max_error();
    EXPECT_EQ(r.open_edges, 0u) << kind;
    EXPECT_GT(signed_volume(r.mesh), 0.0) << kind;
    if (std::string(kind) == "ellipsoid") {
      // Taubin's first-order distance to the analytic ellipsoid (accurate this close to it).
      const Glyph& g = m.glyphs[0];
      const Eigen::Matrix3d Mi = g.axes.inverse();
      double worst = 0;
      for (const auto& p : mesh_samples(r.mesh)) {
        const Eigen::Vector3d u = Mi * (p - g.centre);
        const double f = u.squaredNorm() - 1.0;
        worst = std::max(worst, std::abs(f) / (2.0 * Mi.transpose() * u).norm());
      }
      EXPECT_LE(worst, 1.01 * bound);
    }
  }
}

TEST(ToMesh, HyperboloidTetPatchesOnTheQuadricAndClosedInside) {
  const Model m = synth_model("hyperboloid1", {.resolution = 6});
  const Quadric truth = synth_quadric("hyperboloid1");
  const double bound = 5e-3;
  const ToMeshResult r = mesh_model(m, {.max_error = bound, .progress = {}});
  ASSERT_TRUE(r.within) << "max " << r.max_error() << " misses " << r.mesh_to_surface.misses;
  double worst = 0;
  for (const auto& p : mesh_samples(r.mesh)) worst = std::max(worst, truth.taubin_distance(p));
  EXPECT_LE(worst, 1.01 * bound);
  // Crossings are the quadric's roots: vertices lie on it to rounding.
  for (const auto& p : r.mesh.vertices) ASSERT_LT(truth.taubin_distance(p), 1e-9);
  // Open edges only where the surface leaves the grid of tetrahedra (the box ±1.5).
  std::map<std::pair<int, int>, int> uses;
  for (std::size_t f = 0; f < r.mesh.face_count(); ++f) {
    const auto v = r.mesh.face(f);
    for (int i = 0; i < 3; ++i) ++uses[std::minmax(v[i], v[(i + 1) % 3])];
  }
  std::size_t open = 0;
  for (const auto& [e, n] : uses)
    if (n != 2) {
      ++open;
      for (const int v : {e.first, e.second})
        EXPECT_NEAR(r.mesh.vertices[v].cwiseAbs().maxCoeff(), 1.5, 1e-9) << "open edge inside the box";
    }
  EXPECT_EQ(open, r.open_edges);
  EXPECT_GT(open, 0u);
}

TEST(ToMesh, SlimSphereWithinItsBoundOfTheDrawnBlend) {
  const Model m = synth_model("slim-sphere");
  // The blend itself is not exactly the unit sphere: its radial deviation, from rays to the centre.
  const ReferenceScene scene(m);
  double blend_dev = 0;
  for (int i = 0; i < 2000; ++i) {
    const double z = 1.0 - (2.0 * i + 1.0) / 2000, rr = std::sqrt(1 - z * z), phi = i * 2.399963;
    const Eigen::Vector3d d(rr * std::cos(phi), rr * std::sin(phi), z);
    const auto hit = scene.trace({3.0 * d, -d}, 0.0, 10.0, {});
    ASSERT_TRUE(hit);
    blend_dev = std::max(blend_dev, std::abs(hit->point.norm() - 1.0));
  }
  const double bound = 2e-3;
  const ToMeshResult r = mesh_model(m, {.max_error = bound, .progress = {}});
  ASSERT_TRUE(r.within) << "max " << r.max_error() << " misses " << r.mesh_to_surface.misses;
  EXPECT_EQ(r.open_edges, 0u);
  EXPECT_GT(signed_volume(r.mesh), 0.0);
  double worst = 0;
  for (const auto& p : mesh_samples(r.mesh)) worst = std::max(worst, std::abs(p.norm() - 1.0));
  EXPECT_LE(worst, bound + blend_dev) << "blend deviates by " << blend_dev;
  EXPECT_EQ(r.mesh.colours.size(), r.mesh.vertices.size());
}

TEST(ToMesh, EmptyModelRefused) { EXPECT_THROW(mesh_model(Model{}), InvalidInput); }
