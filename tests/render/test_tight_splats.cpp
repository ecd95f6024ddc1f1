// SLIM splats that bound the surface piece, not the ball (core/slim.h slim_patch_slab,
// slim.vert): the slab holds every zero-set point of its patch inside the ball, and over random
// models and views no covered pixel is lost — GL with tight splats gives the same G-buffer as
// with the ball's splats, and both match the CPU reference.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "core/reference.h"
#include "core/slim.h"
#include "core/synth.h"
#include "render/context.h"
#include "render/renderer.h"
#include "tests/render/gl_test.h"

using namespace quadrix;
using Eigen::Vector3d;

namespace {

Vector3d random_unit(std::mt19937_64& rng) {
  std::normal_distribution<double> n;
  return Vector3d(n(rng), n(rng), n(rng)).normalized();
}

// A patch whose zero set passes near its centre: random curvature, from nearly flat to strongly
// curved (sphere-like, saddles, cylinders), random gradient direction.
SlimPatch random_patch(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-1, 1);
  SlimPatch p;
  p.centre = Vector3d(u(rng), u(rng), u(rng));
  p.radius = 0.05 + 0.3 * (u(rng) + 1);
  const double curvature = std::pow(10.0, 1.5 * u(rng));  // 0.03 … 30 relative to the gradient
  Eigen::Matrix3d A;
  for (int i = 0; i < 3; ++i)
    for (int j = i; j < 3; ++j) A(i, j) = A(j, i) = curvature * u(rng);
  p.local.A = A;
  p.local.b = random_unit(rng);
  p.local.c = 0.6 * u(rng);
  return p;
}

}  // namespace

TEST(TightSplats, SlabHoldsEveryZeroSetPointOfItsBall) {
  std::mt19937_64 rng(17);
  int tight = 0, points = 0, outside = 0, wide = 0;
  double thickness = 0, area = 0, near_rim = 0;
  for (int i = 0; i < 3000; ++i) {
    const SlimPatch p = random_patch(rng);
    const SlimSlab slab = slim_patch_slab(p);
    if (!slab.tight) continue;
    ++tight;
    thickness += slab.s1 - slab.s0;
    // The frustum's side area against the cylinder of the slab's ball cross-section.
    const double h = slab.s1 - slab.s0, rho = (slab.s0 <= 0 && slab.s1 >= 0) ? 1.0 : std::sqrt(1 - std::min(slab.s0 * slab.s0, slab.s1 * slab.s1));
    area += (slab.r0 * slab.r0 + slab.r1 * slab.r1 + (slab.r0 + slab.r1) * std::hypot(slab.r1 - slab.r0, h)) / (2 * rho * rho + 2 * rho * h);
    std::vector<SlimSurfaceSample> samples;
    sample_slim_patch(p, 12, samples);
    double reach = 0;  // the samples' largest r over the frustum's r(s)
    for (const auto& s : samples) {
      const Vector3d u = (s.point - p.centre) / p.radius;
      const double along = u.dot(slab.axis), r = (u - along * slab.axis).norm();
      const double t = slab.s1 > slab.s0 ? (along - slab.s0) / (slab.s1 - slab.s0) : 0.5;
      const double limit = slab.r0 + (slab.r1 - slab.r0) * std::clamp(t, 0.0, 1.0);
      ++points;
      outside += along < slab.s0 - 1e-9 || along > slab.s1 + 1e-9;
      wide += r > limit + 1e-9;
      if (limit > 0) reach = std::max(reach, r / limit);
    }
    near_rim += reach;
  }
  EXPECT_EQ(outside, 0);
  EXPECT_EQ(wide, 0);  // every sample within the frustum
  EXPECT_GT(points, 100000);
  // Not vacuous: most patches get a slab, thinner than the ball on average; the frustums are no
  // larger than the slab's cylinders (random pieces mostly reach the ball's sphere across the
  // whole slab: 0.98 of their area, 5 narrow at one end), and the samples reach close to their
  // side (the bound is not loose).
  EXPECT_GT(tight, 1200);
  EXPECT_LT(thickness / tight, 1.0);
  EXPECT_LE(area / tight, 1.0);
  EXPECT_GT(near_rim / tight, 0.95);
  std::printf("%d tight slabs of 3000, mean thickness %.3f (ball: 2), frustum area / cylinder %.3f, samples reach "
              "%.3f of the frustum, %d zero-set points\n",
              tight, thickness / tight, area / tight, near_rim / tight, points);
}

TEST(TightSplats, ABowlsFrustumNarrowsTowardsItsBottom) {
  // z = x² + y² through the centre: the piece meets the ball's sphere at r = 0.786, z = 0.618,
  // and narrows to its bottom at the centre; a cylinder about its slab would be 1 wide.
  SlimPatch p;
  p.local.A = Eigen::Vector3d(1, 1, 0).asDiagonal();
  p.local.b = Vector3d(0, 0, -0.5);
  p.local.c = 0;
  const SlimSlab s = slim_patch_slab(p);
  ASSERT_TRUE(s.tight);
  const double flip = s.axis.z() < 0 ? -1 : 1;  // the axis is the gradient's: −z here
  const double bottom = flip > 0 ? s.s0 : -s.s1, top = flip > 0 ? s.s1 : -s.s0;
  const double r_bottom = flip > 0 ? s.r0 : s.r1, r_top = flip > 0 ? s.r1 : s.r0;
  EXPECT_LE(bottom, 0.0);
  EXPECT_GE(top, 0.618);
  EXPECT_LE(top, 0.618 + 2.0 / 64 + 1e-9);
  EXPECT_LT(r_bottom, 0.45);  // the line that gives the least area: 0.36
  EXPECT_GE(r_top, 0.786);
  EXPECT_LT(r_top, 0.9);
  std::vector<SlimSurfaceSample> samples;
  sample_slim_patch(p, 40, samples);
  ASSERT_GT(samples.size(), 1000u);
  for (const auto& x : samples) {
    const Vector3d u = x.point - p.centre;
    const double along = u.dot(s.axis), r = (u - along * s.axis).norm();
    EXPECT_LE(r, s.r0 + (s.r1 - s.r0) * (along - s.s0) / (s.s1 - s.s0) + 1e-9);
  }
  std::printf("bowl: s %.3f..%.3f, radii %.3f..%.3f\n", s.s0, s.s1, s.r0, s.r1);
}

