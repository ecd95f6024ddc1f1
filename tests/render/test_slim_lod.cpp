// SLIM level of detail (core/slim_lod.h, the GL SLIM pass): the cut is the coarsest one whose
// every ball passes its own projected test; a far view draws fewer balls than a near one; the
// errors of a .slim2t hierarchy are measured as distances; GL draws the cut exactly as the CPU
// reference does, uploads it only when it changes, and at 0.5 px the image stays close to the
// full-detail one.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <filesystem>
#include <set>

#include "core/error.h"
#include "core/mesh_io.h"
#include "core/model_io.h"
#include "core/reference.h"
#include "core/slim.h"
#include "core/slim_lod.h"
#include "fit/slim_fit.h"
#include "fit/slim_hierarchy.h"
#include "render/renderer.h"
#include "tests/render/gl_compare.h"
#include "tests/render/gl_test.h"
#include "tests/tools/cli_support.h"

using namespace quadrix;
using Eigen::Vector3d;

namespace {

std::vector<Vector3d> fibonacci(int n) {
  std::vector<Vector3d> c;
  for (int i = 0; i < n; ++i) {
    const double z = 1.0 - (2.0 * i + 1.0) / n;
    const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
    const double phi = i * std::numbers::pi * (3.0 - std::sqrt(5.0));
    c.emplace_back(r * std::cos(phi), r * std::sin(phi), z);
  }
  return c;
}

// The unit sphere as a three-level hierarchy: n leaves on a Fibonacci set carrying the sphere
// itself, then n/4 and n/16 balls carrying the spheres of radius 1 + delta1 and 1 − delta2, so
// each ball's error (a distance to the leaves' surface) is exactly |delta| of its level. Each
// ball's parent is the nearest ball of the next level, grown to hold its children's balls.
Model sphere_hierarchy(int n, double delta1, double delta2) {
  Model m;
  const int counts[3] = {n, n / 4, n / 16};
  const double rho[3] = {1.0, 1.0 + delta1, 1.0 - delta2};
  std::vector<std::vector<Vector3d>> centres;
  for (int level = 0; level < 3; ++level) centres.push_back(fibonacci(counts[level]));
  std::vector<SlimPatch> balls;
  std::vector<double> error;
  std::vector<std::int32_t> level_start;
  for (int level = 0; level < 3; ++level) {
    level_start.push_back(static_cast<std::int32_t>(balls.size()));
    const double R = 3.6 / std::sqrt(static_cast<double>(counts[level]));
    const Quadric q = Quadric::sphere(Vector3d::Zero(), rho[level]);
    for (const Vector3d& c : centres[static_cast<std::size_t>(level)]) {
      balls.push_back({c, R, q.to_local(c, R), ClipPlanes{}, std::nullopt, std::nullopt});
      error.push_back(std::abs(rho[level] - 1.0));
    }
  }
  std::vector<std::int32_t> parent(balls.size(), -1);
  for (int level = 0; level < 2; ++level)
    for (int i = 0; i < counts[level]; ++i) {
      const Vector3d& c = centres[static_cast<std::size_t>(level)][static_cast<std::size_t>(i)];
      const auto& up = centres[static_cast<std::size_t>(level + 1)];
      std::size_t best = 0;
      for (std::size_t j = 1; j < up.size(); ++j)
        if ((up[j] - c).squaredNorm() < (up[best] - c).squaredNorm()) best = j;
      parent[static_cast<std::size_t>(level_start[static_cast<std::size_t>(level)] + i)] =
          level_start[static_cast<std::size_t>(level + 1)] + static_cast<std::int32_t>(best);
    }
  // A merged ball holds its children's balls (as Kanai's merges do), so it leaves no hole.
  for (std::size_t b = 0; b < balls.size(); ++b)
    if (parent[b] >= 0) {
      SlimPatch& p = balls[static_cast<std::size_t>(parent[b])];
      p.radius = std::max(p.radius, (balls[b].centre - p.centre).norm() + balls[b].radius);
    }
  for (std::size_t b = static_cast<std::size_t>(n); b < balls.size(); ++b) {
    const double rho_b = b < static_cast<std::size_t>(level_start[2]) ? rho[1] : rho[2];
    balls[b].local = Quadric::sphere(Vector3d::Zero(), rho_b).to_local(balls[b].centre, balls[b].radius);
  }
  m.slims.assign(balls.begin(), balls.begin() + n);
  m.slim_hierarchy.others.assign(balls.begin() + n, balls.end());
  m.slim_hierarchy.parent = parent;
  m.slim_hierarchy.error = error;
  return m;
}

Camera camera_at(double distance, int size = 256) {
  Camera c;
  c.eye = Vector3d(0.3, 0.2, 1.0).normalized() * distance;
  c.target = Vector3d::Zero();
  c.width = c.height = size;
  c.near_plane = 0.05;
  c.far_plane = distance + 3;
  return c;
}

double focal(const Camera& c) { return 0.5 * c.height / std::tan(0.5 * c.fov_y_deg * std::numbers::pi / 180.0); }

// Eye-space depth of the ball's nearest point (the near plane at least).
double nearest_depth(const SlimPatch& b, const Camera& c) {
  return std::max(c.near_plane, (b.centre - c.eye).dot(c.forward()) - b.radius);
}

// Every leaf lies under exactly one ball of the cut.
bool is_cut(const Model& m, const std::vector<std::int32_t>& balls) {
  const std::set<std::int32_t> in(balls.begin(), balls.end());
  for (std::size_t leaf = 0; leaf < m.slims.size(); ++leaf) {
    int hits = 0;
    for (std::int32_t b = static_cast<std::int32_t>(leaf); b >= 0; b = m.slim_hierarchy.parent[static_cast<std::size_t>(b)])
      hits += in.count(b) ? 1 : 0;
    if (hits != 1) return false;
  }
  return true;
}

}  // namespace

