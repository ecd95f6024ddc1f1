// Skin surfaces: ball readers, CGAL mixed complex → (TetGen) tetrahedra → clipped quadrics
// (issue 6, items 1–3 and 7).
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <string>
#include <unistd.h>
#include <unordered_map>
#include <vector>

#include <gtest/gtest.h>
#include <tbb/parallel_for.h>

#include "convert/balls.h"
#include "convert/skin.h"
#include "convert/tetrahedralize.h"
#include "convert/to_mesh.h"
#include "core/bounds.h"
#include "core/camera.h"
#include "core/culling.h"
#include "core/error.h"
#include "core/model_io.h"
#include "core/reference.h"
#include "tests/support.h"

namespace quadrix {
namespace {

namespace fs = std::filesystem;
using Eigen::Vector3d;

const fs::path kData = fs::path(QUADRIX_DATASETS);

using test_support::TempDir;

// ---------------------------------------------------------------------------------------------
// Readers

class BallIo : public TempDir {};

TEST_F(BallIo, SharedMoleculesAndBallFiles) {
  if (!fs::exists(kData / "molecules")) GTEST_SKIP() << "data set folder not found: " << kData.string();
  const auto caffeine = read_balls(kData / "balls/caffeine.cin");
  EXPECT_EQ(caffeine.size(), 23u);
  EXPECT_NEAR(caffeine[0].radius, std::sqrt(0.46875), 1e-12);
  const auto tii = read_balls(kData / "molecules/1tii.pdb");
  EXPECT_GT(tii.size(), 5500u);
  EXPECT_LE(tii.size(), 5684u);  // altLoc B..Z are skipped
  EXPECT_EQ(tii[0].element, "N");
  EXPECT_DOUBLE_EQ(tii[0].radius, 1.55);
  EXPECT_EQ(tii[0].colour, (Rgb{48, 80, 248}));
  EXPECT_EQ(tii[0].centre, Vector3d(42.053, -9.336, 17.867));
  const auto cov = read_balls(kData / "molecules/1tii.pdb", {.radii = RadiusTable::covalent});
  EXPECT_DOUBLE_EQ(cov[0].radius, 0.71);
  // --no-water: exactly the HOH atoms (residue name, columns 18-20) are left out.
  std::ifstream in(kData / "molecules/1tii.pdb");
  std::size_t waters = 0;
  for (std::string line; std::getline(in, line);)
    waters += (line.rfind("HETATM", 0) == 0 || line.rfind("ATOM  ", 0) == 0) && line.substr(17, 3) == "HOH";
  ASSERT_GT(waters, 100u);
  const auto dry = read_balls(kData / "molecules/1tii.pdb", {.water = false});
  EXPECT_EQ(dry.size(), tii.size() - waters);
  EXPECT_EQ(dry[0].centre, tii[0].centre);
}

TEST_F(BallIo, MalformedRecordsAreFormatErrorsWithLineNumbers) {
  const auto expect_format = [&](const std::string& name, const std::string& text, const std::string& needle) {
    try {
      read_balls(write(name, text));
      ADD_FAILURE() << name << ": no FormatError; expected one mentioning '" << needle << "'";
    } catch (const FormatError& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
  };
  const std::string ok = "ATOM      1  N   GLY D   1      42.053  -9.336  17.867  1.00 43.86           N  \n";
  expect_format("a.pdb", "HEADER x\n" + ok + "ATOM      2  CA  GLY D   1      42.7x4 -10.253  18.851  1.00 41.67           C\n",
                "a.pdb:3: x (columns 31-38)");
  expect_format("b.pdb", ok + "ATOM      2  CA  GLY D   1      42.704 -10.253\n", "b.pdb:2: ATOM   record has");
  expect_format("c.pdb", ok + ok, "atoms with serial numbers 1 and 1: duplicate ball");
  expect_format("d.pdb", "HEADER nothing\n", "no atoms");
  expect_format("e.cin", "0 0 0 1\n1 0 0 0\n", "e.cin:2:8: weight (squared radius) 0 must be > 0");
  expect_format("f.xyzr", "0 0 0 1\n# c\n1 0 0 -2\n", "f.xyzr:3:9: radius -2 must be > 0");
  expect_format("g.cin", "0 0 0\n", "g.cin:1:6: expected 4 numbers");
  expect_format("h.cin", "0 0 0 nan\n", "not a finite number");
  EXPECT_THROW(read_balls(write("x.txt", "0 0 0 1\n")), InvalidInput);
  EXPECT_THROW(read_balls(dir_ / "missing.pdb"), IoError);
}

// ---------------------------------------------------------------------------------------------
// TetGen safety

TEST(Tetrahedralize, ConvexCellsValidatedAndIsolated) {
  std::vector<Vector3d> cube;
  for (int c = 0; c < 8; ++c) cube.emplace_back(c & 1, (c >> 1) & 1, (c >> 2) & 1);
  std::vector<Vector3d> octa{{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}, {0, 0, 0.5}};
  const std::vector<std::vector<Vector3d>> cells{cube, octa};
  const auto result = tetrahedralize_convex_cells(cells);
  const auto& tets = result.cells;
  ASSERT_EQ(tets.size(), 2u);
  EXPECT_TRUE(result.failed.empty());
  const double expected[2] = {1.0, 4.0 / 3.0};
  for (int c = 0; c < 2; ++c) {
    double vol = 0;
    for (const auto& t : tets[c]) {
      const auto& p = cells[c];
      const double v = (p[t[1]] - p[t[0]]).cross(p[t[2]] - p[t[0]]).dot(p[t[3]] - p[t[0]]) / 6;
      EXPECT_GT(v, 0);
      vol += v;
    }
    EXPECT_NEAR(vol, expected[c], 1e-12) << "cell " << c;
  }
  // Invalid cells never reach TetGen.
  const std::vector<std::vector<Vector3d>> flat{{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}, {0.5, 0.5, 0}}};
  EXPECT_THROW(tetrahedralize_convex_cells(flat), InvalidInput);
  const std::vector<std::vector<Vector3d>> dup{{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 0, 1e-14}}};
  EXPECT_THROW(tetrahedralize_convex_cells(dup), InvalidInput);
  const std::vector<std::vector<Vector3d>> nan{{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, std::nan("")}}};
  EXPECT_THROW(tetrahedralize_convex_cells(nan), InvalidInput);
}

