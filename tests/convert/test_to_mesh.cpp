// Models as triangle meshes: the measured error against analytic truth, watertightness, colours.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <map>
#include <numbers>
#include <optional>
#include <random>
#include <set>
#include <tuple>

#include "convert/mesh_measure.h"
#include "convert/quads.h"
#include "convert/self_intersections.h"
#include "convert/to_mesh.h"
#include "convert/volume.h"
#include "core/bounds.h"
#include "core/error.h"
#include "core/io/io.h"
#include "core/mesh_io.h"
#include "core/model_io.h"
#include "core/points_io.h"
#include "core/reference.h"
#include "core/synth.h"
#include "fit/data_surface.h"
#include "fit/slim_fit.h"

using namespace quadrix;

namespace {

constexpr double kSmallRadius = 0.12;
constexpr int kSmallBalls = 80;

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

// A glyph union as a slicer or a boolean operation wants it: made, within the bound, closed, no
// triangles crossing.
void expect_clean_union(const ToMeshResult& u) {
  EXPECT_TRUE(u.glyph_union);
  EXPECT_EQ(u.glyph_unions_failed, 0u);
  EXPECT_TRUE(u.within) << u.max_error();
  EXPECT_EQ(u.open_edges, 0u);
  EXPECT_EQ(self_intersections(u.mesh).pairs, 0u);
}

double signed_volume(const PolygonMesh& m) {
  double v = 0;
  for (std::size_t f = 0; f < m.face_count(); ++f) {
    const auto i = m.face(f);
    v += m.vertices[i[0]].dot(m.vertices[i[1]].cross(m.vertices[i[2]])) / 6.0;
  }
  return v;
}

/// Points of the torus (R, r) around z with their normals, seeded.
PointCloud torus_points(std::size_t n, double R, double r, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> U(0, 2 * std::numbers::pi), V(0, 1);
  PointCloud c;
  while (c.points.size() < n) {
    const double u = U(rng), v = U(rng);
    if (V(rng) > (R + r * std::cos(v)) / (R + r)) continue;  // uniform by area
    const Eigen::Vector3d nrm(std::cos(v) * std::cos(u), std::cos(v) * std::sin(u), std::sin(v));
    c.points.push_back(Eigen::Vector3d(R * std::cos(u), R * std::sin(u), 0) + r * nrm);
    c.normals.push_back(nrm);
  }
  return c;
}

/// SLIM balls on the sphere (centre c, radius r) at n Fibonacci points, each holding the sphere
/// itself (as synth "slim-sphere" makes the unit one), support 3.6 r/√n.
void add_slim_sphere(Model& m, const Eigen::Vector3d& c, double r, int n) {
  const double R = 3.6 * r / std::sqrt(static_cast<double>(n));
  const Quadric sphere = Quadric::sphere(c, r);
  for (int i = 0; i < n; ++i) {
    const double z = 1.0 - (2.0 * i + 1.0) / n, rr = std::sqrt(std::max(0.0, 1.0 - z * z));
    const double phi = i * std::numbers::pi * (3.0 - std::sqrt(5.0));
    const Eigen::Vector3d x = c + r * Eigen::Vector3d(rr * std::cos(phi), rr * std::sin(phi), z);
    m.slims.push_back({x, R, sphere.to_local(x, R), ClipPlanes{}, std::nullopt, std::nullopt});
  }
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
  // Each vertex carries the sphere's own normal there (outward), not its faces' average.
  ASSERT_EQ(r.mesh.normals.size(), r.mesh.vertices.size());
  EXPECT_EQ(r.normals_from_faces, 0u);
  for (std::size_t v = 0; v < r.mesh.vertices.size(); ++v)
    EXPECT_LT((r.mesh.normals[v] - (r.mesh.vertices[v] - g.centre).normalized()).norm(), 1e-7) << "vertex " << v;
  EXPECT_TRUE(mesh_model(m, {.max_error = bound, .normals = false, .progress = {}}).mesh.normals.empty());
}

TEST(ToMesh, DistanceOfAReversedOrTiltedMeshIsStillItsDistance) {
  // A mesh lying on the drawn surface is within the bound of it whichever way its triangles face
  // (a grid labelling read the other way round reverses them) and however their normals lean.
  const Model m = synth_model("sphere");
  const double bound = 1e-3;
  const ToMeshResult r = mesh_model(m, {.max_error = bound, .progress = {}});
  ASSERT_TRUE(r.within) << "max " << r.max_error();
  PolygonMesh reversed;
  reversed.vertices = r.mesh.vertices;
  for (std::size_t f = 0; f < r.mesh.face_count(); ++f) {
    const auto v = r.mesh.face(f);
    reversed.add_face(std::array<int, 3>{v[0], v[2], v[1]});
  }
  const MeshDistance back = mesh_distance(m, reversed, 4 * bound, bound);
  EXPECT_EQ(back.misses, 0u);
  EXPECT_LE(back.max, bound);
  EXPECT_NEAR(back.max, r.mesh_to_surface.max, 0.02 * bound);
  // A fin: a strip along the equator reaching half the bound into the sphere, nearly across its
  // surface (normals 75° off the radius). Its samples' normal lines meet the sphere about twice
  // the bound away; the grid lines (within 22.5° of the radius here) within 0.55 of it.
  const Glyph& g = m.glyphs.at(0);
  PolygonMesh tilted;
  const int n = 1024;  // chords' sagitta 5e-6
  for (int k = 0; k <= n; ++k) {
    const double a = 2 * std::numbers::pi * k / n;
    const Eigen::Vector3d on = g.centre + g.radius * Eigen::Vector3d(std::cos(a), std::sin(a), 0.0);
    tilted.vertices.push_back(on);
    tilted.vertices.push_back(on + 0.134 * bound * Eigen::Vector3d(0, 0, 1) - 0.5 * bound * (on - g.centre).normalized());
  }
  for (int k = 0; k < n; ++k) {
    tilted.add_face(std::array<int, 3>{2 * k, 2 * k + 2, 2 * k + 1});
    tilted.add_face(std::array<int, 3>{2 * k + 1, 2 * k + 2, 2 * k + 3});
  }
  const MeshDistance lean = mesh_distance(m, tilted, 4 * bound, bound);
  EXPECT_EQ(lean.misses, 0u);
  EXPECT_LE(lean.max, bound);
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

// Balls and sticks (two atoms and their bond, as convert glyphs makes them: each half of the bond
// a capped cylinder in its atom's colour, the halves' caps meeting at the middle, and a third atom
// bonded at an angle) meshed as their union: CGAL's pairwise corefinement crashed on such tubes
// (4lfq balls-and-sticks), so they are autorefined as one soup in a child process. One closed
// surface, no triangles crossing, nothing left inside a glyph, each part in its own colour.
TEST(ToMesh, BallsAndSticksMeshedAsTheirUnion) {
  Model m;
  const Rgb red{255, 0, 0}, green{0, 255, 0}, blue{0, 0, 255};
  const std::vector<std::tuple<Eigen::Vector3d, double, Rgb>> atoms{
      {{0, 0, 0}, 0.5, red}, {{1.5, 0, 0}, 0.4, green}, {{-0.6, 1.2, 0.3}, 0.45, blue}};
  for (const auto& [c, r, rgb] : atoms) m.glyphs.push_back({GlyphKind::sphere, c, r, Eigen::Matrix3d::Identity(), rgb});
  const double stick = 0.15;
  const auto bond = [&](std::size_t a, std::size_t b) {
    const Eigen::Vector3d pa = std::get<0>(atoms[a]), pb = std::get<0>(atoms[b]), mid = 0.5 * (pa + pb);
    for (const auto& [from, rgb] : {std::pair{pa, std::get<2>(atoms[a])}, std::pair{pb, std::get<2>(atoms[b])}}) {
      Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();
      axes.col(0) = 0.5 * (mid - from);
      m.glyphs.push_back({GlyphKind::cylinder, 0.5 * (from + mid), stick, axes, rgb});
    }
  };
  bond(0, 1);
  bond(0, 2);
  ASSERT_TRUE(unions_glyphs(m));
  const double bound = 5e-3;
  const ToMeshResult u = mesh_model(m, {.max_error = bound, .progress = {}});
  // (With each half its own capped cylinder, the two caps at the bond's middle, a rounding apart,
  // left 80 crossing pairs of slivers: the halves are one tube.)
  expect_clean_union(u);
  EXPECT_GT(signed_volume(u.mesh), 0.0);
  // How deep p lies inside glyph g (negative: outside), exact for spheres and capped cylinders.
  const auto depth = [&](const Glyph& g, const Eigen::Vector3d& p) {
    if (g.kind == GlyphKind::sphere) return g.radius - (p - g.centre).norm();
    const Eigen::Vector3d half = g.axes.col(0);
    const double len = half.norm(), t = (p - g.centre).dot(half / len);
    const double radial = (p - g.centre - t * half / len).norm();
    return std::min(g.radius - radial, len - std::abs(t));
  };
  ASSERT_EQ(u.mesh.colours.size(), u.mesh.vertices.size());
  std::size_t single = 0;
  for (std::size_t v = 0; v < u.mesh.vertices.size(); ++v) {
    const Eigen::Vector3d& p = u.mesh.vertices[v];
    double inside = -1e9;
    int on = 0;
    std::size_t which = 0;
    for (std::size_t g = 0; g < m.glyphs.size(); ++g) {
      const double d = depth(m.glyphs[g], p);
      inside = std::max(inside, d);
      if (std::abs(d) < 1e-9) ++on, which = g;
    }
    ASSERT_LE(inside, bound) << "vertex " << v << " lies inside a glyph";
    ASSERT_GE(inside, -bound) << "vertex " << v << " lies off every glyph";
    // A vertex on one glyph only (a sphere's or a tube's own vertex, not made on an intersection
    // curve) has that glyph's colour.
    if (on == 1) {
      ++single;
      EXPECT_EQ(u.mesh.colours[v], *m.glyphs[which].colour) << "vertex " << v;
    }
  }
  EXPECT_GT(single, u.mesh.vertices.size() / 2);
  // Glyph by glyph the tubes cross the atoms.
  ToMeshOptions apart{.max_error = bound, .progress = {}};
  apart.union_glyphs = false;
  EXPECT_GT(self_intersections(mesh_model(m, apart).mesh).pairs, 100u);
  // As a compact .qxm stores them: 20 units from the origin, centres and axes rounded to float32,
  // so the halves' tips no longer meet exactly (they paired only within 1e-9 of their length).
  Model far = m;
  for (Glyph& g : far.glyphs) {
    g.centre = (g.centre + Eigen::Vector3d::Constant(20.0)).cast<float>().cast<double>();
    g.axes = g.axes.cast<float>().cast<double>();
    g.radius = double(float(g.radius));
  }
  const std::vector<std::size_t> halves = bond_halves(far.glyphs);
  for (std::size_t g = 0; g < far.glyphs.size(); ++g)
    EXPECT_EQ(halves[g] != kNoPartner, far.glyphs[g].kind == GlyphKind::cylinder) << "glyph " << g;
  expect_clean_union(mesh_model(far, {.max_error = bound, .progress = {}}));
}

// Overlapping spheres (a spacefill molecule's atoms) meshed as their union: one closed surface
// without crossing triangles, nothing of a sphere left inside another, each part in its own
// colour; glyph by glyph (union off) the shells cross. A sphere given twice is meshed once.
TEST(ToMesh, OverlappingSpheresMeshedAsTheirUnion) {
  Model m;
  const std::vector<std::pair<Eigen::Vector3d, Rgb>> atoms{{{0, 0, 0}, {255, 0, 0}}, {{1.2, 0, 0}, {0, 255, 0}},
                                                           {{0.6, 1.0, 0.2}, {0, 0, 255}}, {{1.2, 0, 0}, {0, 255, 0}}};
  for (const auto& [c, rgb] : atoms) m.glyphs.push_back({GlyphKind::sphere, c, 1.0, Eigen::Matrix3d::Identity(), rgb});
  const double bound = 5e-3;
  const ToMeshResult u = mesh_model(m, {.max_error = bound, .progress = {}});
  expect_clean_union(u);
  // Every vertex on the union's boundary: at least one sphere's radius out (within the bound,
  // the faces being inscribed), none deeper than the bound inside any sphere.
  ASSERT_EQ(u.mesh.colours.size(), u.mesh.vertices.size());
  for (std::size_t v = 0; v < u.mesh.vertices.size(); ++v) {
    const Eigen::Vector3d& p = u.mesh.vertices[v];
    double inside = -1e9;  // the most any sphere holds p by
    std::size_t nearest = 0;
    for (std::size_t a = 0; a < 3; ++a) {
      const double depth = 1.0 - (p - atoms[a].first).norm();
      if (depth > inside) inside = depth;
      if (std::abs(1.0 - (p - atoms[a].first).norm()) < std::abs(1.0 - (p - atoms[nearest].first).norm())) nearest = a;
    }
    ASSERT_LE(inside, bound) << "vertex " << v << " lies inside a sphere";
    ASSERT_GE(inside, -bound) << "vertex " << v << " lies off every sphere";
    // A vertex on one sphere only (away from the intersection curves) has that sphere's colour.
    if (std::abs(1.0 - (p - atoms[nearest].first).norm()) < 1e-9) {
      int on = 0;
      for (std::size_t a = 0; a < 3; ++a) on += std::abs(1.0 - (p - atoms[a].first).norm()) < 0.05;
      if (on == 1) EXPECT_EQ(u.mesh.colours[v], atoms[nearest].second) << "vertex " << v;
    }
  }
  ToMeshOptions apart{.max_error = bound, .progress = {}};
  apart.union_glyphs = false;
  const ToMeshResult w = mesh_model(m, apart);
  EXPECT_FALSE(w.glyph_union);
  EXPECT_GT(self_intersections(w.mesh).pairs, 100u);
  // The union's area is less than the shells' (the hidden caps are gone).
  const auto area = [](const PolygonMesh& mesh) {
    double s = 0;
    for (std::size_t f = 0; f < mesh.face_count(); ++f) {
      const auto t = mesh.face(f);
      s += 0.5 * (mesh.vertices[t[1]] - mesh.vertices[t[0]]).cross(mesh.vertices[t[2]] - mesh.vertices[t[0]]).norm();
    }
    return s;
  };
  EXPECT_LT(area(u.mesh), 0.8 * area(w.mesh) * 3.0 / 4.0);  // w holds the repeated sphere twice
  EXPECT_GT(signed_volume(u.mesh), 0.0);
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

// A SLIM wire (a cylinder 6e-4 of its ball's radius across, as `fit` makes of a thin wire
// fitted at an E of its radius) slips between every grid's nodes: the mesh comes out empty.
// `mesh` refused the model it could not measure against ("DataSurface: the mesh has no faces",
// exit 3, a valid model); now every drawn pixel counts as beyond the bound, at no finite distance.
TEST(ToMesh, AnEmptyMeshOfADrawnSurfaceIsOutsideTheBound) {
  Model m;
  SlimPatch wire;
  wire.radius = 1.0;
  wire.local.A.diagonal() = Eigen::Vector3d(1, 1, 0);  // x² + y² = r²
  wire.local.c = -1e-7;
  m.slims.push_back(wire);
  const ToMeshResult r = mesh_model(m, {.max_error = 1e-3, .progress = {}});
  ASSERT_EQ(r.mesh.face_count(), 0u) << "the grid found the wire: the case no longer tests an empty mesh";
  EXPECT_FALSE(r.within);
  EXPECT_GT(r.surface_to_mesh.samples, 0u);
  EXPECT_EQ(r.surface_to_mesh.beyond, r.surface_to_mesh.samples);
  EXPECT_TRUE(std::isinf(r.surface_to_mesh.max));
}

TEST(ToMesh, FittedTorusClosedAndWithinItsBoundOfTheDrawnBlendAwayFromItsCracks) {
  const SlimFitResult fit = fit_slim(torus_points(8000, 1.0, 0.35, 7), {.max_error = 1e-3});
  // Default bound (1e-3 of the diagonal), no refinement: seconds.
  const ToMeshResult r = mesh_model(fit.model, {.max_refinements = 0, .progress = {}});
  ASSERT_GT(r.mesh.face_count(), 0u);
  // Closed, one piece, a torus: every edge in two triangles, V − E + F = 0, wound outward.
  std::map<std::pair<int, int>, int> uses;
  for (std::size_t f = 0; f < r.mesh.face_count(); ++f) {
    const auto v = r.mesh.face(f);
    for (int i = 0; i < 3; ++i) ++uses[std::minmax(v[i], v[(i + 1) % 3])];
  }
  std::size_t open = 0;
  for (const auto& [e, n] : uses) open += n != 2;
  EXPECT_EQ(open, 0u);
  EXPECT_EQ(r.open_edges, 0u);
  EXPECT_EQ(static_cast<long>(r.mesh.vertices.size()) - static_cast<long>(uses.size()) + static_cast<long>(r.mesh.face_count()), 0);
  EXPECT_GT(signed_volume(r.mesh), 0.0);
  // The distance, measured apart from the mesher: random points of the triangles against the blend
  // seen along the torus's normal there, and blend points (rays along the torus's normals) against
  // the triangles (closest point). This fit's blend has cracks a few millimetres wide where
  // neighbouring balls barely overlap (its own surface error exceeds E there), which a closed mesh
  // must bridge; so the 99th percentile is held to the bound and the maximum to a few bounds.
  const ReferenceScene scene(fit.model);
  TraceOptions trace;
  trace.slim.offset = slim_offset_of(fit.model);
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> U(0, 1);
  const auto torus_normal = [](const Eigen::Vector3d& p) {
    const Eigen::Vector3d core = Eigen::Vector3d(p.x(), p.y(), 0).normalized();
    return Eigen::Vector3d(p - core).normalized();
  };
  const double reach = 0.1;
  const auto p99 = [](std::vector<double> d) {
    std::sort(d.begin(), d.end());
    return d[static_cast<std::size_t>(0.99 * (d.size() - 1))];
  };
  std::vector<double> mesh_side;
  for (int k = 0; k < 4000; ++k) {
    const auto v = r.mesh.face(static_cast<std::size_t>(U(rng) * r.mesh.face_count()) % r.mesh.face_count());
    double a = U(rng), b = U(rng);
    if (a + b > 1) a = 1 - a, b = 1 - b;
    const Eigen::Vector3d p = r.mesh.vertices[v[0]] + a * (r.mesh.vertices[v[1]] - r.mesh.vertices[v[0]]) +
                              b * (r.mesh.vertices[v[2]] - r.mesh.vertices[v[0]]);
    const Eigen::Vector3d n = torus_normal(p);
    const auto hit = scene.trace({p + reach * n, -n}, 0.0, 2 * reach, trace);
    mesh_side.push_back(hit ? std::abs(hit->t - reach) : reach);
  }
  const DataSurface triangles = DataSurface::from_mesh(r.mesh);
  std::vector<double> surface_side;
  const PointCloud on_torus = torus_points(4000, 1.0, 0.35, 12);
  for (std::size_t k = 0; k < on_torus.points.size(); ++k) {
    const Eigen::Vector3d& n = on_torus.normals[k];
    if (const auto hit = scene.trace({on_torus.points[k] + reach * n, -n}, 0.0, 2 * reach, trace))
      surface_side.push_back(triangles.distance(hit->point));
  }
  ASSERT_GT(surface_side.size(), 3900u);
  EXPECT_LE(p99(mesh_side), r.bound);
  EXPECT_LE(p99(surface_side), r.bound);
  EXPECT_LE(*std::max_element(surface_side.begin(), surface_side.end()), 3.0 * r.bound);
  EXPECT_GT(p99(mesh_side), 0.01 * r.bound) << "a suspiciously fine mesh: " << r.mesh.face_count() << " triangles";
  std::cout << "torus: " << r.mesh.face_count() << " triangles; mesher: max " << r.max_error() << ", beyond "
            << r.mesh_to_surface.beyond << " of " << r.mesh_to_surface.samples << "; here p99 " << p99(mesh_side) << " / "
            << p99(surface_side) << ", bound " << r.bound << "\n";
}

// A large smooth sphere and a small one: the first grid, sized for the large sphere's patches,
// is too coarse only on the small one. Local refinement (bisecting the triangles there) reaches
// the bound both ways with fewer triangles than uniform doubling, and no open edges; without it
// (and without grid refinement), the first grid misses the bound.
TEST(ToMesh, LocalRefinementWhereOnlyOneSmallPartNeedsIt) {
  Model m;
  add_slim_sphere(m, Eigen::Vector3d::Zero(), 1.0, 200);
  add_slim_sphere(m, Eigen::Vector3d(1.6, 0, 0), kSmallRadius, kSmallBalls);
  const ToMeshResult local = mesh_model(m, {.max_refinements = 0, .progress = {}});
  const ToMeshResult first =
      mesh_model(m, {.max_refinements = 0, .local_refinements = 0, .grid_refinements = 0, .progress = {}});
  const ToMeshResult uniform = mesh_model(m, {.local_refinements = 0, .grid_refinements = 0, .progress = {}});
  std::cout << "two spheres, bound " << local.bound << ": first grid " << first.mesh.face_count() << " triangles, max "
            << first.mesh_to_surface.max << " / " << first.surface_to_mesh.max << "; local (" << local.local_rounds
            << " rounds) " << local.mesh.face_count() << ", max " << local.mesh_to_surface.max << " / "
            << local.surface_to_mesh.max << ", open " << local.open_edges << "; uniform (" << uniform.refinements
            << " doublings) " << uniform.mesh.face_count() << ", max " << uniform.mesh_to_surface.max << " / "
            << uniform.surface_to_mesh.max << "\n";
  EXPECT_FALSE(first.within) << "the first grid alone should miss the bound: the case needs refinement";
  ASSERT_TRUE(local.within) << "max " << local.mesh_to_surface.max << " / " << local.surface_to_mesh.max << ", misses "
                            << local.mesh_to_surface.misses;
  EXPECT_LE(local.mesh_to_surface.max, local.bound);
  EXPECT_LE(local.surface_to_mesh.max, local.bound);
  EXPECT_GT(local.local_rounds, 0);
  EXPECT_EQ(local.open_edges, 0u);
  EXPECT_EQ(first.open_edges, 0u);
  EXPECT_GT(signed_volume(local.mesh), 0.0);
  EXPECT_GT(uniform.refinements, 0);
  EXPECT_LT(local.mesh.face_count() * 2, uniform.mesh.face_count()) << "local refinement should need far fewer triangles";
  EXPECT_LT(local.mesh.face_count(), first.mesh.face_count() * 5 / 4) << "refinement should stay local";
}

// A large sphere and, beside it, a sphere a third of a grid cell across: no grid node falls
// inside it and no cut of the large sphere's triangles can create it, so the first grid misses
// it whatever its triangles do. Local grid refinement (the cells where the drawn surface is
// beyond the bound cut finer) finds it, closed, with no crack at the seams between fine and
// coarse cells, and far fewer triangles than a uniform doubling.
TEST(ToMesh, LocalGridRefinementFindsAPartBetweenGridNodes) {
  Model m;
  add_slim_sphere(m, Eigen::Vector3d::Zero(), 1.0, 200);
  add_slim_sphere(m, Eigen::Vector3d(1.45, 0.31, -0.17), 0.016, 40);
  const ToMeshResult grid = mesh_model(m, {.max_refinements = 0, .progress = {}});
  // The first grid alone: neither its cells cut finer nor open sheets on what it misses.
  const ToMeshResult first = mesh_model(m, {.max_refinements = 0, .grid_refinements = 0, .open_parts = false, .progress = {}});
  std::cout << "sphere and a speck, bound " << grid.bound << ": first grid " << first.mesh.face_count()
            << " triangles, max " << first.mesh_to_surface.max << " / " << first.surface_to_mesh.max << ", beyond "
            << first.mesh_to_surface.beyond << " / " << first.surface_to_mesh.beyond << "; grid refined ("
            << grid.grid_rounds << " rounds, " << grid.refined_cells << " cells) " << grid.mesh.face_count()
            << ", max " << grid.mesh_to_surface.max << " / " << grid.surface_to_mesh.max << ", open " << grid.open_edges
            << "\n";
  EXPECT_FALSE(first.within) << "the first grid should miss the small sphere";
  EXPECT_GT(first.surface_to_mesh.max, 10 * first.bound) << "the small sphere should be missing, not coarse";
  ASSERT_TRUE(grid.within) << "max " << grid.mesh_to_surface.max << " / " << grid.surface_to_mesh.max << ", misses "
                           << grid.mesh_to_surface.misses;
  EXPECT_GT(grid.grid_rounds, 0);
  EXPECT_EQ(grid.open_edges, 0u);
  EXPECT_EQ(first.open_edges, 0u);
  // Two closed pieces: V − E + F = 2 + 2, wound outward.
  std::map<std::pair<int, int>, int> uses;
  for (std::size_t f = 0; f < grid.mesh.face_count(); ++f) {
    const auto v = grid.mesh.face(f);
    for (int i = 0; i < 3; ++i) ++uses[std::minmax(v[i], v[(i + 1) % 3])];
  }
  EXPECT_EQ(static_cast<long>(grid.mesh.vertices.size()) - static_cast<long>(uses.size()) +
                static_cast<long>(grid.mesh.face_count()),
            4);
  EXPECT_GT(signed_volume(grid.mesh), 0.0);
  // The speck is there: vertices on it, none far from it.
  std::size_t on_speck = 0;
  for (const auto& p : grid.mesh.vertices)
    if ((p - Eigen::Vector3d(1.45, 0.31, -0.17)).norm() < 0.016 + grid.bound) ++on_speck;
  EXPECT_GT(on_speck, 20u);
  EXPECT_LT(grid.mesh.face_count(), first.mesh.face_count() * 5 / 4) << "grid refinement should stay local";
}

// Local refinement cuts a face at the edge whose midpoint is beyond the bound (longest-edge
// bisection alone can leave that sample where it was, on a shorter edge): the measure names those
// edges. One triangle on the unit sphere: its long edge's midpoint sinks about 0.042 below the
// sphere, the short edges' about 0.014.
TEST(ToMesh, BeyondSamplesNameTheEdgesWhoseMidpointsAreBeyond) {
  Model m;
  m.glyphs.push_back({.kind = GlyphKind::sphere, .centre = Eigen::Vector3d::Zero(), .radius = 1.0});
  PolygonMesh tri;
  tri.vertices = {Eigen::Vector3d(-0.3, 0, 1).normalized(), Eigen::Vector3d(0.3, 0, 1).normalized(),
                  Eigen::Vector3d(0, 0.15, 1).normalized()};
  const int f[3] = {0, 1, 2};
  tri.add_face(f);
  const ReferenceScene scene(m);
  BeyondSamples where;
  const MeshDistance d = mesh_to_surface(scene, TraceOptions{}, tri, 0.1, 0.025, &where);
  ASSERT_EQ(where.edges.size(), 1u);
  EXPECT_EQ(where.edges[0], 0b001) << "only the edge from vertex 0 to vertex 1 has its midpoint beyond";
  EXPECT_NEAR(where.faces[0], 1.0 - std::cos(std::atan(0.3)), 2e-3);
  EXPECT_EQ(d.misses, 0u);
  const BeyondSamples tighter = [&] {
    BeyondSamples w;
    mesh_to_surface(scene, TraceOptions{}, tri, 0.1, 0.005, &w);
    return w;
  }();
  EXPECT_EQ(tighter.edges[0], 0b111);
}

TEST(ToMesh, EmptyModelRefused) { EXPECT_THROW(mesh_model(Model{}), InvalidInput); }

// The Stanford bunny fitted at 1e-3 of its diagonal (as `make demo` does), meshed on one grid:
// the per-ray blend shows grazing views the surface up to about 1.7 bounds in front of where a
// head-on view sees it, so a mesh on the head-on surface leaves those pixels beyond the bound;
// with the vertices moved part of the way towards them the mesh is within the bound both ways.
TEST(ToMesh, FittedBunnyWithinItsBoundBothWays) {
  const std::filesystem::path file = std::filesystem::path(QUADRIX_DATASETS) / "meshes" / "bunny.ply";
  if (!std::filesystem::exists(file)) GTEST_SKIP() << file << " not found";
  const PolygonMesh scan = read_mesh(file);
  const SlimFitResult fit = fit_slim(points_from_mesh(scan), scan, {.max_error = 1e-3});
  const ToMeshResult r = mesh_model(fit.model, {.max_refinements = 0, .progress = {}});
  std::cout << "bunny: " << fit.model.slims.size() << " patches; mesh " << r.mesh.face_count() << " triangles, max "
            << r.mesh_to_surface.max << " / " << r.surface_to_mesh.max << ", beyond " << r.mesh_to_surface.beyond << " / "
            << r.surface_to_mesh.beyond << ", bound " << r.bound << ", grid rounds " << r.grid_rounds << ", view rounds "
            << r.view_rounds << ", open edges " << r.open_edges << "\n";
  EXPECT_TRUE(r.within) << "max " << r.mesh_to_surface.max << " / " << r.surface_to_mesh.max;
  EXPECT_EQ(r.mesh_to_surface.beyond, 0u);
  EXPECT_EQ(r.surface_to_mesh.beyond, 0u);
  EXPECT_EQ(r.mesh_to_surface.misses, 0u);
}

// A scan without normals (radar.xyz: 20,950 points, normals estimated, holes between scan lines),
// fitted at 1e-3 and meshed at `quadrix mesh`'s default bound (the larger of 1e-3 of the model's
// diagonal and the fit's own E): the faces a move leaves
// beyond the bound are left out and the drawn surface under them gets sheets too (it ended at
// 1.92 bounds, 11 pixels beyond under faces left out, with exit 7).
TEST(ToMesh, ScanWithoutNormalsMeshedWithinTheFitsOwnBound) {
  const std::filesystem::path file = std::filesystem::path(QUADRIX_DATASETS) / "points" / "radar.xyz";
  if (!std::filesystem::exists(file)) GTEST_SKIP() << file << " not found";
  const SlimFitResult fit = fit_slim(read_points(file), {.max_error = 1e-3});
  const double bound = std::max(1e-3 * bounds(fit.model).diagonal(), metadata_number(fit.model, "max_error_abs").value_or(0));
  const ToMeshResult r = mesh_model(fit.model, {.max_error = bound, .progress = {}});
  std::cout << "radar: " << fit.model.slims.size() << " patches; mesh " << r.mesh.face_count() << " triangles, max "
            << r.mesh_to_surface.max << " / " << r.surface_to_mesh.max << " (bound " << bound << "), "
            << r.refinements << " doublings, " << r.faces_left_out << " faces left out, " << r.fin_triangles
            << " sheet triangles\n";
  EXPECT_TRUE(r.within) << r.mesh_to_surface.max << " / " << r.surface_to_mesh.max;
  EXPECT_GT(r.faces_left_out, 0u);
  EXPECT_GT(r.fin_triangles, 0u);
}

/// The kitten fitted from its 5,210 points alone at 1e-3 (fitted once per run; null without the data).
const Model* kitten_points_fit() {
  static const std::optional<Model> model = []() -> std::optional<Model> {
    const std::filesystem::path file = std::filesystem::path(QUADRIX_DATASETS) / "points" / "kitten.xyz";
    if (!std::filesystem::exists(file)) return std::nullopt;
    return fit_slim(read_points(file), {.max_error = 1e-3}).model;
  }();
  return model ? &*model : nullptr;
}

// A twisted quad as one tetrahedron patch (convert quads: the bilinear patch through the
// tetrahedron's four corners). At the first level the lattice is the corners, on the surface: no
// triangle. The doublings must go on from there (the empty mesh was kept, reported as "max
// error 0" with exit 7), and a mesh with no triangle never counts as near the surface. At its two
// corners on the positive side the patch hugs the tetrahedron's faces: lattice triangles of three
// nodes on the surface are made there too (those corners were left open, 0.045 from the mesh).
// (Since tetrahedra are cut where their lattice would leave the surface, this quad's first level
// is no longer empty; a quad twisted 1,000 times less, left uncut, still is.)
TEST(ToMesh, TwistedQuadMeshedPastAnEmptyFirstLevel) {
  const auto quad = [](double twist) {
    PolygonMesh q;
    q.vertices = {{0, 0, 0}, {1, 0, 0}, {1, 1, twist}, {0, 1, 0}};
    q.add_face(std::vector<int>{0, 1, 2, 3});
    return convert_quads(q).model;
  };
  const Model m = quad(0.3);
  ASSERT_EQ(m.tets.size(), 1u);
  const ToMeshResult first = mesh_model(quad(3e-4), {.max_refinements = 0, .progress = {}});
  EXPECT_EQ(first.mesh.face_count(), 0u) << "the case no longer starts empty";
  EXPECT_FALSE(first.within);
  EXPECT_TRUE(std::isinf(first.max_error())) << "an empty mesh reported " << first.max_error() << " from the surface";
  const ToMeshResult r = mesh_model(m, {.max_refinements = 4, .progress = {}});
  std::cout << "twisted quad: " << r.mesh.face_count() << " triangles after " << r.refinements << " doublings, max "
            << r.mesh_to_surface.max << " / " << r.surface_to_mesh.max << ", bound " << r.bound << "\n";
  EXPECT_TRUE(r.within) << "max " << r.max_error() << ", bound " << r.bound;
  EXPECT_GT(r.mesh.face_count(), 100u);
  for (const auto& v : r.mesh.vertices) ASSERT_NEAR(v.z(), 0.3 * v.x() * v.y(), 1e-9) << "a vertex off the patch";
  // Consistently oriented (each directed edge used once, every normal on the patch's positive
  // side, +z here), open edges only along the quad's own edges.
  std::map<std::pair<int, int>, int> uses, directed;
  for (std::size_t f = 0; f < r.mesh.face_count(); ++f) {
    const auto v = r.mesh.face(f);
    const Eigen::Vector3d& a = r.mesh.vertices[v[0]];
    const Eigen::Vector3d n = (r.mesh.vertices[v[1]] - a).cross(r.mesh.vertices[v[2]] - a);
    const Eigen::Vector3d c = (a + r.mesh.vertices[v[1]] + r.mesh.vertices[v[2]]) / 3.0;
    EXPECT_GT(n.dot(Eigen::Vector3d(-0.3 * c.y(), -0.3 * c.x(), 1.0)), 0.0) << "a triangle facing the wrong way";
    for (int i = 0; i < 3; ++i) ++uses[std::minmax(v[i], v[(i + 1) % 3])], ++directed[{v[i], v[(i + 1) % 3]}];
  }
  for (const auto& [e, n] : directed) EXPECT_EQ(n, 1) << "a directed edge used twice";
  for (const auto& [e, n] : uses)
    if (n != 2)
      for (const int v : {e.first, e.second}) {
        const Eigen::Vector3d& x = r.mesh.vertices[v];
        EXPECT_NEAR(std::min({x.x(), x.y(), 1 - x.x(), 1 - x.y()}), 0.0, 1e-9) << "open edge inside the quad";
      }
}

/// A 2 × 2 × 1 box of quads about `centre`: its top's middle vertex lifted by `lift` (four curved
/// quads), the rest flat; counter-clockwise from outside.
PolygonMesh quad_box(const Eigen::Vector3d& centre, double lift) {
  PolygonMesh m;
  std::map<std::array<int, 3>, int> id;
  const auto v = [&](int x, int y, int z) {
    const auto [it, added] = id.emplace(std::array<int, 3>{x, y, z}, static_cast<int>(m.vertices.size()));
    if (added) m.vertices.push_back(centre + Eigen::Vector3d(x, y, z == 1 && x == 0 && y == 0 ? 1 + lift : z));
    return it->second;
  };
  const auto quad = [&](int a, int b, int c, int d) { m.add_face(std::vector<int>{a, b, c, d}); };
  for (int i = -1; i < 1; ++i)
    for (int j = -1; j < 1; ++j) {
      quad(v(i, j, 1), v(i + 1, j, 1), v(i + 1, j + 1, 1), v(i, j + 1, 1));       // top, +z
      quad(v(i, j, -1), v(i, j + 1, -1), v(i + 1, j + 1, -1), v(i + 1, j, -1));   // bottom, -z
    }
  for (int i = -1; i < 1; ++i) {
    quad(v(i, -1, -1), v(i + 1, -1, -1), v(i + 1, -1, 1), v(i, -1, 1));  // -y
    quad(v(i + 1, 1, -1), v(i, 1, -1), v(i, 1, 1), v(i + 1, 1, 1));      // +y
    quad(v(1, i, -1), v(1, i + 1, -1), v(1, i + 1, 1), v(1, i, 1));      // +x
    quad(v(-1, i + 1, -1), v(-1, i, -1), v(-1, i, 1), v(-1, i + 1, 1));  // -x
  }
  return m;
}

/// Closed and consistently oriented: every edge in two triangles, once each way.
void expect_closed_oriented(const PolygonMesh& m) {
  std::map<std::pair<int, int>, int> directed;
  for (std::size_t f = 0; f < m.face_count(); ++f) {
    const auto t = m.face(f);
    for (int i = 0; i < 3; ++i) ++directed[{t[i], t[(i + 1) % 3]}];
  }
  int bad = 0;
  for (const auto& [e, n] : directed)
    if ((n != 1 || !directed.count({e.second, e.first})) && bad++ < 5) ADD_FAILURE() << "edge " << e.first << "-" << e.second;
  EXPECT_EQ(bad, 0);
}

// Each tetrahedron is meshed on its own lattice: a flat triangle's on the cross-section of its
// clip tetrahedron, coarser than a curved quad's along a shared side, and each makes its own
// vertices (in a compact .qxm, float32 corners off by up to 5e-8 of the diagonal). The pieces
// are joined where they coincide: a box of flat quads read back from a compact file is 8
// vertices and 12 triangles, closed (it had 36 vertices and 36 open edges); with a curved top,
// closed, its flat sides split where the curved quads' finer lattice meets them.
TEST(ToMesh, PiecesMeshedApartAreClosedAtTheirSeams) {
  {
    const std::filesystem::path file = std::filesystem::temp_directory_path() /
                                       ("quadrix_seams_" + std::to_string(::getpid()) + ".qxm");
    const Model converted = convert_quads(quad_box(Eigen::Vector3d(100, 50, 20), 0.0)).model;
    EXPECT_EQ(write_model(converted, file).encoding, ModelEncoding::compact);
    const Model m = read_model(file);
    std::filesystem::remove(file);
    const ToMeshResult r = mesh_model(m);
    EXPECT_TRUE(r.within);
    EXPECT_EQ(r.open_edges, 0u);
    EXPECT_EQ(r.mesh.vertices.size(), 18u);  // the box's own vertices, no copies
    expect_closed_oriented(r.mesh);
    EXPECT_NEAR(signed_volume(r.mesh), 8.0, 1e-5);
    // A vertex on the box's edges and corners takes its faces' angle-weighted normal (one drawn
    // normal there, one face's, was 90° off the others): at most the corner's 54.7° off any of
    // its faces; a vertex inside a side keeps the side's own.
    ASSERT_EQ(r.mesh.normals.size(), r.mesh.vertices.size());
    for (std::size_t f = 0; f < r.mesh.face_count(); ++f) {
      const auto t = r.mesh.face(f);
      const Eigen::Vector3d n =
          (r.mesh.vertices[t[1]] - r.mesh.vertices[t[0]]).cross(r.mesh.vertices[t[2]] - r.mesh.vertices[t[0]]).normalized();
      for (const int v : t) EXPECT_GT(r.mesh.normals[v].dot(n), std::cos(55.0 * std::numbers::pi / 180)) << "vertex " << v;
    }
  }
  {
    // Doubled: a quad mesh's tetrahedra meet only along edges, so no lattice rounds cut them apart
    // (they opened the seams: beast 6 -> 10,602 open edges).
    const Model m = convert_quads(quad_box(Eigen::Vector3d(0, 0, 0), 0.4)).model;
    const ToMeshResult r = mesh_model(m, {.max_error = 1e-3, .progress = {}});
    std::cout << "curved box: " << r.mesh.face_count() << " triangles after " << r.refinements << " doublings, max "
              << r.max_error() << ", " << r.open_edges << " open edges\n";
    EXPECT_TRUE(r.within) << r.max_error();
    EXPECT_GT(r.refinements, 0);
    EXPECT_EQ(r.lattice_rounds, 0);
    EXPECT_EQ(r.open_edges, 0u);
    expect_closed_oriented(r.mesh);
    EXPECT_GT(signed_volume(r.mesh), 8.0);
  }
}

// The kitten fitted from its points alone at 1e-3: its blend steps between sheets farther apart
// than the blend's push (over its noisy scanned base) and draws lone patches' rims running on as
// fins; a closed mesh (open_parts off: no faces left out, no sheets) bridges the steps whatever
// the grid (mesh -> surface about 3 bounds), so a doubling that does not halve the larger maximum
// stops the doublings instead of spending millions of triangles on them (before: every doubling
// tried, 6.9M triangles in 224 s). With open parts the kitten now meshes within the bound at the
// first grid (ToMesh.OpenWhereNoClosedSurfaceHoldsTheDrawnOne).
TEST(ToMesh, DoublingsStopWhereTheyDoNotBringTheMaximumDown) {
  const Model* kitten = kitten_points_fit();
  if (!kitten) GTEST_SKIP() << "kitten.xyz not found";
  const ToMeshResult r = mesh_model(*kitten, {.max_refinements = 2, .open_parts = false, .progress = {}});
  std::cout << "kitten: " << kitten->slims.size() << " patches; mesh " << r.mesh.face_count() << " triangles after "
            << r.refinements << " doublings, max " << r.mesh_to_surface.max << " / " << r.surface_to_mesh.max << ", bound "
            << r.bound << "\n";
  if (r.within) GTEST_SKIP() << "this fit's blend is within the bound: nothing to stop";
  EXPECT_LT(r.refinements, 2) << "doublings that do not bring the maximum down should stop";
  EXPECT_LT(r.mesh.face_count(), 1'000'000u);
  EXPECT_GT(r.surface_to_mesh.samples, 0u) << "the mesh kept is measured both ways";
}

// The same kitten's fins (a patch's rim drawn alone, 6 bounds from the closed mesh) get open
// sheets of their own: the drawn surface comes within 2.1 bounds of the mesh (6.3 without them);
// the faces over its cracks (nothing drawn, 3.1 bounds from the mesh's samples) are left out.
// (The 663-patch fit of the points in Morton order: 2.59 bounds with the sheets, 5.73 without,
// 29 pixels beyond the bound against 768; the test asked ≤ 2.5 bounds, then at most half the
// distance without them and within 3 bounds. The 659-patch fit, since a boundary point's disc
// distance is a distance: 2.60 bounds with the sheets, 4.88 without, 32 pixels beyond against
// 710; so at most 0.6 of the distance without them.)
TEST(ToMesh, OpenWhereNoClosedSurfaceHoldsTheDrawnOne) {
  const Model* kitten = kitten_points_fit();
  if (!kitten) GTEST_SKIP() << "kitten.xyz not found";
  const ToMeshResult with = mesh_model(*kitten, {.max_refinements = 0, .progress = {}});
  const ToMeshResult without = mesh_model(*kitten, {.max_refinements = 0, .open_parts = false, .progress = {}});
  std::cout << "kitten: with fin sheets (" << with.fin_rounds << " rounds, " << with.fin_triangles << " triangles) max "
            << with.mesh_to_surface.max << " / " << with.surface_to_mesh.max << ", beyond " << with.mesh_to_surface.beyond
            << " / " << with.surface_to_mesh.beyond << "; without " << without.mesh_to_surface.max << " / "
            << without.surface_to_mesh.max << ", beyond " << without.mesh_to_surface.beyond << " / "
            << without.surface_to_mesh.beyond << "; bound " << with.bound << "; mesh samples " << with.mesh_to_surface.samples
            << " / " << without.mesh_to_surface.samples << "\n";
  if (without.surface_to_mesh.max <= 2 * without.bound) GTEST_SKIP() << "this fit draws no fin beyond 2 bounds";
  EXPECT_GT(with.fin_rounds, 0);
  EXPECT_LE(with.surface_to_mesh.max, 0.6 * without.surface_to_mesh.max);
  EXPECT_LE(with.surface_to_mesh.max, 3.0 * with.bound);
  EXPECT_LT(with.surface_to_mesh.beyond * 4, without.surface_to_mesh.beyond);
  // The faces the local refinement left beyond the bound are left out too (steps of the blend:
  // on the scanned base, sheets 6.6E apart over noisy points, which a closed mesh bridges with
  // its samples 3 bounds off whatever is cut), and the drawn surface under them measured and
  // given open sheets, then its vertices moved towards the drawn points left (a blend of two
  // sheets, on neither) by up to the whole bound, and the few faces a move or a turned normal
  // leaves beyond the bound left out too: within the bound (1.01 / 1.05 bounds with moves of 0.85
  // bounds and no second leaving out; 3.1 / 3.2 closed). The fit of stop 48, whose hole checks
  // follow the points' bent discs (630 patches, 3.2e-5 of bench fit's pixels open against 640 and
  // 8.5e-5), is not meshed within it: 7 of 579,396 mesh samples and 1 of 89,545 pixels beyond,
  // at 1.36 / 1.44 bounds (exit 7 for `quadrix mesh`; more view rounds stop where they are). So
  // the test bounds how few and how far.
  EXPECT_GT(with.faces_left_out, 0u);
  EXPECT_EQ(without.faces_left_out, 0u);
  EXPECT_LE(with.mesh_to_surface.beyond, 16u) << with.mesh_to_surface.max;
  EXPECT_LE(with.surface_to_mesh.beyond, 4u) << with.surface_to_mesh.max;
  EXPECT_LE(with.mesh_to_surface.max, 1.5 * with.bound);
  EXPECT_LE(with.surface_to_mesh.max, 1.5 * with.bound);
  // Measured apart from the mesher: the drawn surface a view along each point's normal sees,
  // against the triangles (closest point); random points of the triangles against the drawn
  // surface along 13 lines. The views' pixels are wider than a face left out: this catches the
  // drawn surface under a gap they skip.
  const ReferenceScene scene(*kitten);
  TraceOptions trace;
  trace.slim = slim_blend_of(*kitten);
  const PointCloud cloud = read_points(std::filesystem::path(QUADRIX_DATASETS) / "points" / "kitten.xyz");
  const DataSurface triangles = DataSurface::from_mesh(with.mesh);
  const double reach = 4 * with.bound;
  std::vector<double> surface_side, mesh_side;
  std::size_t shaded = 0, flat_off = 0, smooth_off = 0;
  ASSERT_EQ(with.mesh.normals.size(), with.mesh.vertices.size());
  for (const Eigen::Vector3d& n : with.mesh.normals) ASSERT_NEAR(n.norm(), 1.0, 1e-9);
  // 854 of 67,686: where the normal line meets nothing near (rims) or the drawn normal turns by
  // over 45° to a neighbour's (a fin sheet meeting the surface, a step), its faces' normal.
  EXPECT_LT(with.normals_from_faces, with.mesh.vertices.size() / 50);
  for (std::size_t k = 0; k < cloud.points.size(); ++k) {
    const Eigen::Vector3d& n = cloud.normals[k];
    for (const double side : {1.0, -1.0})
      if (const auto hit = scene.trace({cloud.points[k] + side * reach * n, -side * n}, 0.0, 2 * reach, trace))
        surface_side.push_back(triangles.distance(hit->point));
  }
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> U(0, 1);
  std::vector<double> area_upto;  // faces drawn by area: the sheets' and refined faces are small
  double area = 0;
  for (std::size_t f = 0; f < with.mesh.face_count(); ++f) {
    const auto v = with.mesh.face(f);
    area += 0.5 * (with.mesh.vertices[v[1]] - with.mesh.vertices[v[0]])
                      .cross(with.mesh.vertices[v[2]] - with.mesh.vertices[v[0]])
                      .norm();
    area_upto.push_back(area);
  }
  for (int k = 0; k < 20000; ++k) {
    const std::size_t f = std::min<std::size_t>(
        std::lower_bound(area_upto.begin(), area_upto.end(), U(rng) * area) - area_upto.begin(), with.mesh.face_count() - 1);
    const auto v = with.mesh.face(f);
    double a = U(rng), b = U(rng);
    if (a + b > 1) a = 1 - a, b = 1 - b;
    const Eigen::Vector3d p = with.mesh.vertices[v[0]] + a * (with.mesh.vertices[v[1]] - with.mesh.vertices[v[0]]) +
                              b * (with.mesh.vertices[v[2]] - with.mesh.vertices[v[0]]);
    const Eigen::Vector3d n = (with.mesh.vertices[v[1]] - with.mesh.vertices[v[0]])
                                  .cross(with.mesh.vertices[v[2]] - with.mesh.vertices[v[0]])
                                  .normalized();
    if (!n.allFinite()) continue;
    const double d = nearest_along_lines(scene, trace, p, n, reach, with.bound);
    mesh_side.push_back(d < 0 ? reach : d);
    // Shading: the drawn surface's normal seen along the face's normal, against the face's own
    // normal (flat shading) and the vertex normals interpolated there (smooth shading).
    std::optional<SurfaceHit> near;
    for (const double side : {1.0, -1.0})
      if (const auto hit = scene.trace({p + side * reach * n, -side * n}, 0.0, 2 * reach, trace))
        if (!near || std::abs(hit->t - reach) < std::abs(near->t - reach)) near = hit;
    if (!near) continue;
    const Eigen::Vector3d smooth = ((1 - a - b) * with.mesh.normals[v[0]] + a * with.mesh.normals[v[1]] +
                                    b * with.mesh.normals[v[2]]).normalized();
    ++shaded;
    flat_off += std::abs(near->normal.dot(n)) < std::cos(std::numbers::pi / 6);
    smooth_off += std::abs(near->normal.dot(smooth)) < std::cos(std::numbers::pi / 6);
  }
  // The faces follow sheets that stand off each other by up to the blend's push (within the bound,
  // but tilted against the blended normal: 0.9 % of the area over 30° off, shards under flat
  // shading); the vertex normals are the drawn surface's own, so smooth shading shows what the
  // renderer draws (measured: 184 and 18 of 19,999 points).
  std::cout << "kitten: shading normal more than 30 degrees off the drawn one at " << flat_off << " (flat) and "
            << smooth_off << " (vertex normals) of " << shaded << " points\n";
  ASSERT_GT(shaded, 15000u);
  EXPECT_GT(flat_off, 0u) << "no shard to compare with: pick another model";
  EXPECT_LE(4 * smooth_off, flat_off);
  EXPECT_LE(smooth_off, shaded / 500);
  const auto quantile = [](std::vector<double> d, double q) {
    std::sort(d.begin(), d.end());
    return d[static_cast<std::size_t>(q * double(d.size() - 1))];
  };
  std::cout << "kitten, apart from the mesher: surface -> mesh p99 " << quantile(surface_side, 0.99) << " max "
            << quantile(surface_side, 1.0) << " (" << surface_side.size() << " points); mesh -> surface p99 "
            << quantile(mesh_side, 0.99) << " p99.9 " << quantile(mesh_side, 0.999) << " max " << quantile(mesh_side, 1.0)
            << "\n";
  ASSERT_GT(surface_side.size(), cloud.points.size() / 2);
  EXPECT_LE(quantile(surface_side, 0.999), with.bound);
  EXPECT_LE(quantile(surface_side, 1.0), 1.1 * with.bound);  // 0.98 bounds
  // Between the mesher's samples (vertices, edge midpoints, centroids) a triangle may lie farther:
  // 1.27 bounds at worst here (20,000 points drawn by area; p99.9 0.95 bounds), the mesher's
  // samples 1.01.
  EXPECT_LE(quantile(mesh_side, 0.99), with.bound);
  EXPECT_LE(quantile(mesh_side, 1.0), 1.4 * with.bound);
  // Its faces over cracks between balls left out: the mesh's own samples no farther, a smaller
  // share beyond (the 640-patch fit: 0.0039 against 0.0047, 767 against 805 samples; the 641-patch
  // fit: 0.00376 both, its worst sample over no crack, 775 against 786; the 666-patch fit, whose
  // holes between the points are filled: 0.00565 both, 934 of 591,605 against 916 of 536,564,
  // the fin sheets' own 11,413 triangles sampled too; the 663-patch fit: 0.00465 both, 895 of
  // 593,655 against 891 of 540,548).
  EXPECT_LE(with.mesh_to_surface.max, without.mesh_to_surface.max);
  EXPECT_LT(double(with.mesh_to_surface.beyond) / double(with.mesh_to_surface.samples),
            double(without.mesh_to_surface.beyond) / double(without.mesh_to_surface.samples));
  // The vertices of the faces left out went with them.
  std::vector<char> used(with.mesh.vertices.size(), 0);
  for (const int v : with.mesh.indices) used[static_cast<std::size_t>(v)] = 1;
  EXPECT_EQ(std::count(used.begin(), used.end(), 0), 0);
}

// Volume patches are cut (conforming longest-edge bisection) where their tetrahedron's lattice
// would leave their surface by more than a quarter of the bound, instead of refining every
// tetrahedron's lattice alike. Marschner–Lobb on a 13³ grid, iso ½, default bound: uniform
// doublings reached the bound at the 4th with 553,192 triangles (21.8 s through the CLI); now
// at the 2nd with 134,750 (3.5 s). The pieces share whole faces, so a closed surface stays
// closed: three overlapping balls of 1.3–2.1 voxels, meshed closed with 0 open edges.
TEST(ToMesh, VolumePatchesCutWhereTheirLatticeWouldLeaveTheSurface) {
  const VolumeConversion ml = convert_volume(marschner_lobb_volume(13), {.iso = 0.5});
  const ToMeshResult r = mesh_model(ml.model, {.progress = {}});
  std::cout << "Marschner-Lobb 13^3: " << ml.model.tets.size() << " patches, " << r.mesh.face_count() << " triangles after "
            << r.refinements << " doublings, max " << r.max_error() << " of " << r.bound << "\n";
  EXPECT_TRUE(r.within) << r.max_error() << " of " << r.bound;
  EXPECT_LE(r.refinements, 2);
  EXPECT_LT(r.mesh.face_count(), 250'000u);

  Volume balls;
  balls.dims = {14, 14, 14};
  const std::vector<std::pair<Eigen::Vector3d, double>> centres{
      {{4.3, 5.1, 6.2}, 1.6}, {{9.1, 8.4, 7.3}, 2.1}, {{6.7, 9.6, 4.1}, 1.3}};
  for (int z = 0; z < 14; ++z)
    for (int y = 0; y < 14; ++y)
      for (int x = 0; x < 14; ++x) {
        double f = std::numeric_limits<double>::infinity();
        for (const auto& [c, radius] : centres) f = std::min(f, (Eigen::Vector3d(x, y, z) - c).norm() - radius);
        balls.values.push_back(float(f));
      }
  const ToMeshResult b = mesh_model(convert_volume(balls, {.iso = 0.0}).model, {.progress = {}});
  EXPECT_TRUE(b.within) << b.max_error() << " of " << b.bound;
  EXPECT_EQ(b.open_edges, 0u);
  EXPECT_EQ(self_intersections(b.mesh).pairs, 0u);
}

// A noisy ball (12³ values: distance to a sphere of radius 4 plus noise of ±1.2, a sine hash):
// its tetrahedra's quadrics hold small blobs and saddles the sag estimate does not see. Doubling
// every piece's lattice stops after two doublings, 4 bounds off (not converging); the lattice
// rounds cut only the pieces whose faces, or the drawn points nearest them, stay beyond the bound,
// and reach it without a doubling.
TEST(ToMesh, ANoisyVolumeIsCutWhereItsMeshLeftTheBound) {
  constexpr int n = 12;
  Volume v;
  v.dims = {n, n, n};
  const Eigen::Vector3d c = Eigen::Vector3d::Constant((n - 1) / 2.0) + Eigen::Vector3d(0.2, -0.3, 0.1);
  for (int z = 0; z < n; ++z)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        const double h = std::sin(x * 12.9898 + y * 78.233 + z * 37.719) * 43758.5453;
        v.values.push_back(float(0.33 * n - (Eigen::Vector3d(x, y, z) - c).norm() + 1.2 * (2 * (h - std::floor(h)) - 1)));
      }
  const Model model = convert_volume(v, {.iso = 0.0}).model;
  const ToMeshResult without = mesh_model(model, {.lattice_rounds = 0, .progress = {}});
  const ToMeshResult with = mesh_model(model, {.progress = {}});
  std::cout << "noisy ball: " << model.tets.size() << " patches; without lattice rounds " << without.mesh.face_count()
            << " triangles after " << without.refinements << " doublings, max " << without.max_error() << "; with "
            << with.lattice_rounds << " rounds " << with.mesh.face_count() << " triangles after " << with.refinements
            << " doublings, max " << with.max_error() << " of " << with.bound << "\n";
  EXPECT_FALSE(without.within) << without.max_error() << " of " << without.bound;
  EXPECT_TRUE(with.within) << with.max_error() << " of " << with.bound;
  EXPECT_GE(with.lattice_rounds, 1);
  EXPECT_EQ(with.refinements, 0);
  EXPECT_LT(with.mesh.face_count(), without.mesh.face_count());
  EXPECT_EQ(with.open_edges, 0u);
  EXPECT_EQ(self_intersections(with.mesh).pairs, 0u);
}
