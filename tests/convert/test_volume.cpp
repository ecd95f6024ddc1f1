// Volume readers and quadratic iso-surfaces (issue 6, items 4, 5 and 7), on grids and on
// tetrahedral meshes with per-vertex values.
#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <numeric>
#include <random>
#include <set>
#include <cstring>
#include <functional>
#include <string>
#include <sys/wait.h>
#include <unistd.h>
#include <vector>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <zlib.h>

#include "tests/support.h"
#include <tbb/parallel_for.h>

#include "convert/tetmesh_io.h"
#include "convert/volume.h"
#include "core/bounds.h"
#include "core/camera.h"
#include "core/error.h"
#include "core/model_io.h"
#include "core/reference.h"

namespace quadrix {
namespace {

namespace fs = std::filesystem;
using Eigen::Vector3d;

const fs::path kVolumes = fs::path(QUADRIX_DATASETS) / "volumes";

std::string fmt_double(double x) {
  char b[40];
  std::snprintf(b, sizeof b, "%.17g", x);
  return b;
}

// `"key": N` as nlohmann::json's dump(2) writes it.
std::string fmt_count(const std::string& key, std::size_t n) { return key + ": " + std::to_string(n); }

using test_support::TempDir;

// ---------------------------------------------------------------------------------------------
// Readers

class VolumeIo : public TempDir {};

TEST_F(VolumeIo, SharedNrrdAndInrVolumes) {
  if (!fs::exists(kVolumes)) GTEST_SKIP() << "data set folder not found: " << kVolumes.string();
  const Volume lobster = read_volume(kVolumes / "lobster_120x120x34_uint16.nhdr");
  EXPECT_EQ(lobster.dims, (std::array<int, 3>{120, 120, 34}));
  EXPECT_EQ(lobster.range(), (std::pair<double, double>{0.0, 4080.0}));
  const Volume head = read_volume(kVolumes / "HeadMRVolume_48x62x42_uint8.nhdr");
  EXPECT_EQ(head.dims, (std::array<int, 3>{48, 62, 42}));
  EXPECT_EQ(head.spacing, Vector3d(4, 4, 4));
  const Volume hydrogen = read_volume(kVolumes / "hydrogen_64x64x64_float32.nhdr");
  EXPECT_LE(hydrogen.range().second, 1.0 + 1e-6);
  EXPECT_GT(hydrogen.range().second, 0.5);
  const Volume skull = read_volume(kVolumes / "skull_2.9.inr");
  EXPECT_EQ(skull.dims, (std::array<int, 3>{64, 64, 64}));
  EXPECT_NEAR(skull.spacing.x(), 3.94305, 1e-9);
  EXPECT_NEAR(skull.spacing.z(), 3.65079, 1e-9);
  EXPECT_NEAR(skull.range().second, 5.4288, 1e-3);
  const Volume liver = read_volume(kVolumes / "liver.inr.gz");
  EXPECT_EQ(liver.dims, (std::array<int, 3>{438, 353, 165}));
  EXPECT_EQ(liver.range(), (std::pair<double, double>{0.0, 255.0}));
}

std::string be16(const std::vector<std::int16_t>& v) {
  std::string s;
  for (const auto x : v) {
    const auto u = static_cast<std::uint16_t>(x);
    s.push_back(static_cast<char>(u >> 8));
    s.push_back(static_cast<char>(u & 0xff));
  }
  return s;
}

TEST_F(VolumeIo, NrrdBigEndianAttachedAndRaw) {
  std::vector<std::int16_t> v(2 * 3 * 2);
  std::iota(v.begin(), v.end(), -5);
  const std::string data = be16(v);
  write("a.raw", data);
  const auto hdr = write("a.nhdr", "NRRD0004\n# c\ntype: short\ndimension: 3\nsizes: 2 3 2\n"
                                   "space directions: (0.5,0,0) (0,2,0) (0,0,3)\nendian: big\nencoding: raw\n"
                                   "key:=value\ndata file: a.raw\n");
  const Volume a = read_volume(hdr);
  EXPECT_EQ(a.at(0, 0, 0), -5.0f);
  EXPECT_EQ(a.at(1, 2, 1), 6.0f);
  EXPECT_EQ(a.spacing, Vector3d(0.5, 2, 3));
  const auto att = write("b.nrrd", "NRRD0004\ntype: int16\ndimension: 3\nsizes: 2 3 2\nendian: big\n\n" + data);
  EXPECT_EQ(read_volume(att).values, a.values);
  const Volume r = read_raw_volume(dir_ / "a.raw", {.dims = {2, 3, 2}, .type = VoxelType::int16, .big_endian = true});
  EXPECT_EQ(r.values, a.values);
}

TEST_F(VolumeIo, NrrdRoundTrip) {
  const Volume ml = marschner_lobb_volume(11);
  write_nrrd(ml, dir_ / "ml.nhdr");
  ASSERT_TRUE(fs::exists(dir_ / "ml.raw"));
  const Volume back = read_volume(dir_ / "ml.nhdr");
  EXPECT_EQ(back.dims, ml.dims);
  EXPECT_EQ(back.values, ml.values);
  EXPECT_TRUE(back.spacing.isApprox(ml.spacing, 1e-15));
  EXPECT_TRUE(back.origin.isApprox(ml.origin, 1e-15));
}

TEST_F(VolumeIo, MalformedVolumesAreFormatErrors) {
  write("short.raw", std::string(11, '\0'));
  const auto expect_format = [](const auto& f, const std::string& needle) {
    try {
      f();
      ADD_FAILURE() << "no FormatError; expected one mentioning '" << needle << "'";
    } catch (const FormatError& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
  };
  const auto hdr = [&](const std::string& body) { return write("x.nhdr", "NRRD0004\n" + body); };
  expect_format([&] { read_volume(hdr("type: uint8\ndimension: 3\nsizes: 2 3 2\ndata file: short.raw\n")); },
                "12 bytes of data, the file holds 11");
  expect_format([&] { read_volume(hdr("type: uint16\ndimension: 3\nsizes: 2 3 1\ndata file: short.raw\n")); },
                "endian");
  expect_format([&] { read_volume(hdr("type: quaternion\ndimension: 3\nsizes: 2 3 2\ndata file: short.raw\n")); },
                "quaternion");
  expect_format([&] { read_volume(hdr("type: uint8\ndimension: 3\nsizes: 2 x 2\ndata file: short.raw\n")); },
                "'x' is not an integer");
  expect_format([&] { read_volume(hdr("type: uint8\ndimension: 3\nsizes: 2 3 2\nencoding: bzip2\ndata file: short.raw\n")); },
                "bzip2");
  expect_format([&] { read_volume(write("n.nhdr", "P6\n")); }, "NRRD");
  expect_format([&] { read_raw_volume(dir_ / "short.raw", {.dims = {2, 2, 2}, .type = VoxelType::uint16}); },
                "16 bytes");
  std::string inr = "#INRIMAGE-4#{\nXDIM=2\nYDIM=2\nZDIM=2\nVDIM=1\nTYPE=float\nPIXSIZE=32 bits\nCPU=decm\n";
  inr.resize(252, '\n');
  inr += "##}\n";
  expect_format([&] { read_volume(write("t.inr", inr + std::string(31, '\0'))); }, "32 bytes of data, the file holds 31");
  std::string nan(32, '\0');
  const float q = std::numeric_limits<float>::quiet_NaN();
  std::memcpy(nan.data() + 8, &q, 4);
  expect_format([&] { read_volume(write("nan.inr", inr + nan)); }, "voxel 2");
  EXPECT_NO_THROW(read_volume(write("ok.inr", inr + std::string(32, '\0'))));
  EXPECT_THROW(read_volume(dir_ / "missing.nhdr"), IoError);
}

// ---------------------------------------------------------------------------------------------
// Surface sampling along axis-parallel lines through the grid (our patches, the analytic surface)

// Patches indexed by the grid cell holding their centroid.
struct CellIndex {
  const Volume& grid;
  const Model& model;
  std::map<std::array<int, 3>, std::vector<int>> cells;
  CellIndex(const Volume& v, const Model& m) : grid(v), model(m) {
    for (int t = 0; t < static_cast<int>(m.tets.size()); ++t) {
      const Vector3d u = (m.tets[t].centroid() - v.origin).cwiseQuotient(v.spacing);
      cells[{int(std::floor(u.x())), int(std::floor(u.y())), int(std::floor(u.z()))}].push_back(t);
    }
  }
  // Crossings of the line origin + s·e_axis, s ∈ ℝ, with the patches (the points, unsorted).
  void crossings(const Vector3d& origin, int axis, std::vector<Vector3d>& out) const {
    const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
    std::array<int, 3> c{};
    c[a1] = int(std::floor((origin[a1] - grid.origin[a1]) / grid.spacing[a1]));
    c[a2] = int(std::floor((origin[a2] - grid.origin[a2]) / grid.spacing[a2]));
    for (c[axis] = 0; c[axis] < grid.dims[axis] - 1; ++c[axis]) {
      const auto it = cells.find(c);
      if (it == cells.end()) continue;
      for (const int t : it->second) {
        const TetPatch& p = model.tets[t];
        const Vector3d o = origin - p.centroid();
        Vector3d d = Vector3d::Zero();
        d[axis] = 1;
        // Clip the line to the tetrahedron: the 4 face half-spaces.
        double lo = -1e300, hi = 1e300;
        bool empty = false;
        for (int f = 0; f < 4 && !empty; ++f) {
          const Vector3d a = p.corners[(f + 1) % 4] - p.centroid(), b = p.corners[(f + 2) % 4] - p.centroid(),
                         cc = p.corners[(f + 3) % 4] - p.centroid(), opp = p.corners[f] - p.centroid();
          Vector3d n = (b - a).cross(cc - a);
          if (n.dot(opp - a) < 0) n = -n;
          const double num = n.dot(o - a), den = n.dot(d);  // inside: num + s·den ≥ 0
          if (den == 0) {
            if (num < 0) empty = true;
          } else if (den > 0) {
            lo = std::max(lo, -num / den);
          } else {
            hi = std::min(hi, -num / den);
          }
        }
        if (empty || lo >= hi) continue;
        const Quadric& q = p.quadric;
        const double alpha = d.dot(q.A * d), beta = d.dot(q.A * o + q.b), gamma = q.eval(o);
        std::array<double, 2> roots{};
        int n = 0;
        if (std::abs(alpha) <= 1e-14 * (std::abs(beta) + std::abs(gamma))) {
          if (beta != 0) roots[n++] = -gamma / (2 * beta);
        } else {
          const double disc = beta * beta - alpha * gamma;
          if (disc < 0) continue;
          const double qq = -(beta + std::copysign(std::sqrt(disc), beta));
          roots[n++] = qq / alpha;
          if (qq != 0) roots[n++] = gamma / qq;
        }
        for (int r = 0; r < n; ++r)
          if (roots[r] >= lo && roots[r] < hi) out.push_back(origin + roots[r] * d);
      }
    }
  }
};

struct ErrorStats {
  double rms = 0, mean = 0, max = 0;
  std::size_t samples = 0;
  double missed = 0;  // fraction of analytic crossings with no patch crossing within one cell along the line
};

// Newton projection onto {ML = ½}: the distance to the nearest surface point it finds.
double ml_distance(Vector3d x) {
  const Vector3d x0 = x;
  for (int it = 0; it < 50; ++it) {
    const double g = marschner_lobb(x) - 0.5;
    const Vector3d grad = marschner_lobb_gradient(x);
    if (std::abs(g) < 1e-13 || grad.squaredNorm() == 0) break;
    Vector3d step = g * grad / grad.squaredNorm();
    if (step.norm() > 0.02) step *= 0.02 / step.norm();
    x -= step;
  }
  return (x - x0).norm();
}

// A fixed lattice of axis-parallel lines through [−1, 1]³ (lines² per axis) and, per line, where
// it crosses the analytic surface {ML = ½} (sign changes on a fine step, then bisection).
struct LineLattice {
  int lines = 0;
  std::vector<std::vector<double>> analytic;  // per line id: crossing coordinates along its axis

  explicit LineLattice(int n) : lines(n), analytic(3 * n * n) {
    tbb::parallel_for(0, 3 * n * n, [&](int id) {
      const int axis = id / (lines * lines);
      const Vector3d o = origin(id);
      auto at = [&](double s) {
        Vector3d x = o;
        x[axis] = s;
        return marschner_lobb(x) - 0.5;
      };
      const int steps = 1200;  // step 1/600; the ripples' period is ≈ 0.1
      double s0 = -1, g0 = at(s0);
      for (int k = 1; k <= steps; ++k) {
        const double s1 = -1 + 2.0 * k / steps, g1 = at(s1);
        if ((g0 < 0) != (g1 < 0)) {
          double a = s0, b = s1, ga = g0;
          for (int it = 0; it < 40; ++it) {
            const double m = 0.5 * (a + b), gm = at(m);
            if ((gm < 0) == (ga < 0)) a = m, ga = gm;
            else b = m;
          }
          analytic[id].push_back(0.5 * (a + b));
        }
        s0 = s1;
        g0 = g1;
      }
    });
  }
  int axis(int id) const { return id / (lines * lines); }
  Vector3d origin(int id) const {
    const int ax = id / (lines * lines), u = (id / lines) % lines, v = id % lines;
    Vector3d o = Vector3d::Zero();
    o[(ax + 1) % 3] = -1 + (u + 0.5137) * 2.0 / lines;
    o[(ax + 2) % 3] = -1 + (v + 0.4711) * 2.0 / lines;
    return o;
  }
};

// Distance from our surface to the analytic ML iso-surface over the lattice lines' crossings of
// our patches, and the fraction of analytic crossings our surface misses (no patch crossing
// within one cell along the same line).
ErrorStats ml_error(const Volume& grid, const Model& model, const LineLattice& lattice) {
  const CellIndex index(grid, model);
  const int count = static_cast<int>(lattice.analytic.size());
  std::vector<ErrorStats> per_line(count);
  std::vector<std::size_t> missed(count);
  tbb::parallel_for(0, count, [&](int id) {
    const int axis = lattice.axis(id);
    std::vector<Vector3d> pts;
    index.crossings(lattice.origin(id), axis, pts);
    ErrorStats& s = per_line[id];
    for (const auto& p : pts) {
      const double e = ml_distance(p);
      s.mean += e;
      s.rms += e * e;
      s.max = std::max(s.max, e);
      ++s.samples;
    }
    for (const double c : lattice.analytic[id]) {
      bool hit = false;
      for (const auto& p : pts) hit = hit || std::abs(p[axis] - c) <= grid.spacing[axis];
      missed[id] += !hit;
    }
  });
  ErrorStats total;
  std::size_t a = 0, m = 0;
  for (int i = 0; i < count; ++i) {
    total.mean += per_line[i].mean;
    total.rms += per_line[i].rms;
    total.max = std::max(total.max, per_line[i].max);
    total.samples += per_line[i].samples;
    a += lattice.analytic[i].size();
    m += missed[i];
  }
  total.mean /= std::max<std::size_t>(1, total.samples);
  total.rms = std::sqrt(total.rms / std::max<std::size_t>(1, total.samples));
  total.missed = a ? static_cast<double>(m) / a : 0.0;
  return total;
}

// Marching-tetrahedra triangles: 1 per tetrahedron with one corner apart, 2 with two on each side.
std::size_t mt_triangles(const Model& linear) {
  std::size_t n = 0;
  for (const auto& t : linear.tets) {
    int below = 0;
    for (const auto& c : t.corners) below += t.quadric.eval(c - t.centroid()) > 0;  // V − f > 0: below V
    n += (below == 2) ? 2 : (below == 1 || below == 3) ? 1 : 0;
  }
  return n;
}

// ---------------------------------------------------------------------------------------------
// Conversion

TEST(ConvertVolume, CatmullRomReproducesQuadricsExactly) {
  // f = ‖x − c‖²: Catmull–Rom has quadratic precision, so away from the clamped border every
  // patch is exactly the sphere ‖x − c‖ = r.
  Volume v;
  v.dims = {12, 13, 14};
  v.spacing = Vector3d(0.3, 0.25, 0.2);
  v.origin = Vector3d(100, -50, 7);
  const Vector3d c = v.origin + Vector3d(1.7, 1.6, 1.35);
  v.values.resize(12 * 13 * 14);
  for (int k = 0; k < 14; ++k)
    for (int j = 0; j < 13; ++j)
      for (int i = 0; i < 12; ++i) v.values[v.index(i, j, k)] = float((v.position(i, j, k) - c).squaredNorm());
  // float samples: the reconstruction is exact up to float rounding of the samples.
  const double r = 1.0;
  const VolumeConversion conv = convert_volume(v, {.iso = r * r});
  ASSERT_GT(conv.model.tets.size(), 100u);
  double worst = 0;
  for (const auto& t : conv.model.tets) {
    for (int s = 0; s < 4; ++s) {
      // Points of the patch: project the centroid and corners onto the quadric along the gradient.
      Vector3d y = (s == 0 ? t.centroid() : 0.5 * (t.centroid() + t.corners[s])) - t.centroid();
      for (int it = 0; it < 30; ++it) {
        const Vector3d g = t.quadric.gradient(y);
        y -= t.quadric.eval(y) * g / g.squaredNorm();
      }
      const Vector3d x = y + t.centroid();
      worst = std::max(worst, std::abs((x - c).norm() - r));
    }
  }
  EXPECT_LT(worst, 1e-5) << "patch points off the sphere";
  EXPECT_EQ(conv.value_min, v.range().first);
}

TEST(ConvertVolume, IsoOutsideTheDataRangeIsInvalidInput) {
  const Volume v = marschner_lobb_volume(9);
  const auto [lo, hi] = v.range();
  for (const double iso : {lo - 1, hi + 1, lo, hi, std::nan("")}) {
    try {
      convert_volume(v, {.iso = iso});
      ADD_FAILURE() << "iso " << iso << " accepted";
    } catch (const FormatError&) {
      ADD_FAILURE() << "iso out of range must be InvalidInput, not FormatError";
    } catch (const InvalidInput& e) {
      EXPECT_NE(std::string(e.what()).find("outside the data range"), std::string::npos) << e.what();
    }
  }
  Volume flat = v;
  flat.dims = {1, 9, 81};
  EXPECT_THROW(convert_volume(flat, {.iso = 0.5}), InvalidInput);
}

TEST(ConvertVolume, EveryTetrahedronWhoseCornersStraddleIsKept) {
  // Corners are control points, so a tetrahedron whose corner values straddle V (a marching-
  // tetrahedra cell) must be kept whatever the reconstruction: the cell pre-cull must never drop one.
  const Volume v = marschner_lobb_volume(17);
  const VolumeConversion lin = convert_volume(v, {.iso = 0.5, .linear = true});
  ASSERT_GT(lin.model.tets.size(), 1000u);
  for (const auto rec : {Reconstruction::trilinear, Reconstruction::catmull_rom}) {
    const VolumeConversion conv = convert_volume(v, {.iso = 0.5, .reconstruction = rec});
    EXPECT_LT(conv.cells_visited, conv.cells);
    std::set<std::array<long, 3>> kept;
    const auto key = [](const TetPatch& t) {
      const Vector3d c = t.centroid() * 1e6;
      return std::array<long, 3>{std::lround(c.x()), std::lround(c.y()), std::lround(c.z())};
    };
    for (const auto& t : conv.model.tets) kept.insert(key(t));
    std::size_t dropped = 0;
    for (const auto& t : lin.model.tets) dropped += !kept.count(key(t));
    EXPECT_EQ(dropped, 0u) << "tetrahedra whose corners straddle V were dropped";
    EXPECT_GT(conv.model.tets.size(), lin.model.tets.size());
  }
}

TEST(ConvertVolume, MarschnerLobbAccuracyTable) {
  // Item 5: distance of the surface to the analytic iso-surface {ML = ½} on n³ grids; quadratic
  // patches (Catmull–Rom and trilinear midpoints) against linear marching tetrahedra on the same
  // tetrahedra. Distances in units of the domain [−1, 1]³ (side 2).
  const std::vector<int> grids{9, 17, 25, 33, 41, 49, 65};
  const int lines = 64;
  const LineLattice lattice(lines);
  struct Row {
    int n;
    std::size_t quad_patches, mt_triangles;
    ErrorStats cr, tri, mt;
  };
  std::vector<Row> rows;
  std::printf("\nMarschner–Lobb, iso 0.5, f_M = 6, alpha = 0.25: distance to the analytic surface "
              "(domain side 2; %d×%d lines per axis)\n",
              lines, lines);
  std::printf("%4s | %9s %10s %10s %10s %7s | %10s %10s | %9s %10s %10s %10s %7s\n", "n", "patches", "CR rms",
              "CR mean", "CR max", "missed", "tri rms", "tri max", "MT tris", "MT rms", "MT mean", "MT max", "missed");
  for (const int n : grids) {
    const Volume v = marschner_lobb_volume(n);
    const VolumeConversion cr = convert_volume(v, {.iso = 0.5});
    const VolumeConversion tri = convert_volume(v, {.iso = 0.5, .reconstruction = Reconstruction::trilinear});
    const VolumeConversion mt = convert_volume(v, {.iso = 0.5, .linear = true});
    Row r{n, cr.model.tets.size(), mt_triangles(mt.model), ml_error(v, cr.model, lattice),
          ml_error(v, tri.model, lattice), ml_error(v, mt.model, lattice)};
    std::printf("%4d | %9zu %10.3g %10.3g %10.3g %6.2f%% | %10.3g %10.3g | %9zu %10.3g %10.3g %10.3g %6.2f%%\n", n,
                r.quad_patches, r.cr.rms, r.cr.mean, r.cr.max, 100 * r.cr.missed, r.tri.rms, r.tri.max,
                r.mt_triangles, r.mt.rms, r.mt.mean, r.mt.max, 100 * r.mt.missed);
    rows.push_back(r);
  }
  std::fflush(stdout);
  // Same grid: quadratic (Catmull–Rom) patches are closer than marching tetrahedra once the grid
  // resolves the ripples at all (n ≥ 17; ML's ripple period is ≈ 0.17, Nyquist at n ≈ 25).
  for (const auto& r : rows)
    if (r.n >= 17) {
      EXPECT_LT(r.cr.rms, r.mt.rms) << "n = " << r.n;
      EXPECT_LT(r.cr.mean, r.mt.mean) << "n = " << r.n;
    }
  // Per primitive: each quadratic row beats the marching-tetrahedra row with at least as many
  // triangles as it has patches.
  for (const auto& q : rows) {
    if (q.n < 17) continue;
    const Row* best = nullptr;
    for (const auto& m : rows)
      if (m.mt_triangles >= q.quad_patches && (!best || m.mt_triangles < best->mt_triangles)) best = &m;
    if (!best) continue;
    EXPECT_LT(q.cr.rms, best->mt.rms) << "quadratic n = " << q.n << " (" << q.quad_patches
                                       << " patches) vs MT n = " << best->n << " (" << best->mt_triangles << " triangles)";
  }
}

// Renders a model with the CPU reference (no culling: both sides of the iso-surface).
ReferenceImage render(const Model& m, const Box3& box, int size) {
  const ReferenceScene scene(m);
  const Camera cam = frame_box(box, {.azimuth_deg = 35, .elevation_deg = 25, .width = size, .height = size});
  ReferenceRenderOptions o;
  o.trace.cull_backfaces = false;
  return render_reference(scene, cam, o);
}

// Item 5: the CT skull and the lobster convert and render; their quadratic iso-surface agrees
// with marching tetrahedra on the same grid to within a fraction of a voxel, pixel by pixel.
void convert_and_render(const fs::path& file, double iso, double max_median_voxels) {
  if (!fs::exists(file)) GTEST_SKIP() << "data set not found: " << file.string();
  const Volume v = read_volume(file);
  const auto t0 = std::chrono::steady_clock::now();
  const VolumeConversion q = convert_volume(v, {.iso = iso});
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const VolumeConversion l = convert_volume(v, {.iso = iso, .linear = true});
  std::printf("%s iso %g: %zu of %zu cells visited, %zu patches (MT: %zu tetrahedra) in %.3f s\n",
              file.filename().c_str(), iso, q.cells_visited, q.cells, q.model.tets.size(), l.model.tets.size(),
              seconds);
  ASSERT_GT(q.model.tets.size(), 1000u);
  Box3 box;
  box.extend(v.position(0, 0, 0));
  box.extend(v.position(v.dims[0] - 1, v.dims[1] - 1, v.dims[2] - 1));
  const int size = 96;
  const ReferenceImage a = render(q.model, box, size), b = render(l.model, box, size);
  std::size_t covered = 0, agree = 0;
  std::vector<double> diff;
  for (int i = 0; i < size * size; ++i) {
    covered += a.coverage[i];
    agree += a.coverage[i] == b.coverage[i];
    if (a.coverage[i] && b.coverage[i]) diff.push_back(std::abs(a.distance[i] - b.distance[i]));
  }
  std::nth_element(diff.begin(), diff.begin() + diff.size() / 2, diff.end());
  const double median = diff.empty() ? 1e9 : diff[diff.size() / 2];
  const double voxel = v.spacing.minCoeff();
  std::printf("  %d² render: %.1f%% covered, coverage agreement with MT %.1f%%, median depth difference %.3g voxel\n",
              size, 100.0 * covered / (size * size), 100.0 * agree / (size * size), median / voxel);
  EXPECT_GT(covered, static_cast<std::size_t>(size * size / 20));
  EXPECT_GT(agree, static_cast<std::size_t>(0.95 * size * size));
  EXPECT_LT(median, max_median_voxels * voxel);
}

TEST(ConvertVolume, SkullConvertsAndRenders) { convert_and_render(kVolumes / "skull_2.9.inr", 2.9, 0.25); }
TEST(ConvertVolume, LobsterConvertsAndRenders) {
  convert_and_render(kVolumes / "lobster_120x120x34_uint16.nhdr", 1600, 0.25);
}

// ---------------------------------------------------------------------------------------------
// Tetrahedral meshes with per-vertex values

// The Kuhn split (6 tetrahedra per cell around its main diagonal) of an n³-cell grid over
// [lo, lo + size]³; interior vertices moved by up to jitter·h per coordinate (seeded), so the
// mesh is not a regular grid; every other tetrahedron listed with negative orientation.
TetMesh kuhn_mesh(int n, const Vector3d& lo, double size, double jitter, unsigned seed = 7) {
  TetMesh m;
  m.source = "kuhn";
  const double h = size / n;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-jitter * h, jitter * h);
  const auto id = [n](int i, int j, int k) { return (k * (n + 1) + j) * (n + 1) + i; };
  for (int k = 0; k <= n; ++k)
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) {
        Vector3d x = lo + h * Vector3d(i, j, k);
        const bool interior = i > 0 && j > 0 && k > 0 && i < n && j < n && k < n;
        const Vector3d d(u(rng), u(rng), u(rng));
        if (interior) x += d;
        m.vertices.push_back(x);
      }
  static constexpr int paths[6][2] = {{1, 3}, {1, 5}, {2, 3}, {2, 6}, {4, 5}, {4, 6}};
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i)
        for (int t = 0; t < 6; ++t) {
          std::array<int, 4> v{};
          const int corner[4] = {0, paths[t][0], paths[t][1], 7};
          for (int c = 0; c < 4; ++c)
            v[c] = id(i + (corner[c] & 1), j + ((corner[c] >> 1) & 1), k + ((corner[c] >> 2) & 1));
          if (m.tets.size() % 2) std::swap(v[0], v[1]);
          m.tets.push_back(v);
        }
  return m;
}