// ---------------------------------------------------------------------------------------------
// Skin surfaces

// A point of each patch: a point of its tetrahedron projected onto the quadric (Newton along the
// gradient), kept when it stays inside the tetrahedron.
std::vector<Vector3d> patch_points(const Model& m) {
  std::vector<Vector3d> out;
  for (const auto& t : m.tets) {
    const Vector3d g = t.centroid();
    for (int s = 0; s < 5; ++s) {
      Vector3d y = s == 4 ? Vector3d::Zero() : Vector3d(0.5 * (t.corners[s] - g));
      for (int it = 0; it < 40; ++it) {
        const Vector3d grad = t.quadric.gradient(y);
        if (grad.squaredNorm() == 0) break;
        y -= t.quadric.eval(y) * grad / grad.squaredNorm();
      }
      if (std::abs(t.quadric.eval(y)) > 1e-12 * std::max(1.0, t.quadric.max_abs_coefficient())) continue;
      // Inside the tetrahedron (barycentric coordinates ≥ −1e-9)?
      Eigen::Matrix3d T;
      T << t.corners[1] - t.corners[0], t.corners[2] - t.corners[0], t.corners[3] - t.corners[0];
      const Vector3d l = T.inverse() * (y + g - t.corners[0]);
      if (l.minCoeff() >= -1e-9 && l.sum() <= 1 + 1e-9) out.push_back(y + g);
    }
  }
  return out;
}