TEST(TightSplats, PlaneGivesAThinSlabAndNoGradientTheBall) {
  SlimPatch p;
  p.local.A.setZero();
  p.local.b = Vector3d(0, 0, 1);
  p.local.c = -0.2;  // the plane z = 0.1 in local units
  const SlimSlab s = slim_patch_slab(p);
  ASSERT_TRUE(s.tight);
  EXPECT_LE(s.s0, 0.1);
  EXPECT_GE(s.s1, 0.1);
  EXPECT_LE(s.s1 - s.s0, 2.0 / 64 + 1e-12);  // one bin
  p.local.b.setZero();
  p.local.A.setIdentity();
  p.local.c = -0.25;  // a sphere about the centre: no gradient there, no slab
  EXPECT_FALSE(slim_patch_slab(p).tight);
}

class TightSplatsGl : public GlTest {
protected:
  render::GBuffer draw(const Camera& cam, bool tight, render::FrameStats& st, int sides = 4) {
    render::RenderOptions o;
    o.slim_tight_splats = tight;
    o.slim_splat_sides = sides;
    o.statistics = true;
    st = renderer_->draw(cam, o);
    return renderer_->read_gbuffer();
  }
};

TEST_F(TightSplatsGl, NoCoveredPixelLiesOutsideItsTightSplat) {
  // Random SLIM spheres and random patch soups, random views (some from close by, balls
  // straddling the near plane): tight splats change no pixel of the G-buffer.
  std::mt19937_64 rng(29);
  std::uniform_real_distribution<double> u(0, 1);
  constexpr int kSize = 128;
  std::uint64_t splat_tight = 0, splat_ball = 0, splat_octagon = 0;
  for (int k = 0; k < 10; ++k) {
    SCOPED_TRACE(k);
    Model m;
    if (k % 2 == 0) {
      m = synth_model("slim-sphere", {.count = 200 + 100 * k, .seed = rng()});
    } else {
      for (int i = 0; i < 150; ++i) m.slims.push_back(random_patch(rng));
    }
    renderer_->set_model(m);
    Camera cam = frame_box(bounds(m), {.azimuth_deg = 360 * u(rng), .elevation_deg = -80 + 160 * u(rng),
                                       .width = kSize, .height = kSize});
    if (k >= 8) {  // close: the eye near the model, wide field of view
      cam.eye = cam.target + (cam.eye - cam.target) * 0.35;
      cam.fov_y_deg = 90;
      cam.near_plane = 0.02;
    }
    // The tight rectangles and octagons against the balls' rectangles.
    render::FrameStats tight_st, ball_st, octagon_st;
    const render::GBuffer tight = draw(cam, true, tight_st), ball = draw(cam, false, ball_st),
                          octagon = draw(cam, true, octagon_st, 8);
    int covered = 0, differing = 0;
    for (std::size_t i = 0; i < ball.coverage.size(); ++i) {
      covered += ball.coverage[i];
      for (const render::GBuffer* g : {&tight, &octagon}) {
        const bool same = ball.coverage[i] == g->coverage[i] && ball.primitive[i] == g->primitive[i] &&
                          (!ball.coverage[i] || std::abs(ball.depth[i] - g->depth[i]) <= 1e-5f * ball.depth[i]);
        differing += !same;
      }
    }
    EXPECT_GT(covered, 800);
    EXPECT_EQ(differing, 0);
    // The same rays met their patches; the tight splats spent fewer fragments on it, the
    // polygons fewer than the rectangles.
    EXPECT_EQ(tight_st.slim_hit_fragments, ball_st.slim_hit_fragments);
    EXPECT_EQ(octagon_st.slim_hit_fragments, ball_st.slim_hit_fragments);
    EXPECT_LE(tight_st.slim_splat_fragments, ball_st.slim_splat_fragments);
    EXPECT_LE(octagon_st.slim_splat_fragments, tight_st.slim_splat_fragments);
    splat_tight += tight_st.slim_splat_fragments;
    splat_ball += ball_st.slim_splat_fragments;
    splat_octagon += octagon_st.slim_splat_fragments;
    // …and the image is the CPU reference's.
    const ReferenceImage ref = render_reference(ReferenceScene(m), cam);
    int agree = 0;
    for (std::size_t i = 0; i < ref.coverage.size(); ++i) agree += ref.coverage[i] == tight.coverage[i];
    EXPECT_GE(double(agree) / ref.coverage.size(), 0.995);
  }
  EXPECT_LT(splat_tight, splat_ball * 0.95);
  EXPECT_LT(splat_octagon, splat_tight * 0.97);
  std::printf("splat fragments: tight %llu, octagons %llu, ball %llu\n", (unsigned long long)splat_tight,
              (unsigned long long)splat_octagon, (unsigned long long)splat_ball);
}