TEST(SlimLod, ZeroPixelsGivesTheLeavesAndAFarViewFewerBalls) {
  const Model m = sphere_hierarchy(4096, 0.004, 0.012);
  const SlimLod lod(m);
  EXPECT_EQ(lod.levels(), 3u);
  const SlimLodCut full = lod.cut(camera_at(3), {.pixel_error = 0});
  ASSERT_EQ(full.balls.size(), m.slims.size());
  EXPECT_EQ(full.balls.front(), 0);
  EXPECT_EQ(full.balls.back(), static_cast<std::int32_t>(m.slims.size()) - 1);
  std::size_t previous = full.balls.size();
  for (const double distance : {3.0, 6.0, 12.0}) {
    const SlimLodCut c = lod.cut(camera_at(distance), {.pixel_error = 0.5});
    EXPECT_TRUE(is_cut(m, c.balls)) << distance;
    EXPECT_LT(c.balls.size(), previous) << "at distance " << distance;
    previous = c.balls.size();
    std::size_t sum = 0;
    for (std::size_t k : c.level_counts) sum += k;
    EXPECT_EQ(sum, c.balls.size());
  }
  EXPECT_EQ(previous, 4096u / 16);  // far enough: the roots
  EXPECT_EQ(lod.cut(camera_at(48), {.pixel_error = 0.5}).balls.size(), 4096u / 16);
}