// A skin's tetrahedra are slivers and its mixed cells meet along faces triangulated differently
// on each side, so each tetrahedron's own lattice meshed it outside the bound and open (these three
// balls of caffeine at 3e-3 of the diagonal: 0.0248 for a bound of 0.0225; all of caffeine at
// 1e-3: 0.0612 for 0.0129, 38,942 open edges). A closed tetrahedron model is meshed on one grid
// whose nodes the drawn surface labels: within the bound, closed and consistently oriented.
TEST(ConvertSkin, MeshedOnOneGridWithinItsBoundAndClosed) {
  const std::vector<Ball> balls = {{{-3.3804130, -1.1272367, 0.5733036}, 0.46875, {255, 0, 0}, ""},
                                   {{0.9668296, -1.0737425, -0.8198227}, 0.675, {0, 255, 0}, ""},
                                   {{0.0567293, 0.8527195, 0.3923156}, 0.81675, {0, 0, 255}, ""}};
  Model skin = convert_skin(balls).model;
  skin.metadata[kClosedKey] = "1";  // as `convert skin` marks it: a skin bounds the union of its balls
  const double bound = 3e-3 * bounds(skin).diagonal();
  const ToMeshResult r = mesh_model(skin, {.max_error = bound, .progress = {}});
  std::printf("3-ball skin: %zu tetrahedra; mesh %zu triangles, max %.3g / %.3g (bound %.3g), %zu open edges, %s\n",
              skin.tets.size(), r.mesh.face_count(), r.mesh_to_surface.max, r.surface_to_mesh.max, bound, r.open_edges,
              r.on_grid ? "on the grid" : "on the tetrahedra's lattices");
  EXPECT_TRUE(r.on_grid);
  EXPECT_TRUE(r.within) << r.max_error();
  EXPECT_EQ(r.open_edges, 0u);
  std::map<std::pair<int, int>, int> directed;
  double volume = 0;
  for (std::size_t f = 0; f < r.mesh.face_count(); ++f) {
    const auto t = r.mesh.face(f);
    for (int i = 0; i < 3; ++i) ++directed[{t[i], t[(i + 1) % 3]}];
    volume += r.mesh.vertices[t[0]].dot(r.mesh.vertices[t[1]].cross(r.mesh.vertices[t[2]])) / 6.0;
  }
  int bad = 0;
  for (const auto& [e, n] : directed) bad += n != 1 || !directed.count({e.second, e.first});
  EXPECT_EQ(bad, 0) << "edges not used once each way";
  // Outward: the enclosed volume is positive, at least the largest ball's.
  EXPECT_GT(volume, 4.0 / 3.0 * M_PI * std::pow(0.81675, 3));
  EXPECT_EQ(r.mesh.colours.size(), r.mesh.vertices.size()) << "the skin's colours carried over";
}

TEST(ConvertSkin, OneBallIsTheShrunkSphere) {
  // CGAL grows the balls (weights r²/s), so the skin of one ball (c, r) is the sphere of radius r
  // for every shrink factor s.
  const Ball b{{1.5, -2, 0.25}, 1.3, {255, 0, 0}, "O"};
  for (const auto mode : {SkinTetrahedra::regular, SkinTetrahedra::tetgen, SkinTetrahedra::cgal}) {
    for (const double s : {0.3, 0.5, 0.9}) {
      const SkinConversion conv = convert_skin({b}, {.shrink = s, .tetrahedra = mode});
      ASSERT_GT(conv.model.tets.size(), 0u);
      EXPECT_LT(conv.max_quadric_disagreement, 1e-12);
      const auto pts = patch_points(conv.model);
      ASSERT_GT(pts.size(), conv.model.tets.size());
      double worst = 0;
      for (const auto& p : pts) worst = std::max(worst, std::abs((p - b.centre).norm() - b.radius));
      EXPECT_LT(worst, 1e-12) << "shrink " << s;
      for (const auto& t : conv.model.tets) EXPECT_EQ(t.colour, b.colour);
    }
  }
}

