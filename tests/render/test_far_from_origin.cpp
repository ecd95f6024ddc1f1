// Relative-to-eye rendering: tetrahedron patches (per-chunk origins), SLIM patches and glyphs
// (one origin per model) and meshes, moved 10⁴ and 10⁶ of its diagonals from the
// origin with the camera framed on it, renders as the CPU reference (double) does: depth p99
// ≤ 1e-5 of the depth range, normals p99 ≤ 0.1°, coverage agreement ≥ 99.9 % away from the
// silhouette. Meshes (not in the CPU reference) against their own render at the origin.
#include <gtest/gtest.h>

#include <random>

#include "convert/quads.h"
#include "core/reference.h"
#include "core/synth.h"
#include "tests/render/gl_compare.h"
#include "tests/render/gl_test.h"
#include "tests/render/random_models.h"

using namespace quadrix;
using Eigen::Vector3d;

namespace {

Model translated(Model m, const Vector3d& t) {
  for (auto& s : m.slims) s.centre += t;
  for (auto& p : m.tets)
    for (auto& c : p.corners) c += t;  // the quadric is relative to the centroid: unchanged
  for (auto& g : m.glyphs) g.centre += t;
  return m;
}

Model model_of(const std::string& kind) {
  if (kind == "quad-blob") {
    std::mt19937_64 rng(3);
    return convert_quads(test::random_quad_blob(rng, 6)).model;
  }
  return synth_model(kind, {.resolution = 8});
}

class FarFromOrigin : public GlTest, public ::testing::WithParamInterface<std::string> {};

}  // namespace

TEST_P(FarFromOrigin, MatchesTheCpuReference) {
  const Model at_origin = model_of(GetParam());
  ASSERT_FALSE(at_origin.empty());
  const double diagonal = bounds(at_origin).diagonal();
  for (const double k : {0.0, 1e4, 1e6}) {
    SCOPED_TRACE(testing::Message() << GetParam() << " at " << k << " diagonals");
    const Model m = translated(at_origin, k * diagonal * Vector3d(0.6, -0.48, 0.64));
    const Camera cam = frame_box(bounds(m), {.azimuth_deg = 35, .elevation_deg = 25, .width = 200, .height = 200});
    renderer_->set_model(m);
    renderer_->draw(cam, {});
    const render::GBuffer g = renderer_->read_gbuffer();
    const ReferenceImage ref = render_reference(ReferenceScene(m), cam);
    const testing_gl::Comparison c = testing_gl::compare(ref, g);
    {  // the truth itself: the reference far away equals the reference at the origin
      Camera c0 = cam;
      const Vector3d t = k * diagonal * Vector3d(0.6, -0.48, 0.64);
      c0.eye -= t, c0.target -= t;
      const ReferenceImage r0 = render_reference(ReferenceScene(at_origin), c0);
      render::GBuffer as_gl;
      as_gl.width = ref.width, as_gl.height = ref.height;
      as_gl.coverage = ref.coverage, as_gl.depth = ref.depth;
      as_gl.normal.resize(ref.normal.size());
      for (std::size_t i = 0; i < ref.normal.size(); ++i) as_gl.normal[i] = ref.normal[i].cast<float>();
      const testing_gl::Comparison rc = testing_gl::compare(r0, as_gl);
      EXPECT_GE(rc.coverage_agreement, 0.9999);
      EXPECT_LE(rc.depth_p99, 1e-9);
    }
    EXPECT_GT(c.covered, 3000);
    EXPECT_GE(c.coverage_agreement, 0.999);
    EXPECT_LE(c.depth_p99, 1e-5);
    EXPECT_LE(c.normal_p99_deg, 0.1);
    std::printf("%-12s %8.0e diagonals: coverage %.5f depth p99 %.2e normal p99 %.3f deg\n", GetParam().c_str(), k,
                c.coverage_agreement, c.depth_p99, c.normal_p99_deg);
  }
}

INSTANTIATE_TEST_SUITE_P(Kinds, FarFromOrigin,
                         ::testing::Values("hyperboloid1", "quad-blob", "slim-sphere", "glyphs"),
                         [](const auto& info) {
                           std::string n = info.param;
                           for (char& ch : n)
                             if (ch == '-') ch = '_';
                           return n;
                         });

class FarMesh : public GlTest {};

TEST_F(FarMesh, SameImageAsAtTheOrigin) {
  std::mt19937_64 rng(8);
  const PolygonMesh base = test::random_quad_blob(rng, 6);
  Box3 box;
  for (const auto& v : base.vertices) box.extend(v);
  const Camera cam0 = frame_box(box, {.azimuth_deg = 35, .elevation_deg = 25, .width = 200, .height = 200});
  renderer_->set_mesh(base);
  renderer_->draw(cam0, {});
  const render::GBuffer g0 = renderer_->read_gbuffer();
  float lo = INFINITY, hi = -INFINITY;
  int covered = 0;
  for (std::size_t i = 0; i < g0.coverage.size(); ++i)
    if (g0.coverage[i]) lo = std::min(lo, g0.depth[i]), hi = std::max(hi, g0.depth[i]), ++covered;
  ASSERT_GT(covered, 3000);
  for (const double k : {1e4, 1e6}) {
    SCOPED_TRACE(k);
    const Vector3d t = k * box.diagonal() * Vector3d(0.6, -0.48, 0.64);
    PolygonMesh mesh = base;
    for (auto& v : mesh.vertices) v += t;
    Camera cam = cam0;
    cam.eye += t;
    cam.target += t;
    renderer_->set_mesh(mesh);
    renderer_->draw(cam, {});
    const render::GBuffer g = renderer_->read_gbuffer();
    int mismatch = 0;
    std::vector<double> depth_err, normal_err;
    for (std::size_t i = 0; i < g.coverage.size(); ++i) {
      mismatch += g.coverage[i] != g0.coverage[i];
      if (!(g.coverage[i] && g0.coverage[i])) continue;
      depth_err.push_back(std::abs(double(g.depth[i]) - g0.depth[i]) / (hi - lo));
      normal_err.push_back(std::acos(std::clamp(double(g.normal[i].normalized().dot(g0.normal[i].normalized())), -1.0, 1.0)) *
                           180 / std::numbers::pi);
    }
    std::sort(depth_err.begin(), depth_err.end());
    std::sort(normal_err.begin(), normal_err.end());
    const double d99 = depth_err[depth_err.size() * 99 / 100], n99 = normal_err[normal_err.size() * 99 / 100];
    EXPECT_LE(mismatch, 0.001 * covered);
    EXPECT_LE(d99, 1e-5);
    EXPECT_LE(n99, 0.1);
    std::printf("mesh %8.0e diagonals: coverage mismatch %d of %d, depth p99 %.2e normal p99 %.3f deg\n", k, mismatch,
                covered, d99, n99);
  }
}
