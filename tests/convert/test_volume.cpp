// Volume readers and quadratic iso-surfaces (issue 6, items 4, 5 and 7).
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
#include <set>
#include <cstring>
#include <string>
#include <unistd.h>
#include <vector>

#include <gtest/gtest.h>
#include <tbb/parallel_for.h>

#include "convert/volume.h"
#include "core/camera.h"
#include "core/error.h"
#include "core/reference.h"

namespace quadrix {
namespace {

namespace fs = std::filesystem;
using Eigen::Vector3d;

const fs::path kVolumes = fs::path(QUADRIX_DATASETS) / "volumes";

class TempDir : public ::testing::Test {
protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           (std::string("quadrix_") + info->test_suite_name() + "_" + info->name() + "_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  fs::path write(const std::string& name, const std::string& bytes) const {
    const fs::path p = dir_ / name;
    std::ofstream(p, std::ios::binary) << bytes;
    return p;
  }
  fs::path dir_;
};

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
                "'x' is not a number");
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

}  // namespace
}  // namespace quadrix