// Distance from p to triangle abc (Ericson, Real-Time Collision Detection §5.1.5).
double point_triangle(const Vector3d& p, const Vector3d& a, const Vector3d& b, const Vector3d& c) {
  const Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return (p - a).norm();
  const Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return (p - b).norm();
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return (p - (a + d1 / (d1 - d3) * ab)).norm();
  const Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return (p - c).norm();
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return (p - (a + d2 / (d2 - d6) * ac)).norm();
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
    return (p - (b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b))).norm();
  const double denom = 1 / (va + vb + vc);
  return (p - (a + ab * (vb * denom) + ac * (vc * denom))).norm();
}

// Uniform grid of boxes (triangles or tetrahedra) for nearest queries.
struct Grid {
  Vector3d lo;
  double h;
  std::array<int, 3> n;
  std::vector<std::vector<int>> cells;
  Grid(const Box3& box, double cell) : lo(box.min), h(cell) {
    for (int a = 0; a < 3; ++a) n[a] = std::max(1, int(std::ceil((box.max[a] - box.min[a]) / h)) + 1);
    cells.resize(static_cast<std::size_t>(n[0]) * n[1] * n[2]);
  }
  std::array<int, 3> at(const Vector3d& p) const {
    std::array<int, 3> c;
    for (int a = 0; a < 3; ++a) c[a] = std::clamp(int(std::floor((p[a] - lo[a]) / h)), 0, n[a] - 1);
    return c;
  }
  std::vector<int>& cell(const std::array<int, 3>& c) { return cells[(std::size_t(c[2]) * n[1] + c[1]) * n[0] + c[0]]; }
  const std::vector<int>& cell(const std::array<int, 3>& c) const {
    return cells[(std::size_t(c[2]) * n[1] + c[1]) * n[0] + c[0]];
  }
  void insert(int id, const Box3& b) {
    const auto a = at(b.min), z = at(b.max);
    for (int k = a[2]; k <= z[2]; ++k)
      for (int j = a[1]; j <= z[1]; ++j)
        for (int i = a[0]; i <= z[0]; ++i) cell({i, j, k}).push_back(id);
  }
};

struct TwoSided {
  double ours_to_cgal = 0;  // max over points of our patches of the distance to CGAL's mesh
  double cgal_to_ours = 0;  // max over CGAL's mesh vertices of the distance to our surface
  std::size_t cgal_vertices_outside = 0;  // CGAL vertices in no kept tetrahedron
  std::vector<double> cgal_distances;
};