std::string values_text(const std::vector<double>& values) {
  std::string s = "# per-vertex values\n";
  for (std::size_t i = 0; i < values.size(); ++i) s += fmt_double(values[i]) + (i % 4 == 3 ? "\n" : " ");
  return s + "\n";
}

// Points of each patch inside its tetrahedron: Newton projections onto the patch's quadric from
// the centroid and the points halfway to each corner, kept when they land inside the tetrahedron.
std::vector<Vector3d> patch_points(const Model& m) {
  std::vector<Vector3d> out;
  for (const auto& t : m.tets) {
    Eigen::Matrix4d bary;  // (x, 1) ↦ λ
    for (int c = 0; c < 4; ++c) bary.col(c) << t.corners[c] - t.centroid(), 1.0;
    bary = bary.inverse().eval();
    for (int s = 0; s < 5; ++s) {
      Vector3d y = (s == 0 ? t.centroid() : 0.5 * (t.centroid() + t.corners[s - 1])) - t.centroid();
      for (int it = 0; it < 40; ++it) {
        const Vector3d g = t.quadric.gradient(y);
        if (g.squaredNorm() == 0) break;
        y -= t.quadric.eval(y) * g / g.squaredNorm();
      }
      const Vector3d g = t.quadric.gradient(y);
      if (!(std::abs(t.quadric.eval(y)) <= 1e-13 * g.norm() + 1e-15)) continue;
      const Eigen::Vector4d l = bary * Eigen::Vector4d(y.x(), y.y(), y.z(), 1.0);
      if (l.minCoeff() < -1e-9) continue;
      out.push_back(y + t.centroid());
    }
  }
  return out;
}

