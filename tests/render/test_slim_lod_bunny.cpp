// SLIM level of detail on a real hierarchy: Kanai's .slim2t bunny (69,451 leaves, energies as
// errors, so distances measured on load). At 0.5 px the cut is a fraction of the leaves, GL draws
// it as the CPU reference does, and its covered pixels stay within 2 % of full detail's.
#include <gtest/gtest.h>

#include <filesystem>

#include "core/model_io.h"
#include "core/reference.h"
#include "core/slim_lod.h"
#include "render/renderer.h"
#include "tests/render/gl_compare.h"
#include "tests/render/gl_test.h"

using namespace quadrix;

class GlSlimLodBunny : public GlTest {};

TEST_F(GlSlimLodBunny, HalfAPixelCutMatchesTheReferenceAndStaysCloseToFullDetail) {
  const auto path = std::filesystem::path(QUADRIX_DATASETS) / "slim" / "bunny_mesh2slim.slim2t";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "dataset missing: " << path;
  const Model m = read_model(path);
  const Camera cam = frame_box(bounds(m), {.azimuth_deg = 30, .elevation_deg = 20, .width = 192, .height = 192});
  const SlimLodCut cut = select_slim_lod(m, cam, {.pixel_error = 0.5});
  EXPECT_LT(cut.balls.size(), m.slims.size() / 4);
  EXPECT_GT(cut.level_counts.size(), 3u);
  renderer_->set_model(m);
  render::RenderOptions o;
  o.slim_pixel_error = 0.5;
  EXPECT_EQ(renderer_->draw(cam, o).slim_balls, cut.balls.size());
  const render::GBuffer lod = renderer_->read_gbuffer();
  const Model cut_model = slim_cut_model(m, cut.balls);
  const ReferenceScene scene(cut_model);
  const auto c = testing_gl::compare(render_reference(scene, cam), lod);
  EXPECT_GE(c.coverage_agreement, 0.995);
  EXPECT_LE(c.depth_p99, 2e-3);
  o.slim_pixel_error = 0;
  renderer_->draw(cam, o);
  const render::GBuffer full = renderer_->read_gbuffer();
  std::size_t diff = 0, covered = 0;
  for (std::size_t i = 0; i < full.coverage.size(); ++i) diff += full.coverage[i] != lod.coverage[i], covered += full.coverage[i];
  EXPECT_GT(covered, 5000u);
  EXPECT_LE(double(diff) / double(covered), 0.02);
  std::printf("bunny at 192²: %zu of %zu leaves' worth, symmetric difference %.4f of %zu covered\n", cut.balls.size(),
              m.slims.size(), double(diff) / double(covered), covered);
}