TEST(SlimLod, EachBallPassesItsOwnProjectedTestAndEachRefinedOneFailsIt) {
  const Model m = sphere_hierarchy(4096, 0.004, 0.012);
  const SlimLod lod(m);
  const std::size_t n = m.slims.size() + m.slim_hierarchy.others.size();
  for (const double distance : {2.0, 2.5, 3.0}) {
    const Camera cam = camera_at(distance);
    const double P = 0.5, f = focal(cam);
    const SlimLodCut c = lod.cut(cam, {.pixel_error = P, .skip_outside_view = false});
    ASSERT_TRUE(is_cut(m, c.balls));
    EXPECT_EQ(c.outside_view, 0u);
    std::vector<char> chosen(n, 0), refined(n, 0);
    for (std::int32_t b : c.balls) {
      chosen[static_cast<std::size_t>(b)] = 1;
      for (std::int32_t a = m.slim_hierarchy.parent[static_cast<std::size_t>(b)]; a >= 0;
           a = m.slim_hierarchy.parent[static_cast<std::size_t>(a)])
        refined[static_cast<std::size_t>(a)] = 1;
    }
    int coarse = 0, near_leaves = 0, far_leaves = 0;
    for (std::size_t b = 0; b < n; ++b) {
      const SlimPatch& ball = slim_ball(m, b);
      const double px = m.slim_hierarchy.error[b] * f / nearest_depth(ball, cam);
      if (chosen[b] && b >= m.slims.size()) {
        EXPECT_LE(px, P) << "ball " << b;
        ++coarse;
      }
      if (refined[b]) {
        EXPECT_GT(px, P) << "ball " << b;
      }
      if (chosen[b] && b < m.slims.size()) ((ball.centre.dot(cam.eye) > 0) ? near_leaves : far_leaves) += 1;
    }
    // Per ball, not one global error: at these distances the cut mixes levels, the near side finer.
    EXPECT_GT(coarse, 0) << distance;
    EXPECT_GT(near_leaves, far_leaves) << distance;
  }
}

TEST(SlimLod, BallsWhoseSubtreeIsOutsideTheViewStayCoarseAndTheImageIsTheSame) {
  const Model m = sphere_hierarchy(4096, 0.004, 0.012);
  const SlimLod lod(m);
  Camera cam = camera_at(2.2, 96);
  cam.fov_y_deg = 12;  // zoomed in on a part of the sphere
  const SlimLodCut skip = lod.cut(cam, {.pixel_error = 0.5});
  const SlimLodCut all = lod.cut(cam, {.pixel_error = 0.5, .skip_outside_view = false});
  EXPECT_TRUE(is_cut(m, skip.balls));
  EXPECT_GT(skip.outside_view, 0u);
  EXPECT_LT(skip.balls.size(), all.balls.size() / 2);
  const Model a = slim_cut_model(m, skip.balls), b = slim_cut_model(m, all.balls);
  const ReferenceScene sa(a), sb(b);
  const ReferenceImage ia = render_reference(sa, cam), ib = render_reference(sb, cam);
  std::size_t covered = 0, differ = 0;
  for (std::size_t i = 0; i < ia.coverage.size(); ++i) {
    covered += ib.coverage[i];
    differ += ia.coverage[i] != ib.coverage[i] || (ia.coverage[i] && ia.depth[i] != ib.depth[i]);
  }
  EXPECT_GT(covered, ia.coverage.size() / 2);
  EXPECT_EQ(differ, 0u);
}

TEST(SlimLod, Slim2tEnergiesAreReplacedByMeasuredDistances) {
  Model m = sphere_hierarchy(1024, 0.01, 0.03);
  EXPECT_EQ(slim_lod_errors(m), m.slim_hierarchy.error);  // distances already: kept as stored
  const std::vector<double> truth = m.slim_hierarchy.error;
  for (double& e : m.slim_hierarchy.error) e = e > 0 ? 1e6 / e : 0;  // an energy, not a distance
  m.metadata["source_format"] = "slim2t";
  m.metadata["slim_hierarchy_error"] = "distance";  // as fit --lod-levels says: kept as stored
  EXPECT_EQ(slim_lod_errors(m), m.slim_hierarchy.error);
  m.metadata.erase("slim_hierarchy_error");
  const std::vector<double> measured = slim_lod_errors(m);
  ASSERT_EQ(measured.size(), truth.size());
  for (std::size_t b = 0; b < truth.size(); ++b) {
    if (b < m.slims.size()) {
      EXPECT_EQ(measured[b], 0.0);
      continue;
    }
    // The level-1 sphere lies 0.01 outside the leaves' sphere, the level-2 one 0.03 inside.
    EXPECT_GE(measured[b], 0.9 * truth[b]) << "ball " << b;
    EXPECT_LE(measured[b], 1.2 * truth[b]) << "ball " << b;
  }
}

