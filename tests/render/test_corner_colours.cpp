// Per-corner tetrahedron colours: the .qxm round trip, the GL tet pass against the CPU reference
// (both interpolate barycentrically), and skin surfaces whose neighbouring atoms' colours meet
// smoothly in the hyperboloid cells instead of in a step.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <unistd.h>

#include "convert/balls.h"
#include "convert/skin.h"
#include "core/camera.h"
#include "core/model_io.h"
#include "core/reference.h"
#include "core/shade.h"
#include "core/synth.h"
#include "render/renderer.h"
#include "tests/render/gl_test.h"

using namespace quadrix;

namespace {

// A colour that is affine in position, so barycentric interpolation reproduces it exactly.
Rgb colour_at(const Eigen::Vector3d& p) {
  const auto c = [](double v) { return static_cast<std::uint8_t>(std::clamp(std::lround(128 + 60 * v), 0L, 255L)); };
  return Rgb{c(p.x()), c(p.y()), c(-p.z())};
}

Model coloured_hyperboloid() {
  Model m = synth_model("hyperboloid1", {.resolution = 6});
  for (TetPatch& t : m.tets) {
    t.colour = Rgb{10, 10, 10};  // overridden by the corners
    t.corner_colours = std::array<Rgb, 4>{colour_at(t.corners[0]), colour_at(t.corners[1]), colour_at(t.corners[2]),
                                          colour_at(t.corners[3])};
  }
  return m;
}

}  // namespace

TEST(CornerColours, QxmRoundTrip) {
  Model m = coloured_hyperboloid();
  m.tets[1].corner_colours.reset();  // written as its colour at every corner
  m.tets[1].colour = Rgb{1, 2, 3};
  const auto path = std::filesystem::temp_directory_path() / ("corner_colours_" + std::to_string(::getpid()) + ".qxm");
  write_model(m, path);
  const Model r = read_model(path);
  std::filesystem::remove(path);
  ASSERT_EQ(r.tets.size(), m.tets.size());
  for (std::size_t i = 0; i < m.tets.size(); ++i) {
    ASSERT_TRUE(r.tets[i].corner_colours.has_value()) << "tet " << i;
    const Rgb c = m.tets[i].colour.value();
    const std::array<Rgb, 4> expected = m.tets[i].corner_colours.value_or(std::array<Rgb, 4>{c, c, c, c});
    EXPECT_EQ(*r.tets[i].corner_colours, expected) << "tet " << i;
    EXPECT_EQ(r.tets[i].colour, m.tets[i].colour) << "tet " << i;
  }
}

TEST(CornerColours, ReferenceInterpolatesInsideTheTetrahedron) {
  const Model m = coloured_hyperboloid();
  const ReferenceScene scene(m);
  const Camera cam = frame_box(bounds(m), {.width = 64, .height = 64});
  const ReferenceImage img = render_reference(scene, cam);
  int checked = 0;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * img.width + x;
      if (!img.coverage[i]) continue;
      TraceOptions both_sides;
      both_sides.cull_backfaces = false;
      const auto hit = scene.trace(cam.pixel_ray(x + 0.5, y + 0.5), 0, INFINITY, both_sides);
      ASSERT_TRUE(hit);
      const Rgb want = colour_at(hit->point);
      for (int c = 0; c < 3; ++c) EXPECT_LE(std::abs(int(img.albedo[i][c]) - int(want[c])), 2) << x << "," << y;
      ++checked;
    }
  EXPECT_GT(checked, 500);
}

class CornerColoursGl : public GlTest {};

