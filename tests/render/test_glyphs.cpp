// The GL glyph pass ([Sigg06]) against the CPU reference: coverage, depth and normals for every
// glyph kind, random views, stress scenes, and the property that no glyph pixel lies outside
// its proxy polygon.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>

#include <filesystem>

#include "convert/molecule.h"
#include "convert/molecule_glyphs.h"
#include "convert/to_mesh.h"
#include "core/bounds.h"
#include "core/primitive.h"
#include "core/reference.h"
#include "core/synth.h"
#include "render/context.h"
#include "render/renderer.h"
#include "tests/render/gl_test.h"
#include "tests/render/gl_compare.h"

using namespace quadrix;
using quadrix::testing_gl::Comparison;

namespace {

class GlGlyphs : public GlTest {
protected:
  render::GBuffer draw(const Model& m, const Camera& cam, render::RenderOptions o = {}) {
    renderer_->set_model(m);
    last_stats_ = renderer_->draw(cam, o);
    return renderer_->read_gbuffer();
  }
  static ReferenceImage reference(const Model& m, const Camera& cam, bool cull = true) {
    const ReferenceScene scene(m);
    ReferenceRenderOptions ro;
    ro.trace.cull_backfaces = cull;
    return render_reference(scene, cam, ro);
  }
  Comparison run(const Model& m, const Camera& cam, bool cull = true) {
    render::RenderOptions o;
    o.cull = cull;
    const Comparison c = testing_gl::compare(reference(m, cam, cull), draw(m, cam, o));
    std::printf("coverage %.5f depth p99 %.3g normal median %.4f p99 %.3f deg (%d covered)\n", c.coverage_agreement,
                c.depth_p99, c.normal_median_deg, c.normal_p99_deg, c.covered);
    return c;
  }
  render::FrameStats last_stats_;
};

void expect_accurate(const Comparison& c, int min_covered) {
  EXPECT_GT(c.covered, min_covered);
  EXPECT_GE(c.coverage_agreement, 0.999);
  EXPECT_LE(c.depth_p99, 1e-5);
  EXPECT_LE(c.normal_median_deg, 0.05);
  EXPECT_LE(c.normal_p99_deg, 0.5);
}

Eigen::Matrix3d random_rotation(std::mt19937_64& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  return Eigen::Quaterniond(n(rng), n(rng), n(rng), n(rng)).normalized().toRotationMatrix();
}

// A random glyph of `kind` at the origin, sizes about 1.
Glyph random_glyph(GlyphKind kind, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Glyph g;
  g.kind = kind;
  g.colour = Rgb{200, 100, 50};
  const Eigen::Matrix3d R = random_rotation(rng);
  switch (kind) {
    case GlyphKind::sphere: g.radius = 0.5 + u(rng); break;
    case GlyphKind::ellipsoid:
      g.axes = R * Eigen::Vector3d(0.2 + u(rng), 0.2 + u(rng), 0.05 + u(rng)).asDiagonal();
      break;
    case GlyphKind::cylinder:
      g.radius = 0.1 + 0.6 * u(rng);
      g.axes = Eigen::Matrix3d::Zero();
      g.axes.col(0) = R.col(0) * (0.05 + 1.5 * u(rng));
      break;
  }
  return g;
}

// A camera looking at the origin from a random direction and distance.
Camera random_view(std::mt19937_64& rng, double min_distance, double max_distance, int size) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::normal_distribution<double> n(0.0, 1.0);
  Camera cam;
  cam.eye = Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized() * (min_distance + (max_distance - min_distance) * u(rng));
  // Look a little off the glyph so it lands anywhere in the image, perspective included.
  cam.target = Eigen::Vector3d(n(rng), n(rng), n(rng)) * 0.5;
  cam.up = Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized();
  cam.fov_y_deg = 30 + 60 * u(rng);
  cam.width = size;
  cam.height = size * 3 / 4;
  cam.near_plane = 0.01;
  cam.far_plane = 100;
  return cam;
}

}  // namespace

TEST_F(GlGlyphs, EachKindMatchesTheCpuReference) {
  for (const char* kind : {"sphere", "ellipsoid", "cylinder"})
    for (const bool cull : {true, false})
      for (const double az : {0.0, 50.0, 160.0}) {
        SCOPED_TRACE(testing::Message() << kind << " cull=" << cull << " azimuth=" << az);
        const Model m = synth_model(kind);
        const Camera cam =
            frame_box(bounds(m), {.azimuth_deg = az, .elevation_deg = 35, .width = 200, .height = 160});
        const Comparison c = run(m, cam, cull);
        expect_accurate(c, 4000);
      }
}

