// The compact .qxm encoding (core/model_io.h): float32 values, positions relative to a float64
// origin. Round trips per element kind within the float32 bound, the rendered surface (CPU
// reference) within a stated fraction of the diagonal, models far from the world origin, the
// bytes per patch, and the fallback to the double encoding.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "core/camera.h"
#include "core/error.h"
#include "core/model_io.h"
#include "core/reference.h"
#include "core/synth.h"
#include "tests/core/malformed_corpus.h"

namespace quadrix {
namespace {

using test::make_sample_model;
using test::ScratchDir;

constexpr double kUlp = 0x1.0p-24;  // float32 rounding, relative

WriteModelResult write(const Model& m, const std::filesystem::path& p, ModelEncoding e = ModelEncoding::compact) {
  return write_model(m, p, {.encoding = e, .fallback_to_full = false});
}

/// The origin a compact file was written about (its quadrix-origin line).
Eigen::Vector3d origin_of(const std::filesystem::path& p) {
  const std::string bytes = test::read_bytes(p);
  const std::size_t at = bytes.find("comment quadrix-origin ");
  EXPECT_NE(at, std::string::npos);
  Eigen::Vector3d o;
  std::sscanf(bytes.c_str() + at + 23, "%lf %lf %lf", &o.x(), &o.y(), &o.z());
  return o;
}

double rel(double a, double b) { return std::abs(a - b) / std::max(std::abs(a), 1e-300); }

/// Largest change of a coefficient relative to its own size.
double coefficient_error(const Quadric& a, const Quadric& b) {
  const auto x = a.coefficients(), y = b.coefficients();
  double e = 0;
  for (std::size_t i = 0; i < x.size(); ++i) e = std::max(e, x[i] == 0 ? std::abs(y[i]) : rel(x[i], y[i]));
  return e;
}

/// Every value of b within the float32 bound of a: positions within 2⁻²⁴ of their distance from
/// origin per axis (plus the rounding of the sum), other values within 2⁻²⁴ relative.
void expect_within_float32(const Model& a, const Model& b, const Eigen::Vector3d& origin) {
  const auto position_ok = [&](const Eigen::Vector3d& x, const Eigen::Vector3d& y) {
    const Eigen::Vector3d bound = (x - origin).cwiseAbs() * kUlp + x.cwiseAbs() * 0x1.0p-52;
    return ((x - y).cwiseAbs().array() <= bound.array()).all();
  };
  ASSERT_EQ(a.slims.size(), b.slims.size());
  ASSERT_EQ(a.tets.size(), b.tets.size());
  ASSERT_EQ(a.glyphs.size(), b.glyphs.size());
  for (std::size_t i = 0; i < a.slims.size(); ++i) {
    const SlimPatch &x = a.slims[i], &y = b.slims[i];
    EXPECT_TRUE(position_ok(x.centre, y.centre)) << "slim " << i;
    EXPECT_LE(rel(x.radius, y.radius), kUlp) << "slim " << i;
    EXPECT_LE(coefficient_error(x.local, y.local), kUlp) << "slim " << i;
    ASSERT_EQ(x.clips.size(), y.clips.size()) << "slim " << i;
    for (int k = 0; k < x.clips.size(); ++k)
      EXPECT_LE((x.clips[k].n - y.clips[k].n).norm() + std::abs(x.clips[k].d - y.clips[k].d), 4 * kUlp) << i;
    EXPECT_EQ(x.colour, y.colour) << "slim " << i;
  }
  for (std::size_t i = 0; i < a.tets.size(); ++i) {
    for (int k = 0; k < 4; ++k) EXPECT_TRUE(position_ok(a.tets[i].corners[k], b.tets[i].corners[k])) << "tet " << i;
    // The quadric moved with the centroid: compare both in world coordinates at the corners.
    for (int k = 0; k < 4; ++k) {
      const Eigen::Vector3d p = b.tets[i].corners[k];
      const double fa = a.tets[i].quadric.eval(p - a.tets[i].centroid());
      const double fb = b.tets[i].quadric.eval(p - b.tets[i].centroid());
      EXPECT_LE(std::abs(fa - fb), 1e-5 * a.tets[i].quadric.max_abs_coefficient()) << "tet " << i;
    }
    EXPECT_EQ(a.tets[i].colour, b.tets[i].colour) << "tet " << i;
  }
  for (std::size_t i = 0; i < a.glyphs.size(); ++i) {
    const Glyph &x = a.glyphs[i], &y = b.glyphs[i];
    EXPECT_EQ(x.kind, y.kind);
    EXPECT_TRUE(position_ok(x.centre, y.centre)) << "glyph " << i;
    EXPECT_LE(rel(x.radius, y.radius), kUlp) << "glyph " << i;
    EXPECT_LE((x.axes - y.axes).cwiseAbs().maxCoeff(), kUlp * x.axes.cwiseAbs().maxCoeff()) << "glyph " << i;
    EXPECT_EQ(x.colour, y.colour) << "glyph " << i;
  }
}

struct DepthDifference {
  double max_rel = 0;          ///< max |Δdepth| over pixels both images cover, / diagonal
  double max_normal_rel = 0;   ///< max |Δt·(n·dir)|: the surface's move along its normal, / diagonal
  std::size_t coverage_flips = 0;
  std::size_t covered = 0;
};

/// The CPU reference's depth images of a and b from three directions.
DepthDifference depth_difference(const Model& a, const Model& b, int size = 160) {
  const ReferenceScene sa(a), sb(b);
  const Box3 box = bounds(a);
  DepthDifference d;
  for (const double az : {30.0, 150.0, 260.0}) {
    const Camera cam = frame_box(box, {.azimuth_deg = az, .elevation_deg = 25, .width = size, .height = size});
    const ReferenceImage ia = render_reference(sa, cam), ib = render_reference(sb, cam);
    for (std::size_t p = 0; p < ia.depth.size(); ++p) {
      if (ia.coverage[p] != ib.coverage[p]) ++d.coverage_flips;
      if (!ia.coverage[p] || !ib.coverage[p]) continue;
      ++d.covered;
      d.max_rel = std::max(d.max_rel, std::abs(double(ia.depth[p]) - double(ib.depth[p])) / box.diagonal());
      const Ray ray = cam.pixel_ray(double(p % size) + 0.5, double(p / size) + 0.5);
      const double cosine = std::abs(ia.normal[p].cast<double>().dot(ray.dir));
      d.max_normal_rel = std::max(
          d.max_normal_rel, std::abs(double(ia.distance[p]) - double(ib.distance[p])) * cosine / box.diagonal());
    }
  }
  return d;
}

Model translated(Model m, const Eigen::Vector3d& d) {
  for (auto& s : m.slims) s.centre += d;
  for (auto& t : m.tets)
    for (auto& p : t.corners) p += d;  // the quadric is relative to the centroid: unchanged
  for (auto& g : m.glyphs) g.centre += d;
  return m;
}

TEST(ModelIoCompact, EveryElementKindRoundTripsWithinFloat32) {
  ScratchDir dir("compact");
  for (const bool optional : {false, true}) {
    const Model m = make_sample_model(optional);
    const WriteModelResult w = write(m, dir / "m.qxm");
    EXPECT_EQ(w.encoding, ModelEncoding::compact);
    EXPECT_TRUE(w.fallback.empty()) << w.fallback;
    EXPECT_EQ(w.bytes, std::filesystem::file_size(dir / "m.qxm"));
    const Model r = read_model(dir / "m.qxm");
    expect_within_float32(m, r, origin_of(dir / "m.qxm"));
    EXPECT_EQ(r.metadata.at("producer"), m.metadata.at("producer"));
    EXPECT_EQ(r.metadata.count("quadrix-origin") + r.metadata.count("quadrix-encoding"), 0u);
    // Written again compact, the re-read model reads back within the same bound.
    write(r, dir / "m2.qxm");
    expect_within_float32(r, read_model(dir / "m2.qxm"), origin_of(dir / "m2.qxm"));
  }
}

TEST(ModelIoCompact, HierarchyRoundTripsWithFloatErrors) {
  ScratchDir dir("compact");
  Model m = synth_model("slim-sphere", {.count = 40});
  // A two-level hierarchy: every drawn ball under one of two interior balls.
  m.slim_hierarchy.others = {m.slims[0], m.slims[1]};
  m.slim_hierarchy.others[0].radius = 1.5;
  m.slim_hierarchy.others[1].radius = 1.7;
  for (std::size_t i = 0; i < m.slims.size(); ++i) {
    m.slim_hierarchy.parent.push_back(static_cast<std::int32_t>(m.slims.size() + i % 2));
    m.slim_hierarchy.error.push_back(1e-3 / 3 * static_cast<double>(i + 1));
  }
  m.slim_hierarchy.parent.insert(m.slim_hierarchy.parent.end(), {-1, -1});
  m.slim_hierarchy.error.insert(m.slim_hierarchy.error.end(), {0.1, 0.2});
  write(m, dir / "h.qxm");
  const std::string bytes = test::read_bytes(dir / "h.qxm");
  EXPECT_NE(bytes.find("property int parent\nproperty float error\n"), std::string::npos);
  const Model r = read_model(dir / "h.qxm");
  EXPECT_EQ(r.slim_hierarchy.parent, m.slim_hierarchy.parent);
  ASSERT_EQ(r.slim_hierarchy.error.size(), m.slim_hierarchy.error.size());
  for (std::size_t i = 0; i < m.slim_hierarchy.error.size(); ++i)
    EXPECT_LE(rel(m.slim_hierarchy.error[i], r.slim_hierarchy.error[i]), kUlp);
  ASSERT_EQ(r.slim_hierarchy.others.size(), 2u);
  EXPECT_LE(rel(r.slim_hierarchy.others[1].radius, 1.7), kUlp);
}

TEST(ModelIoCompact, RequiredFieldsTakeAtMost64BytesPerSlimAnd100PerTet) {
  // Bytes per patch: the body's size over the patch count.
  ScratchDir dir("compact");
  const auto bytes_per_patch = [&](const Model& one, const Model&, ModelEncoding e) {
    const std::size_t total = write(one, dir / "a.qxm", e).bytes;
    const std::string bytes = test::read_bytes(dir / "a.qxm");
    EXPECT_EQ(bytes.size(), total);
    return static_cast<double>(total - (bytes.find("end_header\n") + 11)) / static_cast<double>(one.size());
  };
  Model slim1 = synth_model("slim-sphere", {.count = 200}), slim2 = synth_model("slim-sphere", {.count = 400});
  Model tet1 = synth_model("hyperboloid1", {.resolution = 6}), tet2 = tet1;
  tet2.tets.insert(tet2.tets.end(), tet1.tets.begin(), tet1.tets.end());
  for (Model* m : {&slim1, &slim2, &tet1, &tet2}) {  // required fields only
    for (auto& s : m->slims) s.colour.reset(), s.clips.clear();
    for (auto& t : m->tets) t.colour.reset();
  }
  const double slim_compact = bytes_per_patch(slim1, slim2, ModelEncoding::compact);
  const double slim_double = bytes_per_patch(slim1, slim2, ModelEncoding::full);
  const double tet_compact = bytes_per_patch(tet1, tet2, ModelEncoding::compact);
  const double tet_double = bytes_per_patch(tet1, tet2, ModelEncoding::full);
  std::printf("bytes per patch: slim %g compact, %g double; tet %g compact, %g double\n", slim_compact, slim_double,
              tet_compact, tet_double);
  EXPECT_EQ(slim_compact, 56.0);
  EXPECT_EQ(tet_compact, 88.0);
  EXPECT_LE(slim_compact, 64.0);
  EXPECT_LE(tet_compact, 100.0);
  EXPECT_EQ(slim_double, 112.0);
  EXPECT_EQ(tet_double, 176.0);
}

TEST(ModelIoCompact, RenderedSurfaceMovesByLessThanAMillionthOfTheDiagonal) {
  // Round trip of analytic models of every primitive kind, compared as the CPU reference's depth
  // images: the stated round-trip error of the compact encoding.
  ScratchDir dir("compact");
  for (const char* kind : {"slim-sphere", "hyperboloid1", "glyphs"}) {
    SCOPED_TRACE(kind);
    const Model m = synth_model(kind, {});
    write(m, dir / "m.qxm");
    const Model r = read_model(dir / "m.qxm");
    const DepthDifference d = depth_difference(m, r);
    std::printf("%s: %zu primitives; over %zu pixels the surface moved by at most %.3g of the diagonal along its "
                "normal (depth: %.3g at grazing pixels); %zu coverage flips\n",
                kind, m.size(), d.covered, d.max_normal_rel, d.max_rel, d.coverage_flips);
    EXPECT_GT(d.covered, 10000u);
    EXPECT_LE(d.max_normal_rel, 1e-6);
    EXPECT_LE(d.max_rel, 1e-5);
    EXPECT_LE(d.coverage_flips, d.covered / 1000);
  }
}

TEST(ModelIoCompact, ModelsFarFromTheWorldOriginKeepTheirAccuracy) {
  // The same model 10⁶ diagonals away: the origin in the header keeps float32 relative to the
  // model.s size; plain float32 world coordinates would move it by 10⁻³ to 10⁻² of its diagonal.
  ScratchDir dir("compact");
  for (const char* kind : {"slim-sphere", "hyperboloid2", "glyphs"}) {
    SCOPED_TRACE(kind);
    const Model near = synth_model(kind, {});
    const double diag = bounds(near).diagonal();
    const Eigen::Vector3d shift = Eigen::Vector3d(0.6, -0.48, 0.64) * 1e6 * diag;
    const Model far = translated(near, shift);
    write(far, dir / "far.qxm");
    const Model r = read_model(dir / "far.qxm");
    expect_within_float32(far, r, origin_of(dir / "far.qxm"));
    // Brought back by the same double shift, the surface is where the near model's is.
    const Model back = translated(r, -shift);
    double moved = 0;
    for (std::size_t i = 0; i < near.slims.size(); ++i) moved = std::max(moved, (near.slims[i].centre - back.slims[i].centre).norm());
    for (std::size_t i = 0; i < near.glyphs.size(); ++i) moved = std::max(moved, (near.glyphs[i].centre - back.glyphs[i].centre).norm());
    for (std::size_t i = 0; i < near.tets.size(); ++i)
      for (int k = 0; k < 4; ++k) moved = std::max(moved, (near.tets[i].corners[k] - back.tets[i].corners[k]).norm());
    // Double arithmetic at 10⁶ diagonals costs ~10⁶·2⁻⁵² ≈ 2e-10 of the diagonal; float32 about
    // the origin ~2⁻²⁴ of half the diagonal. Far below what plain float32 loses.
    EXPECT_LE(moved / diag, 1e-7);
    const double naive = std::abs(shift.x() - static_cast<double>(static_cast<float>(shift.x()))) / diag;
    std::printf("%s at 1e6 diagonals: positions moved %.3g of the diagonal (float32 world coordinates: up to %.3g)\n",
                kind, moved / diag, naive);
    const DepthDifference d = depth_difference(near, back, 96);
    EXPECT_LE(d.max_normal_rel, 1e-6);
    EXPECT_LE(d.coverage_flips, d.covered / 1000 + 2);
  }
}

TEST(ModelIoCompact, WhatFloat32CannotHoldFallsBackToDoubleOrIsRefused) {
  ScratchDir dir("compact");
  const Model good = make_sample_model(true);
  std::vector<std::pair<Model, std::string>> cases;
  {
    Model m = good;  // a coefficient beyond float range
    m.slims[1].local = Quadric::from_coefficients({1, 1, 1, 0, 0, 0, 0, 0, 0, -1e39});
    cases.emplace_back(m, "slim patch 1: its quadric's coefficients (largest 1e+39) do not fit float32");
  }
  {
    Model m = good;  // a tetrahedron too small for float32 at its distance from the origin
    const Eigen::Vector3d o(3.25, 1.5, -2.125);
    m.tets[2] = TetPatch::from_world({o, o + Eigen::Vector3d(1e-7, 0, 0), o + Eigen::Vector3d(0, 1e-7, 0),
                                      o + Eigen::Vector3d(0, 0, 1e-7)},
                                     Quadric::sphere(o, 5e-8));
    cases.emplace_back(m, "tet patch 2: float32 moves its position");
  }
  {
    Model m = good;  // a radius below float range
    m.glyphs[0].radius = 1e-46;
    cases.emplace_back(m, "glyph 0:");
  }
  for (const auto& [m, why] : cases) {
    SCOPED_TRACE(why);
    try {
      write_model(m, dir / "refused.qxm", {.encoding = ModelEncoding::compact, .fallback_to_full = false});
      ADD_FAILURE() << "no error";
    } catch (const InvalidInput& e) {
      EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("refused.qxm"), std::string::npos) << e.what();
    }
    EXPECT_FALSE(std::filesystem::exists(dir / "refused.qxm"));
    const WriteModelResult w = write_model(m, dir / "m.qxm");  // default: fall back
    EXPECT_EQ(w.encoding, ModelEncoding::full);
    EXPECT_NE(w.fallback.find(why), std::string::npos) << w.fallback;
    EXPECT_NE(test::read_bytes(dir / "m.qxm").find("comment quadrix-encoding double\n"), std::string::npos);
    const Model r = read_model(dir / "m.qxm");
    ASSERT_EQ(r.size(), m.size());
    EXPECT_EQ(r.slims[1].local.c, m.slims[1].local.c);  // lossless
    EXPECT_EQ(r.tets[2].corners[1], m.tets[2].corners[1]);
  }
}

TEST(ModelIoCompact, MalformedCompactHeadersAreFormatErrors) {
  ScratchDir dir("compact");
  write(make_sample_model(false), dir / "m.qxm");
  const std::string good = test::read_bytes(dir / "m.qxm");
  const std::size_t at = good.find("comment quadrix-origin ");
  const std::size_t eol = good.find('\n', at);
  const auto with_line = [&](const std::string& line) { return good.substr(0, at) + line + good.substr(eol + 1); };
  const std::vector<std::pair<std::string, std::string>> cases = {
      {with_line(""), "the compact encoding needs a 'comment quadrix-origin X Y Z' line"},
      {with_line("comment quadrix-origin 1 2\n"), "bad 'comment quadrix-origin 1 2' line (three finite numbers)"},
      {with_line("comment quadrix-origin 1 2 nan\n"), "bad 'comment quadrix-origin 1 2 nan'"},
      {with_line("comment quadrix-origin 1 2 3 4\n"), "bad 'comment quadrix-origin 1 2 3 4'"},
      {with_line("comment quadrix-origin 1 2 3x\n"), "bad 'comment quadrix-origin 1 2 3x'"},
      {with_line("comment quadrix-origin 1 2 3\ncomment quadrix-origin 1 2 3\n"), "two 'comment quadrix-origin' lines"},
      {[&] {
         std::string s = good;
         s.replace(s.find("quadrix-encoding compact"), 24, "quadrix-encoding zipped");
         return s;
       }(),
       "bad 'comment quadrix-encoding zipped' line (compact or double)"},
      {[&] {
         std::string s = good;
         s.replace(s.find("quadrix-format 4"), 16, "quadrix-format 2");
         return s;
       }(),
       "'comment quadrix-origin' needs quadrix-format 3 or later, the file says 2"},
      {good.substr(0, good.size() - 5), "element 'glyph' row 2"},
  };
  for (std::size_t i = 0; i < cases.size(); ++i) {
    SCOPED_TRACE(cases[i].second);
    const std::filesystem::path p = dir / ("bad" + std::to_string(i) + ".qxm");
    test::write_bytes(p, cases[i].first);
    try {
      read_model(p);
      ADD_FAILURE() << "no error";
    } catch (const FormatError& e) {
      EXPECT_NE(std::string(e.what()).find(cases[i].second), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(p.filename().string()), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace quadrix

namespace quadrix {
namespace {

TEST(ModelIoCompact, SliversFloat32FlattensAreLeftOutUpToOneInAThousand) {
  ScratchDir dir("compact");
  Model m = synth_model("hyperboloid1", {});
  ASSERT_GE(m.tets.size(), 1000u);
  // Height 1e-9 over a unit triangle: valid in double, flat once its corners are float32.
  const Eigen::Vector3d o(0.25, -0.5, 0.7);
  const TetPatch sliver = TetPatch::from_world(
      {o, o + Eigen::Vector3d(1, 0, 0), o + Eigen::Vector3d(0, 1, 0), o + Eigen::Vector3d(0.3, 0.3, 1e-9)},
      Quadric::plane(Eigen::Vector3d::UnitX(), -0.5));
  m.tets.push_back(sliver);
  const WriteModelResult w = write(m, dir / "m.qxm");
  EXPECT_EQ(w.encoding, ModelEncoding::compact);
  EXPECT_EQ(w.dropped_tets, 1u);
  EXPECT_EQ(read_model(dir / "m.qxm").tets.size(), m.tets.size() - 1);
  // Too many slivers: the double encoding, all of them kept.
  Model few;
  few.tets = {m.tets[0], sliver};
  const WriteModelResult f = write_model(few, dir / "f.qxm");
  EXPECT_EQ(f.encoding, ModelEncoding::full);
  EXPECT_NE(f.fallback.find("1 of 2 tetrahedra turn flat in float32"), std::string::npos) << f.fallback;
  EXPECT_EQ(f.dropped_tets, 0u);
  EXPECT_EQ(read_model(dir / "f.qxm").tets.size(), 2u);
}

}  // namespace
}  // namespace quadrix