class TetMeshIo : public TempDir {
protected:
  // FormatError whose message names `file` and contains each needle.
  void expect_format(const std::function<void()>& f, const fs::path& file, std::initializer_list<std::string> needles) {
    try {
      f();
      ADD_FAILURE() << "no FormatError for " << file.filename();
    } catch (const FormatError& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find(file.string()), std::string::npos) << "message does not name the file: " << msg;
      for (const auto& n : needles) EXPECT_NE(msg.find(n), std::string::npos) << "'" << n << "' not in: " << msg;
    }
  }
};

constexpr const char* kTwoTets =
    "MeshVersionFormatted 1\n"  // line 1
    "# two tetrahedra sharing a face\n"
    "Dimension\n3\n"
    "Vertices\n5\n"  // lines 5, 6
    "0 0 0 1\n1 0 0 1\n0 1 0 1\n0 0 1 1\n1 1 1 2  # apex\n"  // lines 7-11
    "Triangles\n1\n1 2 3 4\n"                                   // lines 12-14
    "Edges 2\n1 2 0\n2 3 0\n"                                   // lines 15-17
    "Tetrahedra\n2\n"                                           // lines 18, 19
    "1 2 3 4 7\n"                                               // line 20
    "2 3 4 5 7\n"                                               // line 21
    "Corners 1 1\n"
    "End\n";

