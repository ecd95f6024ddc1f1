// Spatial chunks of tetrahedra (render/passes/chunks.h): the frustum and occlusion tests never
// drop a chunk that could show, and the chunked, front-to-back, entry-face-depth frame gives the
// same G-buffer as each fragment writing its hit's depth, and as the CPU reference — from
// outside, zoomed into a corner, and (GL against GL) with the eye inside the model.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "convert/volume.h"
#include "core/reference.h"
#include "render/passes/chunks.h"
#include "tests/render/gl_compare.h"
#include "tests/render/gl_test.h"

using namespace quadrix;
using namespace quadrix::render;
using Eigen::Vector3d;

namespace {

Box3 box_of(const Vector3d& lo, const Vector3d& hi) {
  Box3 b;
  b.extend(lo);
  b.extend(hi);
  return b;
}

// Pixels where the two G-buffers differ in coverage, and the largest depth difference where
// both are covered, relative to the depth range.
struct Difference {
  int coverage = 0;
  double depth = 0;
};
Difference difference(const GBuffer& a, const GBuffer& b) {
  Difference d;
  float lo = INFINITY, hi = -INFINITY;
  for (std::size_t i = 0; i < a.coverage.size(); ++i)
    if (a.coverage[i]) lo = std::min(lo, a.depth[i]), hi = std::max(hi, a.depth[i]);
  for (std::size_t i = 0; i < a.coverage.size(); ++i) {
    d.coverage += a.coverage[i] != b.coverage[i];
    if (a.coverage[i] && b.coverage[i])
      d.depth = std::max(d.depth, std::abs(double(a.depth[i]) - b.depth[i]) / std::max(1e-30, double(hi - lo)));
  }
  return d;
}

}  // namespace

TEST(Chunks, EveryPrimitiveInExactlyOneChunkWhoseBoxHoldsIt) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-10, 10);
  std::vector<Box3> boxes;
  for (int i = 0; i < 5000; ++i) {
    const Vector3d c(u(rng), u(rng), u(rng));
    boxes.push_back(box_of(c, c + Vector3d::Constant(0.1)));
  }
  const Chunks c = make_chunks(boxes, {.chunk_size = 64});
  ASSERT_EQ(c.size(), (5000u + 63) / 64);
  std::vector<int> seen(boxes.size(), 0);
  double volume = 0;
  for (std::size_t k = 0; k < c.size(); ++k) {
    for (std::uint32_t s = c.first[k]; s < c.first[k] + c.count[k]; ++s) {
      ++seen[c.order[s]];
      const Box3& b = boxes[c.order[s]];
      EXPECT_TRUE((b.min.array() >= c.boxes[k].min.array()).all() && (b.max.array() <= c.boxes[k].max.array()).all());
    }
    volume += (c.boxes[k].max - c.boxes[k].min).prod();
  }
  EXPECT_TRUE(std::all_of(seen.begin(), seen.end(), [](int n) { return n == 1; }));
  // Morton order makes the chunks compact: in input order each box would span most of the scene.
  EXPECT_LT(volume, 0.1 * c.size() * 20 * 20 * 20);
}

TEST(Chunks, FrustumKeepsEveryChunkWithAPointInViewNearestFirst) {
  // Random small boxes and random views: a box any of whose sample points projects inside the
  // image between near and far is kept; the kept ones come nearest first.
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> u(-10, 10);
  for (int view = 0; view < 20; ++view) {
    std::vector<Box3> boxes;
    for (int i = 0; i < 400; ++i) {
      const Vector3d c(u(rng), u(rng), u(rng));
      boxes.push_back(box_of(c, c + Vector3d::Constant(0.5)));
    }
    const Chunks chunks = make_chunks(boxes, {.chunk_size = 1});
    Camera cam;
    cam.eye = Vector3d(u(rng), u(rng), u(rng));
    cam.target = Vector3d(u(rng), u(rng), u(rng)) * 0.3;
    cam.fov_y_deg = 20 + 3 * (u(rng) + 10);
    cam.width = 200, cam.height = 120;
    cam.near_plane = 0.5, cam.far_plane = 15;
    const ChunkSelection sel = select_chunks(chunks, cam);
    std::vector<bool> kept(chunks.size(), false);
    for (const auto k : sel.chunks) kept[k] = true;
    EXPECT_EQ(sel.chunks.size() + sel.culled_chunks, chunks.size());
    int visible = 0;
    for (std::size_t k = 0; k < chunks.size(); ++k) {
      bool in_view = false;
      for (int s = 0; s < 64 && !in_view; ++s) {
        const Vector3d t((s & 3) / 3.0, ((s >> 2) & 3) / 3.0, (s >> 4) / 3.0);
        const Vector3d p = chunks.boxes[k].min + t.cwiseProduct(chunks.boxes[k].max - chunks.boxes[k].min);
        const Eigen::Vector4d clip = cam.projection() * cam.view() * p.homogeneous();
        in_view = clip.w() > 0 && (clip.head<3>().array().abs() <= clip.w()).all();
      }
      visible += in_view;
      if (in_view) {
        EXPECT_TRUE(kept[k]) << "view " << view << " chunk " << k;
      }
    }
    EXPECT_GT(visible, 0);
    EXPECT_GT(sel.culled_chunks, 0u);  // not vacuous
    double last = 0;
    for (const auto k : sel.chunks) {
      const Vector3d nearest = cam.eye.cwiseMax(chunks.boxes[k].min).cwiseMin(chunks.boxes[k].max);
      const double d = (nearest - cam.eye).norm();
      EXPECT_GE(d, last - 1e-12);
      last = d;
    }
  }
}