TEST_F(GlGlyphs, RandomViewsOfRandomGlyphs) {
  std::mt19937_64 rng(7);
  int covered = 0;
  for (int i = 0; i < 24; ++i) {
    const auto kind = static_cast<GlyphKind>(i % 3);
    Model m;
    m.glyphs.push_back(random_glyph(kind, rng));
    const Camera cam = random_view(rng, 3.0, 8.0, 160);
    SCOPED_TRACE(testing::Message() << "view " << i << " kind " << int(kind));
    const Comparison c = run(m, cam, true);
    expect_accurate(c, 0);
    covered += c.covered;
  }
  EXPECT_GT(covered, 10000);
}

TEST_F(GlGlyphs, MoleculeLikeCloudFromSeveralViews) {
  const Model m = synth_model("glyphs", {.count = 400, .seed = 3});
  for (const double az : {10.0, 100.0, 250.0}) {
    SCOPED_TRACE(az);
    const Camera cam = frame_box(bounds(m), {.azimuth_deg = az, .elevation_deg = 20, .width = 240, .height = 200});
    const Comparison c = run(m, cam, true);
    expect_accurate(c, 5000);
  }
}

TEST_F(GlGlyphs, IdsNameTheNearestGlyph) {
  const Model m = synth_model("glyphs", {.count = 300, .seed = 5});
  const Camera cam = frame_box(bounds(m), {.azimuth_deg = 40, .elevation_deg = 30, .width = 200, .height = 200});
  const auto gl = draw(m, cam);
  const auto ref = reference(m, cam);
  int both = 0, same = 0;
  for (std::size_t i = 0; i < ref.primitive.size(); ++i) {
    if (ref.primitive[i] < 0 || gl.primitive[i] < 0) continue;
    ++both;
    same += ref.primitive[i] == gl.primitive[i];
    EXPECT_EQ(primitive_kind(gl.primitive[i]), PrimitiveKind::glyph);
  }
  EXPECT_GT(both, 5000);
  EXPECT_GE(double(same) / both, 0.99);  // the rest: ties where two glyphs meet
}

TEST_F(GlGlyphs, NoGlyphPixelLiesOutsideItsProxy) {
  // Property over random glyphs and views, near ones included: every pixel the reference covers
  // is a fragment of the proxy (drawn flat with glyph_proxies), polygons and rectangles alike.
  // The proxies' waste is printed.
  for (const bool rectangles : {false, true}) {
  SCOPED_TRACE(rectangles ? "rectangles" : "polygons");
  std::mt19937_64 rng(11);
  render::RenderOptions proxies;
  proxies.glyph_proxies = true;
  proxies.glyph_rectangles = rectangles;
  proxies.cull = false;
  double proxy_area[3] = {0, 0, 0}, glyph_area[3] = {0, 0, 0};
  for (int i = 0; i < 90; ++i) {
    const auto kind = static_cast<GlyphKind>(i % 3);
    Model m;
    m.glyphs.push_back(random_glyph(kind, rng));
    // Every sixth view close enough to reach the near plane or to stand inside the glyph.
    const Camera cam = i % 6 == 5 ? random_view(rng, 0.3, 1.5, 96) : random_view(rng, 2.0, 12.0, 96);
    const auto proxy = draw(m, cam, proxies);
    const auto ref = reference(m, cam, false);
    int outside = 0, in_proxy = 0, in_glyph = 0;
    for (std::size_t p = 0; p < ref.coverage.size(); ++p) {
      outside += ref.coverage[p] && !proxy.coverage[p];
      in_proxy += proxy.coverage[p];
      in_glyph += ref.coverage[p];
    }
    EXPECT_EQ(outside, 0) << "view " << i << " kind " << int(kind);
    if (i % 6 != 5 && in_glyph > 200 && in_proxy < int(ref.coverage.size())) {
      proxy_area[int(kind)] += in_proxy;
      glyph_area[int(kind)] += in_glyph;
    }
  }
  const char* names[] = {"sphere", "ellipsoid", "cylinder"};
  for (int k = 0; k < 3; ++k) {
    const double waste = 1.0 - glyph_area[k] / proxy_area[k];
    std::printf("%s %s waste %.1f %% (area of the proxies outside the glyphs)\n", names[k],
                rectangles ? "rectangle" : "polygon", 100 * waste);
    EXPECT_GE(waste, 0.0);
    // A circumscribed octagon leaves 5.2 % of its area outside an ellipse, a rectangle 21.5 %,
    // plus pixel rounding.
    if (k != 2) {
      EXPECT_LE(waste, rectangles ? 0.26 : 0.09);
    }
  }
  }
}