TEST_F(TetMeshIo, MeditSkipsOtherSectionsAndTetGenReadsTheSameMesh) {
  const TetMesh m = read_tet_mesh(write("two.mesh", kTwoTets));
  ASSERT_EQ(m.vertices.size(), 5u);
  ASSERT_EQ(m.tets.size(), 2u);
  EXPECT_EQ(m.vertices[4], Vector3d(1, 1, 1));
  EXPECT_EQ(m.tets[1], (std::array<int, 4>{1, 2, 3, 4}));
  write("two.node", "# TetGen\n5 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 0 1\n4 1 1 1\n");
  write("two.ele", "2 4 1\n0 0 1 2 3 7\n1 1 2 3 4 7\n");
  for (const char* name : {"two.node", "two.ele"}) {
    const TetMesh t = read_tet_mesh(dir_ / name);
    EXPECT_EQ(t.vertices, m.vertices);
    EXPECT_EQ(t.tets, m.tets);
  }
  // 1-based TetGen files.
  write("one.node", "5 3 0 1\n1 0 0 0 0\n2 1 0 0 0\n3 0 1 0 0\n4 0 0 1 0\n5 1 1 1 0\n");
  write("one.ele", "2 4 0\n1 1 2 3 4\n2 2 3 4 5\n");
  EXPECT_EQ(read_tet_mesh(dir_ / "one.ele").tets, m.tets);
  // write_medit_mesh round trip.
  write_medit_mesh(m, dir_ / "back.mesh");
  const TetMesh b = read_tet_mesh(dir_ / "back.mesh");
  EXPECT_EQ(b.vertices, m.vertices);
  EXPECT_EQ(b.tets, m.tets);
  const auto v = read_vertex_values(write("v.txt", "# values\n0.5 1e-3\n-2 # third\n+4 5.25\n"), 5);
  EXPECT_EQ(v, (std::vector<double>{0.5, 1e-3, -2, 4, 5.25}));
}

