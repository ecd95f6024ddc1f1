// Culling never hides what is visible (DESIGN §6, core/culling.h): for random open and closed
// models and random views, culling on and off give the same image (coverage and depth), in the
// CPU reference and on GL. Open surfaces (a quad sheet, a SLIM sphere with holes) stay.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "convert/quads.h"
#include "core/culling.h"
#include "core/reference.h"
#include "core/synth.h"
#include "render/context.h"
#include "render/renderer.h"
#include "tests/render/gl_test.h"
#include "tests/render/random_models.h"

using namespace quadrix;
using namespace quadrix::test;

namespace {

struct Images {
  std::vector<std::uint8_t> coverage;
  std::vector<float> depth;
};

// Pixels away from a's 1-pixel silhouette band where a and b differ in coverage, or in depth by
// more than tol relative to the depth range.
struct Difference {
  int covered = 0, differing = 0, differing_anywhere = 0;
};

Difference differ(const Images& a, const Images& b, int w, int h, double tol) {
  float dmin = INFINITY, dmax = -INFINITY;
  for (std::size_t i = 0; i < a.depth.size(); ++i)
    if (a.coverage[i]) dmin = std::min(dmin, a.depth[i]), dmax = std::max(dmax, a.depth[i]);
  const double range = std::max(1e-30f, dmax - dmin);
  Difference d;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * w + x;
      d.covered += a.coverage[i];
      const bool same = a.coverage[i] == b.coverage[i] &&
                        (!a.coverage[i] || std::abs(double(a.depth[i]) - b.depth[i]) <= tol * range);
      if (same) continue;
      ++d.differing_anywhere;
      bool edge = false;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int xx = std::clamp(x + dx, 0, w - 1), yy = std::clamp(y + dy, 0, h - 1);
          edge |= a.coverage[static_cast<std::size_t>(yy) * w + xx] != a.coverage[i];
        }
      d.differing += !edge;
    }
  return d;
}

Images reference_images(const Model& m, const Camera& cam, bool cull) {
  ReferenceRenderOptions o;
  o.trace.cull_backfaces = cull;
  const ReferenceImage r = render_reference(ReferenceScene(m), cam, o);
  return {r.coverage, r.depth};
}

// Random models and views: an open quad sheet, a closed quad blob (seen from outside and from
// inside), a SLIM sphere with holes. Each case names itself.
struct Case {
  std::string name;
  Model model;
  Camera camera;
};

std::vector<Case> random_cases(std::uint64_t seed, int count, int size) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<Case> cases;
  for (int k = 0; k < count; ++k) {
    const int kind = k % 4;
    Case c;
    FramingOptions f{.azimuth_deg = 360 * u(rng), .elevation_deg = -80 + 160 * u(rng), .width = size, .height = size};
    if (kind == 0) {
      c.name = "open quad sheet";
      c.model = convert_quads(random_quad_sheet(rng, 6)).model;
    } else if (kind == 1 || kind == 2) {
      c.name = kind == 1 ? "closed quad blob" : "closed quad blob, eye inside";
      c.model = convert_quads(random_quad_blob(rng, 4)).model;
    } else {
      c.name = "SLIM sphere with holes";
      Model full = synth_model("slim-sphere", {.count = 300, .seed = rng()});
      for (std::size_t i = 0; i < full.slims.size(); ++i)
        if (u(rng) > 0.25) c.model.slims.push_back(full.slims[i]);
    }
    c.camera = frame_box(bounds(c.model), f);
    if (kind == 2) {  // the eye in the blob's middle, looking out through its wall
      c.camera.eye = bounds(c.model).centre() + 0.1 * Eigen::Vector3d(u(rng), u(rng), u(rng));
      c.camera.fov_y_deg = 90;
      c.camera.near_plane = 0.01;
    }
    c.name += " #" + std::to_string(k);
    cases.push_back(std::move(c));
  }
  return cases;
}

}  // namespace

TEST(CullingExact, ClosedMeshesAreMarkedOpenOnesAreNot) {
  std::mt19937_64 rng(5);
  EXPECT_TRUE(surfaces_are_closed(convert_quads(random_quad_blob(rng, 3)).model));
  EXPECT_FALSE(surfaces_are_closed(convert_quads(random_quad_sheet(rng, 3)).model));
  PolygonMesh flipped = random_quad_blob(rng, 3);  // inward normals: its back sides face out
  for (std::size_t f = 0; f < flipped.face_count(); ++f)
    std::reverse(flipped.indices.begin() + flipped.offsets[f], flipped.indices.begin() + flipped.offsets[f + 1]);
  EXPECT_FALSE(surfaces_are_closed(convert_quads(flipped).model));
}

TEST(CullingExact, CpuReferenceCullingChangesNoPixel) {
  for (const Case& c : random_cases(11, 12, 96)) {
    SCOPED_TRACE(c.name);
    const Images on = reference_images(c.model, c.camera, true), off = reference_images(c.model, c.camera, false);
    const Difference d = differ(off, on, 96, 96, 1e-9);
    EXPECT_GT(d.covered, 300);
    EXPECT_EQ(d.differing_anywhere, 0);
  }
}

