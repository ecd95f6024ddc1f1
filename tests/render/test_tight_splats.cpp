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
  int tight = 0, points = 0, outside = 0;
  double thickness = 0;
  for (int i = 0; i < 3000; ++i) {
    const SlimPatch p = random_patch(rng);
    const SlimSlab slab = slim_patch_slab(p);
    if (!slab.tight) continue;
    ++tight;
    thickness += slab.s1 - slab.s0;
    std::vector<SlimSurfaceSample> samples;
    sample_slim_patch(p, 12, samples);
    for (const auto& s : samples) {
      const double along = ((s.point - p.centre) / p.radius).dot(slab.axis);
      ++points;
      outside += along < slab.s0 - 1e-9 || along > slab.s1 + 1e-9;
    }
  }
  EXPECT_EQ(outside, 0);
  EXPECT_GT(points, 100000);
  // Not vacuous: most patches get a slab, thinner than the ball on average.
  EXPECT_GT(tight, 1200);
  EXPECT_LT(thickness / tight, 1.0);
  std::printf("%d tight slabs of 3000, mean thickness %.3f (ball: 2), %d zero-set points\n", tight,
              thickness / tight, points);
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