TEST(SlimLod, AMergedBallThatLeavesAHoleMeasuresTheHole) {
  Model m = sphere_hierarchy(1024, 0.01, 0.03);
  m.metadata["source_format"] = "slim2t";
  const std::size_t b = m.slims.size();  // the first merged ball
  SlimPatch& ball = m.slim_hierarchy.others[0];
  const double before = slim_lod_errors(m)[b];
  ball.radius *= 0.5;  // its children's balls now reach out of it
  ball.local = Quadric::sphere(Vector3d::Zero(), 1.01).to_local(ball.centre, ball.radius);
  const double after = slim_lod_errors(m)[b];
  EXPECT_LE(before, 0.012);
  EXPECT_GT(after, 0.1 * ball.radius);
  EXPECT_GT(after, 3 * before);
}

TEST(SlimLod, CutModelHoldsTheCutsBallsInOrder) {
  const Model m = sphere_hierarchy(256, 0.01, 0.03);
  const std::vector<std::int32_t> balls = {3, 256, 257, 256 + 64};
  const Model c = slim_cut_model(m, balls);
  ASSERT_EQ(c.slims.size(), 4u);
  EXPECT_TRUE(c.slim_hierarchy.empty());
  EXPECT_EQ(c.slims[0].centre, m.slims[3].centre);
  EXPECT_EQ(c.slims[3].radius, m.slim_hierarchy.others[64].radius);
  EXPECT_THROW(slim_cut_model(m, std::vector<std::int32_t>{256 + 64 + 16}), InvalidInput);
}

class GlSlimLod : public GlTest {};

TEST_F(GlSlimLod, GlDrawsTheCutAsTheReferenceDoes) {
  const Model m = sphere_hierarchy(4096, 0.004, 0.012);
  const Camera cam = camera_at(2.5, 200);
  const SlimLodCut cut = select_slim_lod(m, cam, {.pixel_error = 0.5});
  ASSERT_GT(cut.level_counts[0], 0u);
  ASSERT_GT(cut.level_counts[1], 0u);  // a mixed cut
  renderer_->set_model(m);
  render::RenderOptions o;
  o.slim_pixel_error = 0.5;
  const render::FrameStats st = renderer_->draw(cam, o);
  EXPECT_EQ(st.slim_balls, cut.balls.size());
  EXPECT_EQ(st.slim_level_counts, cut.level_counts);
  const Model cut_model = slim_cut_model(m, cut.balls);  // the scene refers to it
  const ReferenceScene scene(cut_model);
  const auto c = testing_gl::compare(render_reference(scene, cam), renderer_->read_gbuffer());
  EXPECT_GT(c.covered, 8000);
  EXPECT_GE(c.coverage_agreement, 0.995);
  EXPECT_LE(c.depth_p99, 2e-3);
  EXPECT_LE(c.normal_median_deg, 0.5);
}

TEST_F(GlSlimLod, UploadsTheCutOnlyWhenItChanges) {
  const Model m = sphere_hierarchy(4096, 0.004, 0.012);
  renderer_->set_model(m);
  render::RenderOptions o;
  EXPECT_TRUE(renderer_->draw(camera_at(2.5, 64), o).slim_cut_uploaded);
  EXPECT_FALSE(renderer_->draw(camera_at(2.5, 64), o).slim_cut_uploaded);
  const render::FrameStats far = renderer_->draw(camera_at(40, 64), o);
  EXPECT_TRUE(far.slim_cut_uploaded);
  EXPECT_EQ(far.slim_balls, 4096u / 16);
  o.slim_pixel_error = 0;
  const render::FrameStats full = renderer_->draw(camera_at(40, 64), o);
  EXPECT_TRUE(full.slim_cut_uploaded);
  EXPECT_EQ(full.slim_balls, 4096u);
}