TEST_F(GlGlyphs, StatisticsMeasureTheWaste) {
  if (!render::has_pipeline_statistics()) GTEST_SKIP() << "no GL_ARB_pipeline_statistics_query";
  Model m;
  std::mt19937_64 rng(2);
  std::uniform_real_distribution<double> u(-4.0, 4.0);
  for (int i = 0; i < 60; ++i)
    m.glyphs.push_back({GlyphKind::sphere, {u(rng), u(rng), u(rng)}, 0.6, Eigen::Matrix3d::Identity(), Rgb{90, 90, 200}});
  const Camera cam = frame_box(bounds(m), {.azimuth_deg = 20, .elevation_deg = 10, .width = 256, .height = 256});
  render::RenderOptions o;
  o.statistics = true;
  o.glyph_early_depth = false;  // the tight proxies (the early-depth path draws rectangles)
  o.glyph_rectangles = false;
  draw(m, cam, o);
  const auto& st = last_stats_;
  std::printf("glyph fragments %llu hit %llu waste %.2f %%\n", (unsigned long long)st.glyph_proxy_fragments,
              (unsigned long long)st.glyph_hit_fragments, 100 * st.glyph_waste());
  EXPECT_EQ(st.primitives, 60u);
  EXPECT_GT(st.glyph_hit_fragments, 1000u);
  EXPECT_GT(st.glyph_proxy_fragments, st.glyph_hit_fragments);
  EXPECT_LE(st.glyph_waste(), 0.10);
}

TEST_F(GlGlyphs, FarCameraNarrowFieldOfView) {
  // Small spheres seen from 10⁵ sizes away through a narrow lens: float keeps their shape.
  Model m;
  for (int i = 0; i < 5; ++i)
    m.glyphs.push_back({GlyphKind::sphere, {1000.0 + 2.5 * i, -300.0, 50.0}, 1.0, Eigen::Matrix3d::Identity(), {}});
  std::mt19937_64 rng(4);
  m.glyphs.push_back(random_glyph(GlyphKind::cylinder, rng));
  m.glyphs.back().centre = {1005.0, -297.0, 50.0};
  Camera cam;
  cam.target = {1005.0, -298.5, 50.0};
  cam.eye = cam.target + Eigen::Vector3d(0.3, 0.2, 1.0).normalized() * 1e5;
  cam.fov_y_deg = 0.01;
  cam.near_plane = 1e4;
  cam.far_plane = 2e5;
  cam.width = 240;
  cam.height = 160;
  const Comparison c = run(m, cam);
  EXPECT_GT(c.covered, 1000);
  EXPECT_GE(c.coverage_agreement, 0.999);
  EXPECT_LE(c.normal_median_deg, 0.05);
  // The G-buffer stores eye depth as float: 10⁵ has a step of 0.0078, 8e-5 of the depth scale
  // compare() uses here (10⁻³ of the depth).
  EXPECT_LE(c.depth_p99, 2e-4);
}

TEST_F(GlGlyphs, TheNearPlaneCutsGlyphsInFrontOfIt) {
  // Two spheres whose near sides both lie in front of the near plane (0.1 and 0.23 from the eye,
  // the plane at 0.5): the rays start at the plane, inside both, so the nearer far side shows, the
  // unit sphere's at 2.1 from the eye, whichever is drawn first. GL clamped both hits to depth 0
  // and the first drawn won (100 % of the pixels off the reference with one order).
  Glyph a, b;
  a.radius = 1.0, a.colour = Rgb{200, 50, 50};
  b.centre = {0.3, 0.0, -0.5}, b.radius = 1.4, b.colour = Rgb{50, 200, 50};
  Camera cam;
  cam.eye = {0.0, 0.0, 1.1};
  cam.target = {0.0, 0.0, 0.0};
  cam.fov_y_deg = 40;
  cam.near_plane = 0.5;
  cam.far_plane = 50;
  cam.width = cam.height = 120;
  for (const bool a_first : {true, false})
    for (const bool early : {true, false}) {
      SCOPED_TRACE(testing::Message() << "a first " << a_first << ", early depth " << early);
      Model m;
      m.glyphs = a_first ? std::vector<Glyph>{a, b} : std::vector<Glyph>{b, a};
      const ReferenceImage ref = reference(m, cam);
      const std::size_t centre = static_cast<std::size_t>(cam.height / 2) * cam.width + cam.width / 2;
      ASSERT_TRUE(ref.coverage[centre]);
      EXPECT_NEAR(ref.depth[centre], 2.1, 1e-3);
      EXPECT_EQ(ref.albedo[centre], *a.colour);
      render::RenderOptions o;
      o.glyph_early_depth = early;
      const render::GBuffer g = draw(m, cam, o);
      const Comparison c = testing_gl::compare(ref, g);
      expect_accurate(c, cam.width * cam.height / 2);
    }
}