// Two-sided distance between our patches and CGAL's mesh. Ours → CGAL: exact point–triangle
// distance within a search radius. CGAL → ours: first-order distance |f|/‖∇f‖ of the patch whose
// tetrahedron holds the vertex (CGAL's vertices lie on the surface to its bisection tolerance).
TwoSided compare_with_cgal(const Model& m, const TriangleMesh& mesh, double size) {
  Box3 box = bounds(m);
  for (const auto& v : mesh.vertices) box.extend(v);
  const double h = size / 40;
  Grid tri(box, h), tet(box, h);
  for (int t = 0; t < static_cast<int>(mesh.triangles.size()); ++t) {
    Box3 b;
    for (const int v : mesh.triangles[t]) b.extend(mesh.vertices[v]);
    tri.insert(t, b);
  }
  for (int t = 0; t < static_cast<int>(m.tets.size()); ++t) tet.insert(t, bounds(m.tets[t]));
  TwoSided r;
  const auto pts = patch_points(m);
  std::vector<double> d1(pts.size());
  tbb::parallel_for(std::size_t(0), pts.size(), [&](std::size_t i) {
    double best = std::numeric_limits<double>::infinity();
    const auto c = tri.at(pts[i]);
    for (int k = c[2] - 1; k <= c[2] + 1; ++k)
      for (int j = c[1] - 1; j <= c[1] + 1; ++j)
        for (int a = c[0] - 1; a <= c[0] + 1; ++a) {
          if (a < 0 || j < 0 || k < 0 || a >= tri.n[0] || j >= tri.n[1] || k >= tri.n[2]) continue;
          for (const int t : tri.cell({a, j, k})) {
            const auto& f = mesh.triangles[t];
            best = std::min(best, point_triangle(pts[i], mesh.vertices[f[0]], mesh.vertices[f[1]], mesh.vertices[f[2]]));
          }
        }
    d1[i] = best;
  });
  for (const double d : d1) r.ours_to_cgal = std::max(r.ours_to_cgal, d);
  for (const auto& v : mesh.vertices) {
    double best = std::numeric_limits<double>::infinity();
    for (const int t : tet.cell(tet.at(v))) {
      const auto& p = m.tets[t];
      Eigen::Matrix3d T;
      T << p.corners[1] - p.corners[0], p.corners[2] - p.corners[0], p.corners[3] - p.corners[0];
      const Vector3d l = T.inverse() * (v - p.corners[0]);
      if (l.minCoeff() < -1e-7 || l.sum() > 1 + 1e-7) continue;
      best = std::min(best, p.quadric.taubin_distance(v - p.centroid()));
    }
    if (std::isinf(best)) ++r.cgal_vertices_outside;
    else r.cgal_to_ours = std::max(r.cgal_to_ours, best), r.cgal_distances.push_back(best);
  }
  return r;
}

// Reference renders of two models (64² CPU ray caster, framed on the balls): pixels whose
// coverage differs or whose distance differs by more than 1e-6 of the size.
std::size_t render_difference(const Model& ma, const Model& mb, const std::vector<Ball>& balls, double size,
                              std::size_t* covered = nullptr) {
  Box3 frame;
  for (const auto& b : balls) frame.extend(b.centre + Vector3d::Constant(b.radius)), frame.extend(b.centre - Vector3d::Constant(b.radius));
  const Camera cam = frame_box(frame, {.width = 64, .height = 64});
  ReferenceRenderOptions o;
  const ReferenceScene a(ma), b(mb);
  const ReferenceImage ia = render_reference(a, cam, o), ib = render_reference(b, cam, o);
  std::size_t differ = 0, cov = 0;
  for (int i = 0; i < 64 * 64; ++i) {
    cov += ia.coverage[i];
    differ += ia.coverage[i] != ib.coverage[i] ||
              (ia.coverage[i] && std::abs(ia.distance[i] - ib.distance[i]) > 1e-6 * size);
  }
  if (covered) *covered = cov;
  return differ;
}

void expect_round_trip(const Model& m) {
  const fs::path tmp = fs::temp_directory_path() / ("quadrix_skin_" + std::to_string(::getpid()) + ".qxm");
  // Compact (the default) may leave out slivers float32 flattens: it counts them, at most 1 in 1,000.
  const WriteModelResult written = write_model(m, tmp);
  const Model back = read_model(tmp);
  fs::remove(tmp);
  EXPECT_LE(written.dropped_tets * 1000, m.tets.size());
  ASSERT_EQ(back.tets.size() + written.dropped_tets, m.tets.size());
  for (const auto& t : m.tets) ASSERT_TRUE(t.colour.has_value());
}

void print_percentiles(const char* what, std::vector<double> d, double size) {
  std::sort(d.begin(), d.end());
  if (!d.empty())
    std::printf("  %s CGAL→ours percentiles 50/99/99.9/100: %.3g %.3g %.3g %.3g (of the size)\n", what,
                d[d.size() / 2] / size, d[d.size() * 99 / 100] / size, d[d.size() * 999 / 1000] / size, d.back() / size);
}