TEST_F(GlSlimLod, HalfAPixelStaysCloseToFullDetail) {
  const Model m = sphere_hierarchy(4096, 0.004, 0.012);
  renderer_->set_model(m);
  const Camera cam = frame_box(bounds(m), {.width = 256, .height = 256});
  render::RenderOptions o;
  const auto image = [&](double P, std::uint64_t& balls) {
    o.slim_pixel_error = P;
    balls = renderer_->draw(cam, o).slim_balls;
    return renderer_->read_gbuffer();
  };
  std::uint64_t full_balls = 0, lod_balls = 0, coarse_balls = 0;
  const render::GBuffer full = image(0, full_balls), lod = image(0.5, lod_balls), coarse = image(8, coarse_balls);
  const auto symmetric_difference = [&](const render::GBuffer& g) {
    std::size_t diff = 0, covered = 0;
    for (std::size_t i = 0; i < full.coverage.size(); ++i) diff += full.coverage[i] != g.coverage[i], covered += full.coverage[i];
    return double(diff) / double(covered);
  };
  EXPECT_LT(lod_balls, full_balls);  // not vacuous: the cut is coarser than the leaves
  EXPECT_LT(coarse_balls, lod_balls);
  const double d_lod = symmetric_difference(lod), d_coarse = symmetric_difference(coarse);
  EXPECT_LE(d_lod, 0.02);
  EXPECT_GT(d_coarse, d_lod);  // and the measure sees a coarser cut
  std::printf("balls: full %llu, 0.5 px %llu, 8 px %llu; symmetric difference 0.5 px %.4f, 8 px %.4f\n",
              (unsigned long long)full_balls, (unsigned long long)lod_balls, (unsigned long long)coarse_balls, d_lod,
              d_coarse);
}

// A fitted hierarchy (fit/slim_hierarchy.h, the fits rule): a cut at a large pixel error draws the
// coarsest level alone, GL draws it as the CPU reference does (each coarse ball with its own
// push bound), and its covered pixels stay close to full detail's: the coarse level is a real
// fit at 16E, not merged balls.
TEST_F(GlSlimLod, ACoarseCutOfFittedLevelsMatchesTheReferenceAndStaysCloseToFullDetail) {
  const auto path = std::filesystem::path(QUADRIX_DATASETS) / "meshes" / "dragon_10k.obj";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "dataset missing: " << path;
  const PolygonMesh mesh = read_mesh(path);
  const PointCloud cloud = points_from_mesh(mesh);
  const SlimFitOptions o{.max_error = 2e-3};
  SlimFitResult r = fit_slim(cloud, mesh, o);
  const SlimLevelsStats st = add_slim_hierarchy(r, cloud, &mesh, o, {.levels = 2});
  ASSERT_EQ(st.patches.size(), 3u);
  const Model& m = r.model;
  const Camera cam = frame_box(bounds(m), {.azimuth_deg = 30, .elevation_deg = 20, .width = 192, .height = 192});
  const SlimLodCut cut = select_slim_lod(m, cam, {.pixel_error = 100});
  ASSERT_EQ(cut.level_counts.size(), 3u);
  EXPECT_EQ(cut.level_counts[2], cut.balls.size());  // the coarsest level alone
  EXPECT_EQ(cut.balls.size(), st.patches[2]);
  renderer_->set_model(m);
  render::RenderOptions ro;
  ro.set_slim_blend(slim_blend_of(m));
  ro.slim_pixel_error = 100;
  EXPECT_EQ(renderer_->draw(cam, ro).slim_balls, cut.balls.size());
  const render::GBuffer coarse = renderer_->read_gbuffer();
  const Model cut_model = slim_cut_model(m, cut.balls);
  const ReferenceScene scene(cut_model);
  ReferenceRenderOptions rro;
  rro.trace.slim = slim_blend_of(m);
  const auto c = testing_gl::compare(render_reference(scene, cam, rro), coarse);
  EXPECT_GT(c.covered, 4000);
  EXPECT_GE(c.coverage_agreement, 0.995);
  EXPECT_LE(c.depth_p99, 2e-3);
  EXPECT_LE(c.normal_median_deg, 0.5);
  ro.slim_pixel_error = 0;
  renderer_->draw(cam, ro);
  const render::GBuffer full = renderer_->read_gbuffer();
  std::size_t diff = 0, covered = 0;
  for (std::size_t i = 0; i < full.coverage.size(); ++i) diff += full.coverage[i] != coarse.coverage[i], covered += full.coverage[i];
  const double d = double(diff) / double(covered);
  std::printf("dragon_10k at 2e-3, levels %zu/%zu/%zu: the level-2 cut (%zu balls) differs from full detail in %.4f of "
              "%zu covered pixels; GL against the reference: coverage %.4f, depth p99 %.2g\n",
              st.patches[0], st.patches[1], st.patches[2], cut.balls.size(), d, covered, c.coverage_agreement,
              c.depth_p99);
  // Measured 0.0325 (530 balls of a fit at 3.2e-2 of the diagonal, ~6 px here); the merge rule's level 2
  // (54 balls holding their children) 0.364.
  EXPECT_LE(d, 0.05);
}

