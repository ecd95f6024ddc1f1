// Large-but-legal models: whatever the readers accept (coordinates up to the ±1e12 world limit of
// core/limits.h, huge and tiny radii) either renders as the CPU reference does, or is refused
// with a clear InvalidInput before anything is drawn; never an empty, NaN or blank image.
// Every model goes through write_model and read_model first: these are models a file can hold.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>

#include "core/camera.h"
#include "core/error.h"
#include "core/limits.h"
#include "core/model_io.h"
#include "core/reference.h"
#include "core/synth.h"
#include "tests/render/gl_compare.h"
#include "tests/render/gl_test.h"

using namespace quadrix;
using Eigen::Vector3d;

namespace {

// Tetrahedron patches, SLIM patches and glyphs side by side, about 8 units across.
Model mixed_model() {
  Model m = synth_model("hyperboloid1", {.resolution = 4});
  const Model slims = synth_model("slim-sphere", {.count = 120});
  for (SlimPatch s : slims.slims) {
    s.centre += Vector3d(3.5, 0, 0);
    m.slims.push_back(s);
  }
  const Model glyphs = synth_model("glyphs", {.count = 12, .seed = 5});
  for (Glyph g : glyphs.glyphs) {
    g.centre = 0.4 * g.centre + Vector3d(-3.5, 0, 0);
    g.radius *= 0.4;
    g.axes *= 0.4;
    m.glyphs.push_back(g);
  }
  return m;
}

// x ↦ s·x + t for every primitive.
Model scaled(const Model& in, double s, const Vector3d& t) {
  Model m = in;
  for (auto& p : m.slims) p.centre = s * p.centre + t, p.radius *= s;  // the local quadric is unchanged
  for (auto& p : m.tets) {
    for (auto& c : p.corners) c = s * c + t;
    p.quadric = p.quadric.to_local(Vector3d::Zero(), 1.0 / s);  // f′(y) = f(y / s) about the centroid
  }
  for (auto& g : m.glyphs) g.centre = s * g.centre + t, g.radius *= s, g.axes *= s;
  return m;
}

Model one_sphere(const Vector3d& centre, double radius) {
  Model m;
  m.glyphs.push_back({GlyphKind::sphere, centre, radius, Eigen::Matrix3d::Identity(), Rgb{200, 80, 40}});
  return m;
}

// What a case must do: render as the reference (refusal empty) or be refused with a message
// holding `refusal`.
struct Case {
  std::string name;
  Model model;
  std::string refusal;
};

std::vector<Case> cases() {
  const Model base = mixed_model();
  const Vector3d dir(0.6, -0.48, 0.64);
  Model speck = one_sphere(Vector3d::Zero(), 1.0);
  speck.glyphs.push_back({GlyphKind::sphere, Vector3d(0.5, 0, 0), 1e-35, Eigen::Matrix3d::Identity(), std::nullopt});
  return {
      {"spans_the_world", scaled(base, 1e11, Vector3d::Zero()), ""},  // ±4e11, glyph radii to 6e10
      {"spans_to_the_limit_corner", scaled(base, 5e10, 6e11 * dir), ""},
      {"thousand_at_the_limit", scaled(base, 1e3, 0.99e12 * dir), ""},
      {"micro_at_the_origin", scaled(base, 1e-6, Vector3d::Zero()), ""},
      {"femto_at_the_origin", scaled(base, 1e-15, Vector3d::Zero()), ""},
      {"1e-24_at_the_origin", scaled(base, 1e-24, Vector3d::Zero()), ""},
      {"sphere_radius_1e12", one_sphere(Vector3d::Zero(), 1e12), ""},
      {"sphere_radius_1e12_at_1e12", one_sphere(Vector3d::Constant(1e12), 1e12), ""},
      {"sphere_radius_1e-30", one_sphere(Vector3d::Zero(), 1e-30), ""},
      {"sphere_radius_1e3_at_1e12", one_sphere(Vector3d::Constant(1e12), 1e3), ""},
      // Double resolves 1e12 to 1.2e-4: an 8-unit model there has depth p99 3e-5 (> 1e-5).
      {"unit_at_the_limit", scaled(base, 1.0, 0.99e12 * dir), "of its largest coordinate 6.336e+11"},
      {"sphere_radius_1e-3_at_1e12", one_sphere(Vector3d::Constant(1e12), 1e-3), "of its largest coordinate 1e+12"},
      {"1e-100_at_the_origin", scaled(base, 1e-100, Vector3d::Zero()), "the smallest size Quadrix draws"},
      {"sphere_radius_1e-300", one_sphere(Vector3d::Zero(), 1e-300), "its extent 2e-300 is below 1e-30"},
      {"sphere_radius_denormal", one_sphere(Vector3d::Zero(), 1e-310), "the smallest size Quadrix draws"},
      {"speck_beside_a_sphere", speck, "glyph 1: its size 1e-35 is below 1e-30"},
  };
}

class ExtremeModels : public GlTest {};

}  // namespace

TEST_F(ExtremeModels, RenderAsTheReferenceOrAreRefused) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("quadrix_extreme_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  for (const Case& c : cases()) {
    SCOPED_TRACE(c.name);
    // A model a file can hold: written and read back (double encoding where float32 cannot).
    const std::filesystem::path file = dir / (c.name + ".qxm");
    write_model(c.model, file);
    const Model m = read_model(file);
    ASSERT_EQ(m.size(), c.model.size());
    const Camera cam = frame_box(bounds(m), {.azimuth_deg = 35, .elevation_deg = 25, .width = 160, .height = 160});
    try {
      renderer_->set_model(m);
      renderer_->draw(cam, {});
    } catch (const InvalidInput& e) {
      std::printf("%-28s refused: %s\n", c.name.c_str(), e.what());
      EXPECT_FALSE(c.refusal.empty()) << "refused: " << e.what();
      EXPECT_NE(std::string(e.what()).find(c.refusal), std::string::npos) << e.what();
      continue;
    }
    EXPECT_TRUE(c.refusal.empty()) << "drawn, but should be refused with '" << c.refusal << "'";
    const render::GBuffer g = renderer_->read_gbuffer();
    const ReferenceImage ref = render_reference(ReferenceScene(m), cam);
    const testing_gl::Comparison cmp = testing_gl::compare(ref, g);
    int gl_covered = 0, not_finite = 0;
    for (std::size_t i = 0; i < g.coverage.size(); ++i)
      if (g.coverage[i]) {
        ++gl_covered;
        not_finite += !(std::isfinite(g.depth[i]) && g.normal[i].allFinite() && g.normal[i].norm() > 0.5f);
      }
    std::printf("%-28s covered %5d (GL %5d) agreement %.5f depth p99 %.2e normal p99 %.3f deg\n", c.name.c_str(),
                cmp.covered, gl_covered, cmp.coverage_agreement, cmp.depth_p99, cmp.normal_p99_deg);
    EXPECT_GT(cmp.covered, 2000);  // the model fills a good part of the 160² image
    EXPECT_EQ(not_finite, 0);
    EXPECT_GE(cmp.coverage_agreement, 0.999);
    EXPECT_LE(cmp.depth_p99, 1e-5);
    EXPECT_LE(cmp.normal_p99_deg, 0.1);
  }
  std::filesystem::remove_all(dir);
}