// Our patch points lie on CGAL's subdivided, chord-limited mesh; CGAL's vertices lie on our
// surface to its bisection tolerance, inside our tetrahedra.
void expect_close_to_cgal_mesh(const TwoSided& d, double size, double ours_to_cgal) {
  EXPECT_LT(d.ours_to_cgal, ours_to_cgal * size);
  auto cd = d.cgal_distances;
  std::sort(cd.begin(), cd.end());
  ASSERT_FALSE(cd.empty());
  EXPECT_LT(cd[cd.size() * 999 / 1000], 1e-4 * size);
  EXPECT_LT(cd.back(), 1e-2 * size);
  EXPECT_EQ(d.cgal_vertices_outside, 0u);
}

struct MoleculeCheck {
  int subdivisions = 3;   // of CGAL's reference mesh
  // Bound on ours→CGAL (of the size): the 1e-3 needs CGAL's mesh subdivided 3 times (its
  // chords, not our surface, set this direction: CGAL→ours stays ~1e-5).
  double ours_to_cgal = 1e-3;
  bool tetgen = true;     // TetGen mode too (one child process per crossed mixed cell: small molecules)
  bool cgal_mesh = true;  // CGAL's mesh_skin_surface_3 (well over 10 minutes for thousands of atoms)
};

// Our mixed complex (regular mode, the default) against CGAL's Skin_surface_3: its triangulated
// mixed complex (quadrics checked against CGAL's value()) must render identically, and both lie on
// CGAL's own mesh of the skin.
void check_molecule(const fs::path& file, MoleculeCheck check) {
  if (!fs::exists(file)) GTEST_SKIP() << "data set not found: " << file.string();
  const auto balls = read_balls(file);
  Box3 box;
  for (const auto& b : balls) box.extend(b.centre);
  const double size = box.diagonal();
  const auto seconds = [](auto t0) { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(); };
  auto t0 = std::chrono::steady_clock::now();
  const SkinConversion rg = convert_skin(balls, {.source = file.filename().string()});
  const double rg_s = seconds(t0);
  t0 = std::chrono::steady_clock::now();
  const SkinConversion cg = convert_skin(balls, {.tetrahedra = SkinTetrahedra::cgal});
  const double cg_s = seconds(t0);
  std::printf("%s: %zu balls; regular: %zu mixed cells (%zu crossed), %zu tets → %zu patches, %.2f s; "
              "CGAL: %zu mixed cells (%zu crossed), %zu tets (%zu crossed) → %zu patches, %.2f s, quadric "
              "disagreement %.2g\n",
              file.filename().c_str(), balls.size(), rg.mixed_cells, rg.mixed_cells_crossed, rg.mixed_tets,
              rg.model.tets.size(), rg_s, cg.mixed_cells, cg.mixed_cells_crossed, cg.cgal_tets, cg.cgal_tets_crossed,
              cg.model.tets.size(), cg_s, cg.max_quadric_disagreement);
  EXPECT_EQ(rg.mixed_cells, cg.mixed_cells);
  EXPECT_LT(cg.max_quadric_disagreement, 1e-9);
  expect_round_trip(rg.model);
  expect_round_trip(cg.model);
  std::size_t covered = 0;
  EXPECT_LE(render_difference(rg.model, cg.model, balls, size, &covered), 2u)
      << "our mixed complex and CGAL's render differently";
  EXPECT_GT(covered, 64u * 64u / 10);

  std::optional<SkinConversion> tg;
  if (check.tetgen) {
    tg = convert_skin(balls, {.tetrahedra = SkinTetrahedra::tetgen, .source = file.filename().string()});
    std::printf("  TetGen: %zu tets → %zu patches, %zu slivers skipped, failed on %zu cells, %.2f s\n", tg->tetgen_tets,
                tg->model.tets.size(), tg->slivers_skipped, tg->tetgen_failed_cells, tg->tetgen_seconds);
    expect_round_trip(tg->model);
    EXPECT_LE(render_difference(tg->model, cg.model, balls, size), 2u) << "TetGen and CGAL tetrahedra render differently";
  }
  if (!check.cgal_mesh) return;
  const TriangleMesh mesh = cgal_skin_mesh(balls, 0.5, check.subdivisions);
  const TwoSided dr = compare_with_cgal(rg.model, mesh, size), dc = compare_with_cgal(cg.model, mesh, size);
  std::printf("  vs CGAL mesh (%zu triangles, %d subdivisions), of the size %.3g: regular ours→CGAL %.3g, CGAL→ours "
              "%.3g, %zu CGAL vertices outside; CGAL tets ours→CGAL %.3g, CGAL→ours %.3g, %zu outside\n",
              mesh.triangles.size(), check.subdivisions, size, dr.ours_to_cgal / size, dr.cgal_to_ours / size,
              dr.cgal_vertices_outside, dc.ours_to_cgal / size, dc.cgal_to_ours / size, dc.cgal_vertices_outside);
  print_percentiles("regular", dr.cgal_distances, size);
  print_percentiles("CGAL tets", dc.cgal_distances, size);
  expect_close_to_cgal_mesh(dr, size, check.ours_to_cgal);
  expect_close_to_cgal_mesh(dc, size, check.ours_to_cgal);
  if (tg) {
    // TetGen mode (known issue, not asserted beyond this): flat TetGen tetrahedra are skipped and
    // leave a few CGAL vertices outside every kept tetrahedron.
    const TwoSided dt = compare_with_cgal(tg->model, mesh, size);
    std::printf("  TetGen tetrahedra: ours→CGAL %.3g, CGAL→ours %.3g of the size; %zu CGAL vertices outside\n",
                dt.ours_to_cgal / size, dt.cgal_to_ours / size, dt.cgal_vertices_outside);
    EXPECT_LT(dt.ours_to_cgal, check.ours_to_cgal * size);
  }
}