// The CLI: both backends choose the same cut for the same view; 0 px draws every leaf.
class SlimLodCli : public test_support::TempDir {};

TEST_F(SlimLodCli, RenderReportsTheSameCutOnBothBackends) {
  using test_support::q;
  const auto model = dir_ / "sphere.qxm";
  write_model(sphere_hierarchy(4096, 0.004, 0.012), model, {});
  const auto balls = [&](const std::string& backend, const std::string& pixel_error) -> long {
    const auto report = dir_ / (backend + pixel_error + ".json");
    const auto r = test_support::quadrix_run("render " + q(model) + " -o " + q(dir_ / "out.png") + " --backend " + backend +
                                             " --size 96x96 --pixel-error " + pixel_error + " --report " + q(report));
    if (r.code == 6 && backend == "gl") return -2;  // no usable GL context here (exit code of a GL error)
    EXPECT_EQ(r.code, 0) << r.out;
    if (r.code != 0) return -1;
    return test_support::read_json(report)["render"]["slim_lod"]["balls"].get<long>();
  };
  const long cpu = balls("cpu", "0.5"), gl = balls("gl", "0.5");
  EXPECT_GT(cpu, 0);
  EXPECT_LT(cpu, 4096);
  if (gl == -2) GTEST_SKIP() << "no OpenGL context for the GL backend";
  EXPECT_EQ(gl, cpu);
  EXPECT_EQ(balls("gl", "0"), 4096);
}

// The viewer chooses the cut per frame and uploads it only when it changes: a still view uploads
// once, and its cut is the one `render` chooses for the same view.
TEST_F(SlimLodCli, ViewerUploadsAStillViewsCutOnce) {
  using test_support::q;
  if (test_support::run_command("command -v", "xvfb-run").code != 0) GTEST_SKIP() << "xvfb-run is not installed";
  const auto model = dir_ / "sphere.qxm";
  write_model(sphere_hierarchy(4096, 0.004, 0.012), model, {});
  const std::string view = " --size 160x120 --azimuth 40 --elevation 30 --pixel-error 0.5";
  const auto v = test_support::run_command("xvfb-run -a -s '-screen 0 640x480x24' " + std::string(QUADRIX_BINARY),
                                           "view " + q(model) + view + " --frames 4 --quiet --report " + q(dir_ / "v.json"));
  if (v.code == 6) GTEST_SKIP() << "no OpenGL 4.5 context through GLFW under Xvfb";
  ASSERT_EQ(v.code, 0) << v.out;
  const auto lod = test_support::read_json(dir_ / "v.json")["view"]["slim_lod"];
  EXPECT_EQ(lod["cut_uploads"].get<int>(), 1);
  const auto r = test_support::quadrix_run("render " + q(model) + " -o " + q(dir_ / "r.png") + view + " --report " +
                                           q(dir_ / "r.json"));
  ASSERT_EQ(r.code, 0) << r.out;
  const long balls = test_support::read_json(dir_ / "r.json")["render"]["slim_lod"]["balls"].get<long>();
  EXPECT_LT(balls, 4096);
  EXPECT_EQ(lod["balls_last_frame"].get<long>(), balls);
}