TEST_F(TetMeshIo, MalformedMeshesAndValuesNameFileAndLine) {
  const std::string good = kTwoTets;
  const auto edit = [&](const std::string& from, const std::string& to) {
    std::string s = good;
    const auto at = s.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    return s.replace(at, from.size(), to);
  };
  const auto mesh = [&](const std::string& text) { return write("bad.mesh", text); };
  fs::path f;
  // Truncated inside a section.
  f = mesh(good.substr(0, good.find("0 0 1 1\n")));
  expect_format([&] { read_tet_mesh(f); }, f, {"ends inside 'Vertices' (line 5) after 3 of its 5 entries"});
  // Truncated at a section boundary: no End.
  f = mesh(good.substr(0, good.find("Corners")));
  expect_format([&] { read_tet_mesh(f); }, f, {"no 'End'"});
  // A count larger than the section: the next keyword is not a number.
  f = mesh(edit("Vertices\n5\n", "Vertices\n6\n"));
  expect_format([&] { read_tet_mesh(f); }, f, {":12:", "'Triangles' is not a number", "entry 6 of 6"});
  // Index out of range and zero index.
  f = mesh(edit("2 3 4 5 7\n", "2 3 4 9 7\n"));
  expect_format([&] { read_tet_mesh(f); }, f, {":21:", "tetrahedron 2", "vertex index 9 is outside 1..5"});
  f = mesh(edit("1 2 3 4 7\n", "1 2 0 4 7\n"));
  expect_format([&] { read_tet_mesh(f); }, f, {":20:", "vertex index 0"});
  // Non-finite coordinate.
  f = mesh(edit("1 0 0 1\n", "1 nan 0 1\n"));
  expect_format([&] { read_tet_mesh(f); }, f, {":8:", "vertex 2", "non-finite"});
  f = mesh(edit("0 1 0 1\n", "0 1 inf 1\n"));
  expect_format([&] { read_tet_mesh(f); }, f, {":9:", "non-finite"});
  // Degenerate (coplanar and repeated-vertex) tetrahedra.
  f = mesh(edit("1 1 1 2  # apex", "0.5 0.5 0 2"));
  expect_format([&] { read_tet_mesh(f); }, f, {":21:", "tetrahedron 2 (2 3 4 5) is degenerate"});
  f = mesh(edit("1 2 3 4 7\n", "1 2 3 2 7\n"));
  expect_format([&] { read_tet_mesh(f); }, f, {":20:", "degenerate"});
  // Header problems.
  f = mesh(edit("Dimension\n3", "Dimension\n2"));
  expect_format([&] { read_tet_mesh(f); }, f, {":4:", "Dimension 2"});
  f = mesh(edit("Corners", "Cornets"));
  expect_format([&] { read_tet_mesh(f); }, f, {":22:", "unknown keyword 'Cornets'"});
  f = mesh(edit("Tetrahedra\n2\n", "Tetrahedra\n-2\n"));
  expect_format([&] { read_tet_mesh(f); }, f, {":19:", "'-2'"});
  // TetGen.
  write("t.node", "5 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 0 1\n");
  write("t.ele", "1 4 0\n0 0 1 2 3\n");
  expect_format([&] { read_tet_mesh(dir_ / "t.ele"); }, dir_ / "t.node", {"says 5 points, the file holds 4"});
  write("t.node", "4 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 0 1\n");
  write("t.ele", "1 4 0\n0 0 1 2 4\n");
  expect_format([&] { read_tet_mesh(dir_ / "t.ele"); }, dir_ / "t.ele", {":2:", "vertex index 4 is outside 0..3"});
  write("t.ele", "1 4 0\n0 0 1 2\n");
  expect_format([&] { read_tet_mesh(dir_ / "t.ele"); }, dir_ / "t.ele", {":2:", "4 numbers, a tetrahedron has 5"});
  write("t.node", "4 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 nan 1\n");
  expect_format([&] { read_tet_mesh(dir_ / "t.node"); }, dir_ / "t.node", {":5:", "non-finite"});

  // Values: wrong count (short, long), NaN, Inf, not a number.
  fs::path v = write("v.txt", "1 2\n3\n");
  expect_format([&] { read_vertex_values(v, 5); }, v, {"3 values for 5 vertices", ":2:"});
  v = write("v.txt", "1 2 3\n4 5\n# trailing\n6\n");
  expect_format([&] { read_vertex_values(v, 5); }, v, {":4:", "more values than the mesh's 5 vertices"});
  v = write("v.txt", "1 2\n3 nan 5\n");
  expect_format([&] { read_vertex_values(v, 5); }, v, {":2:", "value 4 ('nan', vertex 4) is not finite"});
  v = write("v.txt", "1 2\n3 4\n-inf\n");
  expect_format([&] { read_vertex_values(v, 5); }, v, {":3:", "not finite"});
  v = write("v.txt", "1 2\n3 4,5\n");
  expect_format([&] { read_vertex_values(v, 5); }, v, {":2:", "'4,5' is not a number"});
  EXPECT_THROW(read_tet_mesh(dir_ / "missing.mesh"), IoError);
  EXPECT_THROW(read_tet_mesh(dir_ / "mesh.obj"), InvalidInput);
}