class CullingExactGl : public GlTest {
protected:
  Images draw(const Camera& cam, bool cull, render::FrameStats* stats = nullptr) {
    render::RenderOptions o;
    o.cull = cull;
    o.statistics = stats != nullptr;
    const auto st = renderer_->draw(cam, o);
    if (stats) *stats = st;
    const auto g = renderer_->read_gbuffer();
    return {g.coverage, g.depth};
  }
};

TEST_F(CullingExactGl, CullingChangesNoPixelAndMatchesTheReference) {
  constexpr int kSize = 128;
  for (const Case& c : random_cases(23, 16, kSize)) {
    SCOPED_TRACE(c.name);
    renderer_->set_model(c.model);
    const Images on = draw(c.camera, true), off = draw(c.camera, false);
    const Difference d = differ(off, on, kSize, kSize, 1e-5);
    EXPECT_GT(d.covered, 500);
    EXPECT_EQ(d.differing, 0);
    EXPECT_LE(d.differing_anywhere, d.covered / 500);  // silhouette pixels only
    // …and the culled GL image is the reference's (both ways the same image).
    const Difference r = differ(reference_images(c.model, c.camera, false), on, kSize, kSize, 1e-4);
    EXPECT_LE(r.differing, d.covered / 1000);
  }
}

TEST_F(CullingExactGl, OpenQuadSheetIsVisibleFromBothSides) {
  // The issue's case: an open sheet through convert quads rendered empty from behind with culling.
  std::mt19937_64 rng(3);
  const Model m = convert_quads(random_quad_sheet(rng, 8)).model;
  renderer_->set_model(m);
  for (const double el : {60.0, -60.0}) {
    SCOPED_TRACE(el);
    const Camera cam = frame_box(bounds(m), {.azimuth_deg = 10, .elevation_deg = el, .width = 96, .height = 96});
    const Images on = draw(cam, true);
    EXPECT_GT(std::count(on.coverage.begin(), on.coverage.end(), 1), 1500);
  }
}

TEST_F(CullingExactGl, ClosedModelsSeenFromOutsideAreStillCulled) {
  // Exactness must not switch the optimisation off where it is exact.
  std::mt19937_64 rng(8);
  const Model m = convert_quads(random_quad_blob(rng, 6)).model;
  ASSERT_TRUE(surfaces_are_closed(m));
  renderer_->set_model(m);
  const Camera cam = frame_box(bounds(m), {.azimuth_deg = 40, .elevation_deg = 20, .width = 96, .height = 96});
  render::FrameStats st;
  draw(cam, true, &st);
  EXPECT_GT(st.culled, st.primitives / 4);
}

TEST_F(CullingExactGl, SlimPatchesPastTheSilhouetteAreCulledByTheirSlab) {
  // A curved patch seen just past its silhouette faces away wherever its zero set is, but its
  // A·y term reaches across the whole ball, so the whole-ball test ([Stoll06] eq. 18) keeps it;
  // the ball cut by the patch's slab (core/slim.h slim_patch_slab) culls it. More culled than
  // the whole-ball test would, and still no pixel changed.
  // Sphere patches with a term λ(eᵀu)² along their normal e added, as a fit leaves that
  // coefficient free (its points lie at eᵀu ≈ 0): the zero set barely moves, A grows along e.
  constexpr int kSize = 128;
  Model m = synth_model("slim-sphere", {.count = 400});
  for (SlimPatch& p : m.slims) {
    const Eigen::Vector3d e = p.local.b.normalized();
    p.local.A += 0.25 * e * e.transpose();
  }
  renderer_->set_model(m);
  for (const double az : {0.0, 70.0, 200.0}) {
    SCOPED_TRACE(az);
    const Camera cam = frame_box(bounds(m), {.azimuth_deg = az, .elevation_deg = 25, .width = kSize, .height = kSize});
    std::size_t ball_test = 0;  // the whole-ball test, in double
    for (const SlimPatch& p : m.slims) {
      const Eigen::Vector3d y = (p.centre - cam.eye) / p.radius;  // the eye is −y in local units
      ball_test += p.local.c - y.dot(p.local.b) < -(p.local.b - p.local.A * y).norm();
    }
    render::FrameStats st;
    const Images on = draw(cam, true, &st), off = draw(cam, false);
    std::printf("culled %zu, whole-ball test %zu of %zu\n", static_cast<std::size_t>(st.culled), ball_test, m.slims.size());
    EXPECT_GT(st.culled, ball_test + m.slims.size() / 20);
    const Difference d = differ(off, on, kSize, kSize, 1e-5);
    EXPECT_GT(d.covered, 2000);
    EXPECT_EQ(d.differing, 0);
    EXPECT_LE(d.differing_anywhere, d.covered / 500);
  }
}