TEST_F(GlGlyphs, AMeshWithVertexNormalsShadesAsTheSurfaceItWasMeshedFrom) {
  // `quadrix mesh` gives each vertex the drawn surface's normal; the mesh pass shades with them
  // (flat face normals without). The sphere glyph meshed at 1e-3 of its box, drawn as a mesh,
  // against the CPU reference's normals of the sphere itself.
  const Model m = synth_model("sphere");
  ToMeshResult r = mesh_model(m, {.max_error = 1e-3 * bounds(m).diagonal(), .progress = {}});
  ASSERT_EQ(r.mesh.normals.size(), r.mesh.vertices.size());
  const Camera cam = frame_box(bounds(m), {.azimuth_deg = 30, .elevation_deg = 20, .width = 200, .height = 200});
  const ReferenceImage truth = reference(m, cam);
  const auto angles = [&](const PolygonMesh& mesh) {
    renderer_->set_mesh(mesh);
    renderer_->draw(cam, {});
    const render::GBuffer g = renderer_->read_gbuffer();
    std::vector<double> deg;
    for (std::size_t i = 0; i < g.coverage.size(); ++i)
      if (g.coverage[i] && truth.coverage[i])
        deg.push_back(std::acos(std::clamp(double(g.normal[i].normalized().dot(truth.normal[i].normalized())), -1.0, 1.0)) *
                      180 / std::numbers::pi);
    std::sort(deg.begin(), deg.end());
    return deg;
  };
  const std::vector<double> smooth = angles(r.mesh);
  r.mesh.normals.clear();
  const std::vector<double> flat = angles(r.mesh);
  ASSERT_GT(smooth.size(), 8000u);
  ASSERT_GT(flat.size(), 8000u);
  const auto q = [](const std::vector<double>& d, double p) { return d[static_cast<std::size_t>(p * double(d.size() - 1))]; };
  std::printf("normal error against the sphere: vertex normals median %.3f p99 %.3f deg, flat median %.3f p99 %.3f deg\n",
              q(smooth, 0.5), q(smooth, 0.99), q(flat, 0.5), q(flat, 0.99));
  EXPECT_LT(q(smooth, 0.99), 0.25 * q(flat, 0.99));
  EXPECT_LT(q(smooth, 0.5), 0.25 * q(flat, 0.5));
}

TEST_F(GlGlyphs, AMeshWithVertexColoursDrawsThemAsTheModelItWasMeshedFrom) {
  // `quadrix mesh` carries a molecule's colours onto its vertices; the mesh pass draws them (it
  // drew every mesh in one grey). Two overlapping spheres in two colours meshed as their union,
  // drawn as a mesh, against the CPU reference's albedo of the spheres themselves: the same
  // colour at every pixel both cover, but for a band along the intersection curve, where the
  // colour turns between two vertices.
  Model m;
  m.glyphs.push_back({GlyphKind::sphere, {0, 0, 0}, 1.0, Eigen::Matrix3d::Identity(), Rgb{220, 30, 30}});
  m.glyphs.push_back({GlyphKind::sphere, {1.2, 0, 0}, 0.9, Eigen::Matrix3d::Identity(), Rgb{30, 30, 220}});
  const ToMeshResult r = mesh_model(m, {.max_error = 1e-3 * bounds(m).diagonal(), .progress = {}});
  ASSERT_EQ(r.mesh.colours.size(), r.mesh.vertices.size());
  const Camera cam = frame_box(bounds(m), {.azimuth_deg = 30, .elevation_deg = 20, .width = 200, .height = 200});
  const ReferenceImage truth = reference(m, cam);
  renderer_->set_model(Model{});
  renderer_->set_mesh(r.mesh);
  renderer_->draw(cam, {});
  const render::GBuffer g = renderer_->read_gbuffer();
  const Image8 image = renderer_->read_colour();
  ASSERT_EQ(image.rgba.size(), 4 * g.coverage.size());
  // Shaded, so judged by which of red and blue dominates, as in the sphere the reference sees.
  int both = 0, same = 0;
  for (std::size_t i = 0; i < g.coverage.size(); ++i) {
    if (!g.coverage[i] || !truth.coverage[i]) continue;
    ++both;
    const int red = image.rgba[4 * i], blue = image.rgba[4 * i + 2];
    const bool want_red = truth.albedo[i][0] > truth.albedo[i][2];
    same += want_red ? red > blue + 20 : blue > red + 20;
  }
  std::printf("mesh colours: %d of %d pixels as the spheres' own\n", same, both);
  ASSERT_GT(both, 8000);
  EXPECT_GT(same, 0.97 * both);  // measured: 8,893 of 8,938
}