TEST_F(TetMeshIo, QuadraticValuesReproduceTheIsoSurfaceExactly) {
  // f(x) = (x − c)ᵀM(x − c) (an ellipsoid, M SPD and not diagonal) on a jittered Kuhn mesh far
  // from the origin: the quadratic least-squares gradients are exact, so the Hermite midpoints and
  // the patches are exact: every patch point lies on {f = V} up to rounding.
  const Vector3d lo(40, -20, 7);
  const double size = 2.0;
  const TetMesh gen = kuhn_mesh(6, lo, size, 0.15);
  Eigen::Matrix3d M;
  M << 1.0, 0.3, -0.2, 0.3, 1.6, 0.25, -0.2, 0.25, 0.8;
  const Vector3d c = lo + Vector3d(1.05, 0.93, 1.1);
  const auto f = [&](const Vector3d& x) { return (x - c).dot(M * (x - c)); };
  std::vector<double> vals;
  for (const auto& x : gen.vertices) vals.push_back(f(x));
  write_medit_mesh(gen, dir_ / "e.mesh");
  write("e.txt", values_text(vals));
  const TetMesh mesh = read_tet_mesh(dir_ / "e.mesh");
  const std::vector<double> values = read_vertex_values(dir_ / "e.txt", mesh.vertices.size());
  ASSERT_EQ(values, vals);

  const VertexGradients g = estimate_vertex_gradients(mesh, values);
  EXPECT_EQ(g.linear_fits, 0u);
  double grad_err = 0;
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i)
    grad_err = std::max(grad_err, (g.gradients[i] - 2 * M * (mesh.vertices[i] - c)).norm());
  EXPECT_LT(grad_err, 1e-9) << "quadratic fit gradients are not exact";

  const double V = 0.5;
  const VolumeConversion conv = convert_tet_mesh(mesh, values, {.iso = V});
  EXPECT_EQ(conv.cells, mesh.tets.size());
  EXPECT_EQ(conv.linear_gradients, 0u);
  ASSERT_GT(conv.model.tets.size(), 50u);
  // Orientation: every patch positively oriented.
  for (const auto& t : conv.model.tets)
    EXPECT_GT((t.corners[1] - t.corners[0]).cross(t.corners[2] - t.corners[0]).dot(t.corners[3] - t.corners[0]), 0);
  const auto pts = patch_points(conv.model);
  ASSERT_GT(pts.size(), conv.model.tets.size());
  double worst = 0;  // |f − V| / ‖∇f‖: first-order distance to {f = V}, relative to the mesh size
  for (const auto& x : pts) worst = std::max(worst, std::abs(f(x) - V) / (2 * M * (x - c)).norm() / size);
  std::printf("quadratic data on a jittered Kuhn mesh (%zu tets, %zu patches): max gradient error %.2e, "
              "max |f - V|/|grad f| %.2e of the mesh size over %zu patch points\n",
              mesh.tets.size(), conv.model.tets.size(), grad_err, worst, pts.size());
  EXPECT_LT(worst, 1e-10);

  // Every tetrahedron whose corners straddle V (a marching-tetrahedra cell) is kept.
  const VolumeConversion lin = convert_tet_mesh(mesh, values, {.iso = V, .linear = true});
  std::size_t straddle = 0;
  for (const auto& t : mesh.tets) {
    double a = 1e300, b = -1e300;
    for (const int k : t) a = std::min(a, values[k]), b = std::max(b, values[k]);
    straddle += a <= V && V <= b && a < b;
  }
  EXPECT_EQ(lin.model.tets.size(), straddle);
  EXPECT_GE(conv.model.tets.size(), straddle);

  // The iso-value must lie strictly inside the value range: InvalidInput, not FormatError.
  const auto [vmin, vmax] = std::minmax_element(values.begin(), values.end());
  for (const double iso : {*vmin, *vmax + 1, std::nan("")}) {
    try {
      convert_tet_mesh(mesh, values, {.iso = iso});
      ADD_FAILURE() << "iso " << iso << " accepted";
    } catch (const FormatError&) {
      ADD_FAILURE() << "iso out of range must be InvalidInput, not FormatError";
    } catch (const InvalidInput& e) {
      EXPECT_NE(std::string(e.what()).find("outside the data range"), std::string::npos) << e.what();
    }
  }
  EXPECT_THROW(convert_tet_mesh(mesh, std::span(values).first(values.size() - 1), {.iso = V}), InvalidInput);
}

