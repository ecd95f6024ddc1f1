// Every GL context kind this machine has (OSMesa; EGL on its device and surfaceless platforms,
// with and without a pbuffer) draws every primitive kind the GL renderer has (tetrahedron patches,
// SLIM balls, glyphs, mesh triangles) as the CPU reference does.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <numbers>
#include <string>

#include "convert/volume.h"
#include "core/camera.h"
#include "core/io/polygon_mesh.h"
#include "core/primitive.h"
#include "core/reference.h"
#include "core/synth.h"
#include "render/context.h"
#include "render/renderer.h"
#include "tests/render/gl_compare.h"

using namespace quadrix;

namespace {

// Pixels the reference covers, away from its silhouette, that the GL image leaves empty.
int cracks(const ReferenceImage& ref, const render::GBuffer& gl) {
  int n = 0;
  for (int y = 0; y < ref.height; ++y)
    for (int x = 0; x < ref.width; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * ref.width + x;
      n += ref.coverage[i] && !gl.coverage[i] && !testing_gl::near_silhouette(ref.coverage, ref.width, ref.height, x, y);
    }
  return n;
}

struct Result : testing_gl::Comparison {
  int cracks = 0;
};

struct ContextCase {
  const char* name;            // create_context name
  const char* egl_platform;    // QUADRIX_EGL_PLATFORM, or nullptr
  bool egl_pbuffer = false;    // QUADRIX_EGL_PBUFFER=1
};

std::string case_name(const testing::TestParamInfo<ContextCase>& info) {
  std::string n = info.param.name;
  if (info.param.egl_platform) n += std::string("_") + info.param.egl_platform;
  if (info.param.egl_pbuffer) n += "_pbuffer";
  return n;
}

void PrintTo(const ContextCase& c, std::ostream* os) { *os << case_name({c, 0}); }

class GlContexts : public testing::TestWithParam<ContextCase> {
protected:
  void SetUp() override {
    const ContextCase& c = GetParam();
    // Each test runs in its own process (gtest_discover_tests), so the variables stay local to it.
    if (c.egl_platform) setenv("QUADRIX_EGL_PLATFORM", c.egl_platform, 1);
    else unsetenv("QUADRIX_EGL_PLATFORM");
    setenv("QUADRIX_EGL_PBUFFER", c.egl_pbuffer ? "1" : "0", 1);
    try {
      context_ = render::create_context(c.name);
    } catch (const std::exception& e) {
      GTEST_SKIP() << "no " << case_name({c, 0}) << " OpenGL 4.5 context on this machine: " << e.what();
    }
    ASSERT_EQ(context_->name(), std::string(c.name));
    std::printf("%s\n", context_->description().c_str());
    renderer_ = std::make_unique<render::Renderer>(*context_);
  }
  Result run(const Model& m, const Camera& cam, bool cull) {
    renderer_->set_model(m);
    render::RenderOptions options;
    options.cull = cull;
    renderer_->draw(cam, options);
    ReferenceRenderOptions ro;
    ro.trace.cull_backfaces = cull;
    const ReferenceImage ref = render_reference(ReferenceScene(m), cam, ro);
    const render::GBuffer gl = renderer_->read_gbuffer();
    Result c{testing_gl::compare(ref, gl)};
    c.cracks = cracks(ref, gl);
    std::printf("coverage %.5f depth p99 %.3g normal median %.4f deg cracks %d (%d covered)\n", c.coverage_agreement,
                c.depth_p99, c.normal_median_deg, c.cracks, c.covered);
    return c;
  }
  std::unique_ptr<render::GlContext> context_;
  std::unique_ptr<render::Renderer> renderer_;
};

// The tolerances of an exact primitive against the CPU reference (tetrahedra, glyphs).
void expect_exact(const Result& c, int min_covered) {
  EXPECT_GT(c.covered, min_covered);
  EXPECT_GE(c.coverage_agreement, 0.999);
  EXPECT_LE(c.depth_p99, 1e-5);
  EXPECT_LE(c.normal_median_deg, 0.1);
}

TEST_P(GlContexts, TetrahedronPatchesMatchTheCpuReference) {
  for (const char* kind : {"hyperboloid1", "hyperboloid2"})
    for (const bool cull : {false, true}) {
      SCOPED_TRACE(testing::Message() << kind << " cull=" << cull);
      const Model m = synth_model(kind, {.resolution = 8});
      const Camera cam = frame_box(bounds(m), {.azimuth_deg = 35, .elevation_deg = 25, .width = 160, .height = 128});
      expect_exact(run(m, cam, cull), 1500);
    }
}

TEST_P(GlContexts, VolumeIsoSurfacePatchesMatchTheCpuReference) {
  const Model m = convert_volume(marschner_lobb_volume(13), {.iso = 0.5}).model;
  ASSERT_GT(m.tets.size(), 100u);
  const Camera cam = frame_box(bounds(m), {.azimuth_deg = 35, .elevation_deg = 30, .width = 160, .height = 160});
  expect_exact(run(m, cam, true), 3000);
}

TEST_P(GlContexts, SlimBallsMatchTheCpuBlend) {
  const Model m = synth_model("slim-sphere", {.count = 300});
  const Camera cam = frame_box(bounds(m), {.azimuth_deg = 70, .elevation_deg = 30, .width = 160, .height = 160});
  const auto c = run(m, cam, false);
  EXPECT_GT(c.covered, 3000);
  EXPECT_GE(c.coverage_agreement, 0.995);
  EXPECT_LE(c.normal_median_deg, 0.5);
  EXPECT_EQ(c.cracks, 0);
}

TEST_P(GlContexts, GlyphsMatchTheCpuReference) {
  // Spheres, ellipsoids and capped cylinders, alone and mixed (synth "glyphs": 7 : 2 : 1).
  for (const char* kind : {"sphere", "ellipsoid", "cylinder", "glyphs"}) {
    SCOPED_TRACE(kind);
    const Model m = synth_model(kind, {.count = 60});
    const Camera cam = frame_box(bounds(m), {.azimuth_deg = 35, .elevation_deg = 25, .width = 160, .height = 128});
    const auto c = run(m, cam, false);
    expect_exact(c, 1500);
    EXPECT_EQ(c.cracks, 0);
  }
}

TEST_P(GlContexts, MeshTrianglesLieOnTheirPlane) {
  // A square facing the camera at view depth D: its pixels are the projected square's, at depth D
  // with the normal towards the eye (the reference draws no meshes, so the truth is analytic).
  Camera cam;
  cam.eye = Eigen::Vector3d(1, 2, 3);
  cam.target = Eigen::Vector3d(-2, 0.5, -4);
  cam.fov_y_deg = 50;
  cam.near_plane = 0.1;
  cam.far_plane = 100;
  cam.width = 200, cam.height = 160;
  const double D = 5, s = 1.2;
  const Eigen::Vector3d f = cam.forward(), right = f.cross(cam.up).normalized(), up = right.cross(f);
  const Eigen::Vector3d centre = cam.eye + D * f;
  PolygonMesh square;
  for (const auto& [a, b] : {std::pair{-1, -1}, {1, -1}, {1, 1}, {-1, 1}})
    square.vertices.push_back(centre + s * (a * right + b * up));
  square.add_face(std::array{0, 1, 2, 3});
  renderer_->set_model(Model{});
  renderer_->set_mesh(square);
  renderer_->draw(cam, {});
  const auto gl = renderer_->read_gbuffer();
  const double half_px = s / (D * std::tan(cam.fov_y_deg * std::numbers::pi / 360.0)) * cam.height / 2;
  int pixels = 0;
  double worst_depth = 0, worst_normal = 0;
  for (std::size_t i = 0; i < gl.coverage.size(); ++i) {
    if (!gl.coverage[i]) continue;
    ++pixels;
    EXPECT_EQ(primitive_kind(gl.primitive[i]), PrimitiveKind::mesh);
    worst_depth = std::max(worst_depth, std::abs(gl.depth[i] - D) / D);
    worst_normal = std::max(worst_normal, std::acos(std::clamp(-double(gl.normal[i].normalized().cast<double>().dot(f)), -1.0, 1.0)));
  }
  const double expected = 4 * half_px * half_px;
  std::printf("mesh pixels %d (analytic %.0f), depth error %.3g, normal error %.3g deg\n", pixels, expected,
              worst_depth, worst_normal * 180 / std::numbers::pi);
  EXPECT_NEAR(pixels, expected, 4 * 2 * half_px + 4);  // one pixel row along each edge
  EXPECT_LE(worst_depth, 1e-5);
  EXPECT_LE(worst_normal * 180 / std::numbers::pi, 0.01);
}

INSTANTIATE_TEST_SUITE_P(Contexts, GlContexts,
                         testing::Values(ContextCase{"osmesa", nullptr}, ContextCase{"egl", "device"},
                                         ContextCase{"egl", "surfaceless"}, ContextCase{"egl", "surfaceless", true}),
                         case_name);

TEST(GlContextChoice, AutoPrefersEglWhereItWorks) {
  unsetenv("QUADRIX_EGL_PLATFORM");
  unsetenv("QUADRIX_EGL_PBUFFER");
  std::unique_ptr<render::GlContext> egl;
  try {
    egl = render::create_context("egl");
  } catch (const std::exception& e) {
    GTEST_SKIP() << "EGL does not work on this machine: " << e.what();
  }
  egl.reset();
  EXPECT_EQ(render::create_context("auto")->name(), "egl");
}

}  // namespace