TEST_F(GlGlyphs, StressHundredThousandGlyphsTinyAndHugeAcrossTheNearPlane) {
  // 10⁵ glyphs of every kind with radii from 10⁻³ to 10 (log-uniform), the eye inside the cloud
  // so glyphs straddle the near plane, wrap the eye and lie behind it.
  std::mt19937_64 rng(13);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Model m;
  m.glyphs.reserve(100'000);
  for (int i = 0; i < 100'000; ++i) {
    Glyph g = random_glyph(static_cast<GlyphKind>(i % 3), rng);
    const double s = std::pow(10.0, -3.0 + 4.0 * u(rng) * u(rng));  // most small, a few up to 10
    g.radius *= s;
    g.axes *= s;
    g.centre = Eigen::Vector3d(u(rng), u(rng), u(rng)) * 200.0 - Eigen::Vector3d::Constant(100.0);
    m.glyphs.push_back(g);
  }
  Camera cam;
  cam.eye = {3.0, 2.0, 1.0};
  cam.target = {0.0, 0.0, -40.0};
  cam.fov_y_deg = 70;
  cam.near_plane = 0.05;
  cam.far_plane = 500;
  cam.width = 256;
  cam.height = 192;
  const Comparison c = run(m, cam, true);
  EXPECT_GT(c.covered, 5000);
  EXPECT_GE(c.coverage_agreement, 0.995);
  EXPECT_LE(c.depth_p99, 1e-4);
  EXPECT_LE(c.normal_median_deg, 0.1);
}

TEST_F(GlGlyphs, MoleculesInEveryStyleMatchTheCpuReference) {
  const auto path = std::filesystem::path(QUADRIX_DATASETS) / "molecules" / "4lfq.pdb";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "dataset missing: " << path;
  const Molecule mol = read_molecule(path);
  for (const auto style : {MoleculeStyle::spacefill, MoleculeStyle::balls_sticks, MoleculeStyle::licorice}) {
    SCOPED_TRACE(int(style));
    MoleculeGlyphOptions options;
    options.style = style;
    const Model m = molecule_glyphs(mol, options).model;
    const Camera cam = frame_box(bounds(m), {.azimuth_deg = 30, .elevation_deg = 20, .width = 256, .height = 256});
    const Comparison c = run(m, cam, true);
    expect_accurate(c, 4000);
  }
}

TEST_F(GlGlyphs, EarlyDepthRayCastsOnlyNearTheSurface) {
  // A spacefill molecule: most atoms lie behind others. The early-depth path (occluders, nearest
  // hits, one ray per pixel) must draw the same image as one pass writing each hit's depth, and
  // ray-cast far fewer proxy fragments; both against the CPU reference.
  const auto path = std::filesystem::path(QUADRIX_DATASETS) / "molecules" / "4lfq.pdb";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "dataset missing: " << path;
  MoleculeGlyphOptions options;
  options.style = MoleculeStyle::spacefill;
  const Model m = molecule_glyphs(read_molecule(path), options).model;
  const Camera cam = frame_box(bounds(m), {.azimuth_deg = 60, .elevation_deg = 10, .width = 320, .height = 320});
  const ReferenceImage ref = reference(m, cam);
  std::uint64_t fragments[2] = {};
  for (const bool early : {true, false}) {
    SCOPED_TRACE(early);
    render::RenderOptions o;
    o.glyph_early_depth = early;
    o.glyph_rectangles = false;
    o.statistics = true;
    const Comparison c = testing_gl::compare(ref, draw(m, cam, o));
    expect_accurate(c, 10000);
    fragments[early] = last_stats_.glyph_proxy_fragments;
  }
  {  // the direct path with rectangles (the default on software rasterizers)
    render::RenderOptions o;
    o.glyph_early_depth = false;
    o.glyph_rectangles = true;
    SCOPED_TRACE("rectangles");
    expect_accurate(testing_gl::compare(ref, draw(m, cam, o)), 10000);
  }
  std::printf("proxy fragments ray-cast: %llu early depth, %llu hit depth\n", (unsigned long long)fragments[1],
              (unsigned long long)fragments[0]);
  EXPECT_GT(fragments[1], 0u);
  EXPECT_LT(fragments[1], fragments[0] / 2);
}