TEST(ConvertSkin, CaffeineAgreesWithCgal) { check_molecule(kData / "balls/caffeine.cin", {}); }
TEST(ConvertSkin, MoleculeTunnelAgreesWithCgal) { check_molecule(kData / "balls/molecule_tunnel.cin", {}); }
TEST(ConvertSkin, Protein1tiiAgreesWithCgal) {
  // 5.7k atoms: our mixed complex against CGAL's triangulated one (~50 s and 5.8 GB). CGAL's own
  // reference mesh (mesh_skin_surface_3) takes well over 10 minutes more: opt-in.
#if defined(__SANITIZE_ADDRESS__)
  // make test-sanitize: CGAL's side alone would need ~3× the memory and time under ASan.
  if (!std::getenv("QUADRIX_SLOW_TESTS")) GTEST_SKIP() << "skipped under AddressSanitizer (set QUADRIX_SLOW_TESTS=1)";
#endif
  check_molecule(kData / "molecules/1tii.pdb",
                 {.subdivisions = 0,
                  .ours_to_cgal = 1e-2,  // CGAL's unsubdivided mesh: chords up to ~1% of the size
                  .tetgen = false,
                  .cgal_mesh = std::getenv("QUADRIX_SLOW_TESTS") != nullptr});
}

TEST(ConvertSkin, BadBallSetsAreInvalidInput) {
  EXPECT_THROW(convert_skin({}), InvalidInput);
  const Ball a{{0, 0, 0}, 1, {}, ""};
  Ball neg = a;
  neg.centre.x() = 3;
  neg.radius = -1;
  EXPECT_THROW(convert_skin({a, neg}), InvalidInput);
  EXPECT_THROW(convert_skin({a, a}), InvalidInput);
  EXPECT_THROW(convert_skin({a}, {.shrink = 1.0}), InvalidInput);
}

}  // namespace
}  // namespace quadrix