TEST(ConvertTetMesh, SphereDistanceConverges) {
  // f(x) = ‖x − c‖ on jittered Kuhn meshes of [−1, 1]³, iso R: the distance of patch points to the
  // sphere drops as the mesh refines (third order for the quadratic patches: Hermite midpoints
  // from O(h²) gradients), and beats linear patches on the same mesh.
  const Vector3d c(0.05, -0.03, 0.02);
  const double R = 0.6;
  struct Row {
    int n;
    std::size_t patches;
    double max_q, rms_q, max_l;
  };
  std::vector<Row> rows;
  std::printf("\nsphere distance field, R = %.1f, jittered Kuhn meshes of [-1,1]^3 (distances in domain units)\n", R);
  std::printf("%4s %8s %9s | %10s %10s %6s | %10s %6s\n", "n", "tets", "patches", "quad max", "quad rms", "order",
              "linear max", "order");
  for (const int n : {4, 8, 16, 32}) {
    const TetMesh mesh = kuhn_mesh(n, Vector3d::Constant(-1), 2.0, 0.1, 11u + n);
    std::vector<double> values;
    for (const auto& x : mesh.vertices) values.push_back((x - c).norm());
    const VolumeConversion q = convert_tet_mesh(mesh, values, {.iso = R});
    const VolumeConversion l = convert_tet_mesh(mesh, values, {.iso = R, .linear = true});
    Row r{n, q.model.tets.size(), 0, 0, 0};
    const auto pq = patch_points(q.model), pl = patch_points(l.model);
    for (const auto& x : pq) {
      const double e = std::abs((x - c).norm() - R);
      r.max_q = std::max(r.max_q, e);
      r.rms_q += e * e;
    }
    r.rms_q = std::sqrt(r.rms_q / std::max<std::size_t>(1, pq.size()));
    for (const auto& x : pl) r.max_l = std::max(r.max_l, std::abs((x - c).norm() - R));
    const double oq = rows.empty() ? 0 : std::log2(rows.back().max_q / r.max_q);
    const double ol = rows.empty() ? 0 : std::log2(rows.back().max_l / r.max_l);
    std::printf("%4d %8zu %9zu | %10.3e %10.3e %6.2f | %10.3e %6.2f\n", n, mesh.tets.size(), r.patches, r.max_q,
                r.rms_q, oq, r.max_l, ol);
    ASSERT_GT(pq.size(), r.patches / 2);
    EXPECT_LT(r.max_q, r.max_l) << "n = " << n;
    rows.push_back(r);
  }
  std::fflush(stdout);
  for (std::size_t i = 1; i < rows.size(); ++i)
    EXPECT_LT(rows[i].max_q, rows[i - 1].max_q / 4) << "n = " << rows[i].n << ": less than second-order convergence";
}

// ---------------------------------------------------------------------------------------------
// Command line

using test_support::CmdResult;
CmdResult quadrix_run(const std::string& args) { return test_support::run_command(QUADRIX_BINARY, args); }

std::string quoted(const fs::path& p) {
  std::string s(1, '\'');
  s += p.string();
  s += '\'';
  return s;
}

class VolumeCli : public TempDir {
protected:
  void SetUp() override {
    if (!fs::exists(QUADRIX_BINARY)) GTEST_SKIP() << "quadrix binary not built: " << QUADRIX_BINARY;
    TempDir::SetUp();
  }
};

TEST_F(VolumeCli, SynthMarschnerLobbWritesANrrd) {
  const fs::path hdr = dir_ / "ml.nhdr";
  CmdResult r = quadrix_run("synth marschner-lobb --resolution 13 -o " + quoted(hdr));
  ASSERT_EQ(r.code, 0) << r.out;
  const Volume v = read_nrrd(hdr);
  EXPECT_EQ(v.dims, (std::array<int, 3>{13, 13, 13}));
  EXPECT_TRUE(v.origin.isApprox(Vector3d::Constant(-1), 1e-15));
  EXPECT_TRUE(v.spacing.isApprox(Vector3d::Constant(2.0 / 12), 1e-15));
  double worst = 0;
  for (int k = 0; k < 13; ++k)
    for (int j = 0; j < 13; ++j)
      for (int i = 0; i < 13; ++i)
        worst = std::max(worst, std::abs(v.at(i, j, k) - marschner_lobb(v.position(i, j, k))));
  EXPECT_LT(worst, 1e-7) << "samples differ from the analytic function beyond float rounding";
  EXPECT_EQ(v.values, marschner_lobb_volume(13).values);
  // Default resolution: the classic 41³; other kinds unchanged.
  r = quadrix_run("synth marschner-lobb -o " + quoted(dir_ / "d.nhdr"));
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_EQ(read_nrrd(dir_ / "d.nhdr").dims, (std::array<int, 3>{41, 41, 41}));
  EXPECT_EQ(quadrix_run("synth marschner-lobb -o " + quoted(dir_ / "ml.qxm")).code, 2);
  r = quadrix_run("synth hyperboloid1 --resolution 4 -o " + quoted(dir_ / "h.qxm"));
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_GT(read_model(dir_ / "h.qxm").tets.size(), 0u);
}