TEST_F(CornerColoursGl, TetPassMatchesTheReference) {
  const Model m = coloured_hyperboloid();
  Model flat = m;
  for (TetPatch& t : flat.tets) t.corner_colours.reset();
  const Camera cam = frame_box(bounds(m), {.azimuth_deg = 40, .width = 128, .height = 128});
  const ReferenceScene scene(m);
  const ReferenceImage ref = render_reference(scene, cam);
  const Image8 cpu = shade_phong(ref, cam);
  renderer_->set_model(m);
  renderer_->draw(cam, {});
  const Image8 gl = renderer_->read_colour();
  renderer_->set_model(flat);
  renderer_->draw(cam, {});
  const Image8 gl_flat = renderer_->read_colour();
  std::vector<int> diff, diff_flat;
  for (int y = 1; y + 1 < ref.height; ++y)
    for (int x = 1; x + 1 < ref.width; ++x) {
      bool interior = true;  // away from silhouettes
      for (int d = -1; d <= 1; ++d)
        interior = interior && ref.coverage[(y + d) * ref.width + x] && ref.coverage[y * ref.width + x + d];
      if (!interior) continue;
      const std::size_t i = static_cast<std::size_t>(y) * ref.width + x;
      int worst = 0, worst_flat = 0;
      for (int c = 0; c < 3; ++c) {
        worst = std::max(worst, std::abs(int(gl.rgba[4 * i + c]) - int(cpu.rgba[4 * i + c])));
        worst_flat = std::max(worst_flat, std::abs(int(gl_flat.rgba[4 * i + c]) - int(cpu.rgba[4 * i + c])));
      }
      diff.push_back(worst);
      diff_flat.push_back(worst_flat);
    }
  ASSERT_GT(diff.size(), 2000u);
  std::sort(diff.begin(), diff.end());
  std::sort(diff_flat.begin(), diff_flat.end());
  const int median = diff[diff.size() / 2], p99 = diff[diff.size() * 99 / 100];
  std::printf("GL vs reference colour: median %d, p99 %d levels (flat colours: median %d)\n", median, p99,
              diff_flat[diff_flat.size() / 2]);
  EXPECT_LE(median, 2);
  EXPECT_LE(p99, 12);
  EXPECT_GE(diff_flat[diff_flat.size() / 2], 20) << "the corner colours must change the image";
}

// Two overlapping atoms, red and blue: along the skin their colours blend instead of jumping.
TEST(CornerColoursSkin, NeighbouringAtomsBlendSmoothly) {
  std::vector<Ball> balls(2);
  balls[0].centre = Eigen::Vector3d(-0.8, 0, 0);
  balls[0].colour = Rgb{230, 30, 30};
  balls[1].centre = Eigen::Vector3d(0.8, 0, 0);
  balls[1].colour = Rgb{30, 30, 230};
  const SkinConversion skin = convert_skin(balls);
  const Model& m = skin.model;
  ASSERT_FALSE(m.tets.empty());
  const ReferenceScene scene(m);
  const Camera cam = frame_box(bounds(m), {.azimuth_deg = 0, .elevation_deg = 0, .width = 160, .height = 96});
  const ReferenceImage img = render_reference(scene, cam);
  // The largest red step between horizontal neighbours along the middle rows, and how many
  // distinct reds appear (a step: two; a blend: many).
  int step = 0;
  std::vector<int> reds;
  for (int y = img.height / 2 - 5; y <= img.height / 2 + 5; ++y)
    for (int x = 0; x + 1 < img.width; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * img.width + x;
      if (!img.coverage[i] || !img.coverage[i + 1]) continue;
      step = std::max(step, std::abs(int(img.albedo[i][0]) - int(img.albedo[i + 1][0])));
      reds.push_back(img.albedo[i][0]);
    }
  std::sort(reds.begin(), reds.end());
  const auto distinct = std::unique(reds.begin(), reds.end()) - reds.begin();
  std::printf("skin: largest red step %d between neighbouring pixels, %td distinct reds\n", step, distinct);
  EXPECT_EQ(reds.front(), 30);
  EXPECT_EQ(reds.back(), 230);
  EXPECT_LE(step, 40);
  EXPECT_GE(distinct, 10);
}