TEST(Chunks, OcclusionNeedsEveryTileNearer) {
  Camera cam;
  cam.eye = Vector3d(0, 0, 5);
  cam.target = Vector3d::Zero();
  cam.width = cam.height = 64;
  cam.near_plane = 1, cam.far_plane = 10;
  const Box3 box = box_of(Vector3d(-0.2, -0.2, -1), Vector3d(0.2, 0.2, -0.5));  // depth 5.5 … 6
  const auto window = [&](double eye_depth) {
    const Eigen::Matrix4d P = cam.projection();
    return float(0.5 * (P(2, 2) * -eye_depth + P(2, 3)) / eye_depth + 0.5);
  };
  std::vector<float> depth(64 * 64, window(5.0));  // a wall in front everywhere
  EXPECT_TRUE(box_occluded(box, cam, depth_tiles(depth, 64, 64, 8)));
  depth[32 * 64 + 32] = 1.0f;  // one background pixel behind the box's centre
  EXPECT_FALSE(box_occluded(box, cam, depth_tiles(depth, 64, 64, 8)));
  std::fill(depth.begin(), depth.end(), window(5.6));  // a wall that cuts the box
  EXPECT_FALSE(box_occluded(box, cam, depth_tiles(depth, 64, 64, 8)));
  std::fill(depth.begin(), depth.end(), window(5.0));
  Camera inside = cam;
  inside.eye = Vector3d(0, 0, -0.7);  // the eye in the box
  EXPECT_FALSE(box_occluded(box, inside, depth_tiles(depth, 64, 64, 8)));
}

class ChunksGl : public GlTest {};

TEST_F(ChunksGl, EarlyDepthAndOcclusionChangeNoPixel) {
  Model m = convert_volume(marschner_lobb_volume(41), {.iso = 0.5}).model;
  m.metadata["tetrahedra"] = "tessellation";
  ASSERT_GT(m.tets.size(), 20000u);  // ≥ 64 chunks, so occlusion runs
  renderer_->set_model(m);
  const Box3 box = bounds(m);
  std::vector<Camera> views;
  for (const double az : {30.0, 160.0, 250.0})
    views.push_back(frame_box(box, {.azimuth_deg = az, .elevation_deg = 25, .width = 200, .height = 200}));
  Camera corner = views[0];  // zoomed into a corner: most chunks outside the frustum
  corner.fov_y_deg = 8;
  corner.target = box.min + 0.2 * (box.max - box.min);
  views.push_back(corner);
  Camera inside = views[1];  // the eye among the tetrahedra
  inside.eye = box.centre() + Vector3d(0.1, 0.05, 0.02);
  inside.target = box.max;
  inside.near_plane = 1e-3;
  views.push_back(inside);
  int occluded = 0, outside = 0;
  for (std::size_t v = 0; v < views.size(); ++v) {
    SCOPED_TRACE(v);
    const Camera& cam = views[v];
    RenderOptions exact;
    exact.tet_early_depth = false;
    exact.tet_occlusion = false;
    renderer_->draw(cam, exact);
    const GBuffer reference_gl = renderer_->read_gbuffer();
    for (int frame = 0; frame < 2; ++frame) {  // without, then with the previous frame's chunks
      RenderOptions fast;
      fast.statistics = frame == 1;
      const FrameStats st = renderer_->draw(cam, fast);
      const GBuffer g = renderer_->read_gbuffer();
      const Difference d = difference(reference_gl, g);
      EXPECT_EQ(d.coverage, 0);
      EXPECT_LE(d.depth, 1e-6);
      occluded += static_cast<int>(st.chunks_occluded);
      outside += static_cast<int>(st.chunks_culled);
    }
    if (v == 4) continue;  // the eye inside: tetrahedra cut by the near plane differ from the CPU either way
    const ReferenceImage ref = render_reference(ReferenceScene(m), cam);
    const testing_gl::Comparison c = testing_gl::compare(ref, renderer_->read_gbuffer());
    EXPECT_GE(c.coverage_agreement, 0.999);
    EXPECT_LE(c.depth_p99, 1e-5);
  }
  EXPECT_GT(outside, 0);  // not vacuous: the corner view skips chunks
  std::printf("chunks skipped over the views: %d outside the frustum, %d hidden\n", outside, occluded);
}