TEST_F(VolumeCli, ConvertVolumeTets) {
  const TetMesh mesh = kuhn_mesh(5, Vector3d::Constant(-1), 2.0, 0.1);
  std::vector<double> values;
  for (const auto& x : mesh.vertices) values.push_back(x.squaredNorm());
  write_medit_mesh(mesh, dir_ / "m.mesh");
  write("v.txt", values_text(values));
  const fs::path out = dir_ / "iso.qxm", report = dir_ / "r.json";
  CmdResult r = quadrix_run("convert volume --tets " + quoted(dir_ / "m.mesh") + " --values " + quoted(dir_ / "v.txt") +
                            " --iso 0.5 -o " + quoted(out) + " --report " + quoted(report));
  ASSERT_EQ(r.code, 0) << r.out;
  const Model m = read_model(out);
  EXPECT_EQ(m.tets.size(), convert_tet_mesh(mesh, values, {.iso = 0.5}).model.tets.size());
  std::ifstream in(report);
  const std::string json((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(json.find(fmt_count("\"tets\"", m.tets.size())), std::string::npos) << json;
  EXPECT_NE(json.find(fmt_count("\"cells\"", mesh.tets.size())), std::string::npos) << json;
  // Bad input: exit code 3 with file and line; iso outside the range: 3; option misuse: 2.
  write("short.txt", "1 2 3\n");
  r = quadrix_run("convert volume --tets " + quoted(dir_ / "m.mesh") + " --values " + quoted(dir_ / "short.txt") +
                  " --iso 0.5 -o " + quoted(out));
  EXPECT_EQ(r.code, 3) << r.out;
  EXPECT_NE(r.out.find("3 values for 216 vertices"), std::string::npos) << r.out;
  r = quadrix_run("convert volume --tets " + quoted(dir_ / "m.mesh") + " --values " + quoted(dir_ / "v.txt") +
                  " --iso 7 -o " + quoted(out));
  EXPECT_EQ(r.code, 3) << r.out;
  EXPECT_NE(r.out.find("outside the data range"), std::string::npos) << r.out;
  write("bad.mesh", "MeshVersionFormatted 1\nDimension 3\nVertices\n1\n0 0 0 0\nTetrahedra\n1\n1 1 1 2 0\nEnd\n");
  r = quadrix_run("convert volume --tets " + quoted(dir_ / "bad.mesh") + " --values " + quoted(dir_ / "v.txt") +
                  " --iso 0.5 -o " + quoted(out));
  EXPECT_EQ(r.code, 3) << r.out;
  EXPECT_NE(r.out.find("bad.mesh:8:"), std::string::npos) << r.out;
  EXPECT_EQ(quadrix_run("convert volume --tets " + quoted(dir_ / "m.mesh") + " --iso 0.5 -o " + quoted(out)).code, 2);
  EXPECT_EQ(quadrix_run("convert volume --synth marschner-lobb --tets " + quoted(dir_ / "m.mesh") + " --values " +
                        quoted(dir_ / "v.txt") + " --iso 0.5 -o " + quoted(out))
                .code,
            2);
}

// Extreme but finite grids are refused by the one world limit (core/limits.h), never turned into
// infinite positions and an empty model.
TEST(VolumeLimits, GridsPastTheWorldLimitAreRefused) {
  Volume v = marschner_lobb_volume(5);
  EXPECT_GT(convert_volume(v, {.iso = 0.5}).model.tets.size(), 0u);
  for (const Vector3d& spacing : {Vector3d(1, 1e308, 1), Vector3d(1e12, 1, 1)}) {
    v.spacing = spacing;
    try {
      convert_volume(v, {.iso = 0.5});
      ADD_FAILURE() << "accepted spacing " << spacing.transpose();
    } catch (const InvalidInput& e) {
      EXPECT_NE(std::string(e.what()).find("largest world coordinate"), std::string::npos) << e.what();
    }
  }
  v.spacing = Vector3d::Ones();
  v.origin = Vector3d(0, 0, -1e300);
  EXPECT_THROW(convert_volume(v, {.iso = 0.5}), InvalidInput);
}

// The tetrahedral-mesh readers apply the same limit and the same degeneracy rule as the model
// reader (core/bounds.h kDegenerateTetrahedron).
TEST_F(TetMeshIo, OneLimitForCoordinatesAndDegenerateTetrahedra) {
  const auto mesh_with = [&](const std::string& apex) {
    return write("l.mesh", "MeshVersionFormatted 1\nDimension 3\nVertices\n4\n0 0 0 0\n1 0 0 0\n0 1 0 0\n" + apex +
                               " 0\nTetrahedra\n1\n1 2 3 4 0\nEnd\n");
  };
  const double L3 = std::pow(std::sqrt(2.0), 3);  // longest edge √2; 6V = the apex height
  EXPECT_EQ(read_tet_mesh(mesh_with(fmt::format("0.2 0.2 {:.17g}", 2 * kDegenerateTetrahedron * L3))).tets.size(), 1u);
  expect_format([&] { read_tet_mesh(mesh_with(fmt::format("0.2 0.2 {:.17g}", 0.5 * kDegenerateTetrahedron * L3))); },
                dir_ / "l.mesh", {":11:", "degenerate"});
  expect_format([&] { read_tet_mesh(mesh_with("0.2 0.2 1e13")); }, dir_ / "l.mesh", {":8:", "largest world coordinate"});
}

}  // namespace
}  // namespace quadrix

// The I/O kit's bounds on volume inputs: a data file that never ends, a small gzip bomb.
TEST(VolumeIoKit, DevZeroDataFileIsRefused) {
  if (!std::filesystem::exists("/dev/zero")) GTEST_SKIP() << "no /dev/zero";
  const auto dir = std::filesystem::temp_directory_path() / ("quadrix-volkit-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const auto h = dir / "zero.nhdr";
  std::ofstream(h) << "NRRD0004\ntype: uint8\ndimension: 3\nsizes: 1024 1024 1024\nencoding: raw\n"
                      "data file: /dev/zero\n";
  try {
    quadrix::read_volume(h);
    ADD_FAILURE() << "accepted";
  } catch (const quadrix::FormatError& e) {
    EXPECT_NE(std::string(e.what()).find("zero.nhdr"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("not a regular file"), std::string::npos) << e.what();
  }
  std::filesystem::remove_all(dir);
}

TEST(VolumeIoKit, InrGzBombIsNotInflatedWhole) {
  const auto dir = std::filesystem::temp_directory_path() / ("quadrix-volkit-gz-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const auto p = dir / "bomb.inr.gz";
  std::string header = "#INRIMAGE-4#{\nXDIM=8\nYDIM=8\nZDIM=8\nVDIM=1\nTYPE=unsigned fixed\nPIXSIZE=8 bits\nCPU=decm\n";
  header += std::string(256 - 4 - header.size(), '\n') + "##}\n";
  gzFile f = gzopen(p.string().c_str(), "wb9");
  gzwrite(f, header.data(), static_cast<unsigned>(header.size()));
  const std::string zeros(1 << 20, '\0');
  for (int i = 0; i < 256; ++i) gzwrite(f, zeros.data(), static_cast<unsigned>(zeros.size()));  // 256 MB
  gzclose(f);
  const auto t0 = std::chrono::steady_clock::now();
  try {
    quadrix::read_volume(p);
    ADD_FAILURE() << "accepted";
  } catch (const quadrix::FormatError& e) {
    EXPECT_NE(std::string(e.what()).find("bomb.inr.gz"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("768 bytes its header promises"), std::string::npos) << e.what();
  }
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 0.5);
  std::filesystem::remove_all(dir);
}
